#include "base/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <locale>
#include <memory>

#include "base/error.h"

namespace mvtm {

namespace {
std::atomic<unsigned> g_counter{0};

bool ProcessAlive(long pid) {
  return pid > 0 && (kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM);
}

// Where a process id means something: the host name and the process-id namespace (containers on
// one host share its name, not their pid namespace), as letters, digits and '-' only.
std::string MakeProcessSpace() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = 0;
  std::string out;
  for (const char* c = host; *c && out.size() < 64; ++c)
    out += std::isalnum(static_cast<unsigned char>(*c)) || *c == '-' ? *c : '-';
  struct stat st {};
  if (stat("/proc/self/ns/pid", &st) == 0) out += "~" + std::to_string(st.st_ino);
  return out.empty() ? "local" : out;
}

// A temporary of another host or namespace is judged by its age only: nothing mvtm writes takes
// an hour between two writes, so one untouched that long belongs to a dead run.
constexpr auto kForeignTemporaryAge = std::chrono::hours(1);
}  // namespace

const std::string& ProcessSpace() {
  static const std::string space = MakeProcessSpace();
  return space;
}

void CreateFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(dir.string(), 0, "cannot create folder: " + ec.message());
}

bool LinkOrCopy(const fs::path& from, const fs::path& to, std::error_code& ec) {
  fs::create_hard_link(from, to, ec);
  if (!ec) return true;
  ec.clear();
  fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
  return false;
}

fs::path TemporaryPathFor(const fs::path& final_path) {
  return final_path.parent_path() /
         ("." + final_path.stem().string() + ".tmp-" + std::to_string(getpid()) + "-" +
          std::to_string(g_counter++) + "@" + ProcessSpace() + final_path.extension().string());
}

AtomicFile::AtomicFile(const fs::path& final_path) : final_(final_path) {
  fs::path dir = final_.parent_path();
  if (!dir.empty()) CreateFolder(dir);
  temp_ = TemporaryPathFor(final_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::Commit() {
  std::error_code ec;
  fs::rename(temp_, final_, ec);
  if (ec) throw Error(final_.string(), 0, "cannot write: " + ec.message());
  committed_ = true;
}

Error WriteFailed(const fs::path& path, int err) {
  return Error(path.string(), 0,
               err != 0 ? std::string("write failed: ") + strerror(err)
                        : std::string("write failed (disk full?)"));
}

// Writes the temporary of `out` through `write`; errors name `out`'s final path.
static void WriteTemporary(const AtomicFile& out, std::ios::openmode mode,
                           const std::function<void(std::ostream&)>& write) {
  const fs::path& path = out.final_path();
  {
    std::ofstream f(out.temp_path(), mode | std::ios::trunc);
    if (!f)
      throw Error(path.string(), 0, std::string("cannot open for writing: ") + strerror(errno));
    f.imbue(std::locale::classic());
    f.precision(17);
    // The first failure's reason is kept: the callback may make other calls after it.
    int err = StreamFailure(f, [&] { write(f); });
    const int close_err = StreamFailure(f, [&] { f.close(); });
    if (err == 0) err = close_err;
    if (f.fail()) throw WriteFailed(path, err);
  }
}

static void WriteAtomic(const fs::path& path, std::ios::openmode mode,
                        const std::function<void(std::ostream&)>& write) {
  AtomicFile out(path);
  WriteTemporary(out, mode, write);
  out.Commit();
}

void WriteTogetherAtomic(const std::vector<FileWriter>& files, bool binary,
                         const std::function<void()>& before_rename) {
  const std::ios::openmode mode = binary ? std::ios::binary : std::ios::openmode{};
  std::vector<std::unique_ptr<AtomicFile>> outs;
  for (const FileWriter& w : files) {
    outs.push_back(std::make_unique<AtomicFile>(w.path));
    WriteTemporary(*outs.back(), mode, w.write);
  }
  if (before_rename) before_rename();
  for (auto& out : outs) out->Commit();
}

void WriteBytesAtomic(const fs::path& path, const void* data, size_t size) {
  AtomicFile out(path);
  int fd = ::open(out.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
    throw Error(path.string(), 0, std::string("cannot open for writing: ") + strerror(errno));
  const char* p = static_cast<const char*>(data);
  size_t left = size;
  while (left > 0) {
    ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      throw WriteFailed(path, err);
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::close(fd) != 0) throw WriteFailed(path, errno);
  out.Commit();
}

void WriteTextAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  WriteAtomic(path, std::ios::out, write);
}

void WriteBinaryAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  WriteAtomic(path, std::ios::out | std::ios::binary, write);
}

bool IsUpToDate(const fs::path& output, const std::vector<fs::path>& inputs) {
  std::error_code ec;
  if (!fs::is_regular_file(output, ec)) return false;  // a folder under the name is no output
  auto out_time = fs::last_write_time(output, ec);
  if (ec) return false;
  for (const auto& in : inputs) {
    auto t = fs::last_write_time(in, ec);
    if (ec) continue;
    if (t > out_time) return false;
  }
  return true;
}

void RemoveStaleTemporaries(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::string n = it->path().filename().string();
    auto p = n.find(".tmp-");
    if (n.empty() || n[0] != '.' || p == std::string::npos) continue;
    char* pid_end = nullptr;
    const long pid = std::strtol(n.c_str() + p + 5, &pid_end, 10);
    // ".tmp-PID-N@SPACE.EXT"; a name without "@SPACE" is from this machine (older mvtm).
    const size_t at = n.find('@', size_t(pid_end - n.c_str()));
    const std::string space =
        at == std::string::npos ? ProcessSpace() : n.substr(at + 1, n.find('.', at) - at - 1);
    std::error_code age_ec;
    bool dead = !ProcessAlive(pid);
    if (space != ProcessSpace()) {
      const auto written = it->last_write_time(age_ec);
      dead = !age_ec && fs::file_time_type::clock::now() - written > kForeignTemporaryAge;
    }
    if (dead) fs::remove_all(it->path(), ec);
  }
}

}  // namespace mvtm
