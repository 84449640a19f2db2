#include "image/async_writer.h"

#include "base/error.h"

namespace mvtm {

AsyncImageWriter::AsyncImageWriter() : thread_([this] { Loop(); }) {}

AsyncImageWriter::~AsyncImageWriter() { Stop(); }

void AsyncImageWriter::Push(std::string path, Image img, PngCompression png,
                            std::function<void(const std::string&)> done) {
  std::unique_lock<std::mutex> l(mu_);
  cv_.wait(l, [&] { return queue_.size() < 4 || !error_.empty(); });
  if (!error_.empty()) {
    reported_ = true;
    throw Error(error_);
  }
  queue_.push_back(Job{std::move(path), std::move(img), png, std::move(done)});
  cv_.notify_all();
}

void AsyncImageWriter::Stop() {
  {
    std::lock_guard<std::mutex> l(mu_);
    done_ = true;
    cv_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
}

void AsyncImageWriter::Finish() {
  Stop();
  if (!error_.empty() && !reported_) {
    reported_ = true;
    throw Error(error_);
  }
}

void AsyncImageWriter::Loop() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> l(mu_);
      cv_.wait(l, [&] { return !queue_.empty() || done_; });
      if (queue_.empty()) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      cv_.notify_all();
    }
    try {
      WriteImage(job.path, job.image, job.png);
      if (job.done) job.done(job.path);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> l(mu_);
      error_ = e.what();
      queue_.clear();
      cv_.notify_all();
      return;
    }
  }
}

}  // namespace mvtm
