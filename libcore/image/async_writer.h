// mvtm — writing images on a second thread, so that encoding (PNG, EXR) overlaps the work that
// produces the next image.
//
// Push() queues a write (blocking while 4 are already queued); Finish() waits for the queue to
// drain. The first write that fails stops the writer: the next Push() or Finish() throws its
// Error, and nothing queued after it is written. Each write is atomic (WriteImage).
// Thread safety: Push/Finish from one producer thread.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "image/image.h"

namespace mvtm {

class AsyncImageWriter {
 public:
  AsyncImageWriter();
  ~AsyncImageWriter();  // waits; an error not yet reported is dropped (call Finish to see it)
  AsyncImageWriter(const AsyncImageWriter&) = delete;
  AsyncImageWriter& operator=(const AsyncImageWriter&) = delete;

  // `done` (optional) runs on the writer thread once the file is in place (e.g. to record it).
  void Push(std::string path, Image img, PngCompression png = PngCompression::kDefault,
            std::function<void(const std::string&)> done = {});
  void Finish();

 private:
  void Loop();
  void Stop();

  std::mutex mu_;
  std::condition_variable cv_;
  struct Job {
    std::string path;
    Image image;
    PngCompression png;
    std::function<void(const std::string&)> done;
  };
  std::deque<Job> queue_;
  bool done_ = false, reported_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace mvtm
