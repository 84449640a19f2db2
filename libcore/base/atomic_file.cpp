#include "base/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <locale>
#include <memory>
#include <set>
#include <utility>

#include "base/error.h"

namespace mvtm {

namespace {
std::atomic<unsigned> g_counter{0};

// The folder a path names, "" being the current one.
fs::path FolderOrCurrent(const fs::path& dir) { return dir.empty() ? fs::path(".") : dir; }

// A zombie (killed, not yet reaped by its parent) is not alive: its locks are already released.
bool ProcessAlive(long pid) {
  if (pid <= 0 || (kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM)) return false;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return true;  // no /proc: the signal's answer
  const size_t paren = line.rfind(')');        // "PID (COMM) STATE ...": COMM may hold anything
  return paren == std::string::npos || paren + 2 >= line.size() ||
         (line[paren + 2] != 'Z' && line[paren + 2] != 'X');
}

// Where a process id means something: the host name, the process-id namespace (containers on
// one host share its name, not their pid namespace) and the boot (pids start again after a
// reboot: a journal a power loss left must not be taken for the live process now holding its
// pid), as letters, digits and '-' only, joined by '~': HOST~NS~BOOT.
std::string MakeProcessSpace() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = 0;
  std::string out;
  for (const char* c = host; *c && out.size() < 64; ++c)
    out += std::isalnum(static_cast<unsigned char>(*c)) || *c == '-' ? *c : '-';
  if (out.empty()) out = "local";
  struct stat st {};
  out += "~" + std::to_string(stat("/proc/self/ns/pid", &st) == 0 ? st.st_ino : 0);
  std::ifstream boot_id("/proc/sys/kernel/random/boot_id");
  std::string boot;
  if (std::getline(boot_id, boot)) {
    boot.erase(std::remove_if(boot.begin(), boot.end(),
                              [](char c) { return !std::isxdigit(static_cast<unsigned char>(c)); }),
               boot.end());
    if (!boot.empty()) out += "~" + boot.substr(0, 12);
  }
  return out;
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
  if (dir.empty() || fs::is_directory(dir, ec)) return;
  fs::path first = dir;  // the outermost folder this call creates
  while (first.has_parent_path() && first.parent_path() != first &&
         !fs::exists(first.parent_path(), ec))
    first = first.parent_path();
  fs::create_directories(dir, ec);
  if (ec) throw Error(dir.string(), 0, "cannot create folder: " + ec.message());
  // Each new folder's entry on the disk (in its parent), so the files synced in it stay found.
  for (fs::path d = dir;; d = d.parent_path()) {
    SyncFolder(d.parent_path());
    if (d == first || !d.has_parent_path()) break;
  }
}

void ReplaceFolder(const fs::path& built, const fs::path& dest) {
  SyncTree(built);
  const fs::path parent = FolderOrCurrent(dest.parent_path());
  std::error_code ec;
  if (fs::exists(fs::symlink_status(dest, ec))) {
    // One step: the old folder takes the built one's name, so there is always a whole DEST.
    if (::renameat2(AT_FDCWD, built.c_str(), AT_FDCWD, dest.c_str(), RENAME_EXCHANGE) == 0) {
      SyncFolder(parent);
      fs::remove_all(built, ec);
      return;
    }
    if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP && errno != EXDEV)
      throw Error(dest.string(), 0, std::string("cannot replace: ") + strerror(errno));
    // No exchange on this file system: the old folder aside first. A kill between the two
    // renames leaves both under temporary names, which the next run sweeps: a rerun makes DEST.
    const fs::path aside = TemporaryPathFor(dest);
    fs::rename(dest, aside, ec);
    if (ec) throw Error(dest.string(), 0, "cannot replace: " + ec.message());
    fs::rename(built, dest, ec);
    if (ec) {
      std::error_code back;
      fs::rename(aside, dest, back);  // the old one stays DEST
      throw Error(dest.string(), 0, "cannot write: " + ec.message());
    }
    SyncFolder(parent);
    fs::remove_all(aside, ec);
    return;
  }
  fs::rename(built, dest, ec);
  if (ec) throw Error(dest.string(), 0, "cannot write: " + ec.message());
  SyncFolder(parent);
}

void SyncTree(const fs::path& root) {
  std::error_code ec;
  for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::file_status st = it->symlink_status(ec);  // a link's target is not the tree's
    if (ec) break;
    if (fs::is_directory(st))
      SyncFolder(it->path());
    else if (fs::is_regular_file(st))
      SyncFile(it->path(), it->path());
  }
  if (ec) throw Error(root.string(), 0, "cannot list to sync: " + ec.message());
  SyncFolder(root);
  SyncFolder(root.parent_path());
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
  Sync();
  Rename();
  SyncFolder(final_.parent_path());
}

void AtomicFile::Sync() const { SyncFile(temp_, final_); }

void AtomicFile::Rename() {
  std::error_code ec;
  fs::rename(temp_, final_, ec);
  if (ec) throw Error(final_.string(), 0, "cannot write: " + ec.message());
  committed_ = true;
}

namespace {
// fsync(2) or fdatasync(2) of `fd`, interrupted calls repeated: 0, or the errno of the failure.
// EINVAL, EROFS, ENOTSUP (a file that cannot be synced: a pipe, a file system without the call,
// a FUSE or network one that does not sync folders) count as done.
int SyncDescriptor(int fd, bool data_only) {
  int r;
  while ((r = data_only ? ::fdatasync(fd) : ::fsync(fd)) != 0 && errno == EINTR) {
  }
  const bool cannot = errno == EINVAL || errno == EROFS || errno == ENOTSUP || errno == EOPNOTSUPP;
  return r == 0 || cannot ? 0 : errno;
}
}  // namespace

void SyncFile(const fs::path& path, const fs::path& named) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 && errno == EACCES) fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);  // umask 0277
  if (fd < 0)
    throw Error(named.string(), 0, std::string("cannot open to sync: ") + strerror(errno));
  const int err = SyncDescriptor(fd, true);
  ::close(fd);
  if (err != 0) throw WriteFailed(named, err);
}

void SyncFolder(const fs::path& dir) {
  const fs::path d = FolderOrCurrent(dir);
  const int fd = ::open(d.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0 && (errno == EACCES || errno == EPERM)) return;  // write and search rights only
  if (fd < 0) throw Error(d.string(), 0, std::string("cannot open to sync: ") + strerror(errno));
  const int err = SyncDescriptor(fd, false);
  ::close(fd);
  if (err != 0)
    throw Error(d.string(), 0, std::string("cannot write the folder's entries: ") + strerror(err));
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

namespace {

std::function<void(size_t)>& AfterRenameHook() {
  static std::function<void(size_t)> hook;
  return hook;
}

constexpr const char* kJournalPrefix = ".mvtm-journal-";
constexpr const char* kJournalHead = "mvtm-journal 1";

// A journal's steps: the files to remove, then the temporaries to rename (names in its folder).
struct Journal {
  std::vector<std::string> removals;
  std::vector<std::pair<std::string, std::string>> renames;  // temporary, final
};

void WriteJournal(const fs::path& path, const Journal& j) {
  WriteAtomic(path, std::ios::out, [&](std::ostream& f) {
    f << kJournalHead << '\n';
    for (const auto& n : j.removals) f << "remove\n" << n << '\n';
    for (const auto& [from, to] : j.renames) f << "rename\n" << from << '\n' << to << '\n';
  });
}

// Throws when the journal is not one this code wrote whole (an empty or foreign file); reads
// `file`, names `path` in its errors.
Journal ReadJournal(const fs::path& file, const fs::path& path) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line) || line != kJournalHead)
    throw Error(path.string(), 1, "not an mvtm commit journal");
  Journal j;
  long no = 1;
  const auto next = [&] {
    ++no;
    // A file of this folder only: never "." or "..", nothing with a '/' or a NUL.
    if (!std::getline(in, line) || line.empty() || line == "." || line == ".." ||
        line.find_first_of(std::string("/\0", 2)) != std::string::npos)
      throw Error(path.string(), no, "truncated or damaged commit journal");
    return line;
  };
  while (std::getline(in, line)) {
    ++no;
    if (line == "remove") {
      j.removals.push_back(next());
    } else if (line == "rename") {
      std::string from = next();
      if (from.find(".tmp-") == std::string::npos)  // what is renamed is a temporary
        throw Error(path.string(), no, "a commit journal renames a file that is no temporary");
      j.renames.emplace_back(from, next());
    } else {
      throw Error(path.string(), no, "unknown step '" + line + "' in a commit journal");
    }
  }
  return j;
}

// The writer a name "...PID-N@SPACE..." belongs to, "PID" starting at `pid_at` (a name without
// "@SPACE" is from this machine: older mvtm).
struct Owner {
  long pid;
  std::string space;
  std::string Key() const { return std::to_string(pid) + "@" + space; }
};
Owner OwnerOf(const std::string& n, size_t pid_at) {
  char* pid_end = nullptr;
  const long pid = std::strtol(n.c_str() + pid_at, &pid_end, 10);
  const size_t at = n.find('@', size_t(pid_end - n.c_str()));
  return {pid,
          at == std::string::npos ? ProcessSpace() : n.substr(at + 1, n.find('.', at) - at - 1)};
}

// Where an owner's SPACE is. kHere: this host and namespace in this boot, or where a boot is not
// known (a SPACE of older mvtm, HOST~NS, or this process's where /proc/sys cannot be read): its
// pid is checked. kOtherBoot: this host name and namespace, another boot id: an earlier boot of
// this machine, or another machine of the same name sharing the folder (told apart by the entry's
// time). kElsewhere: another host or namespace.
enum class Where { kHere, kOtherBoot, kElsewhere };
Where WhereOf(const std::string& space) {
  const std::string& here = ProcessSpace();
  if (space == here) return Where::kHere;
  const auto split = [](const std::string& sp) {  // HOST~NS, BOOT
    const size_t a = sp.find('~');
    const size_t b = a == std::string::npos ? a : sp.find('~', a + 1);
    return std::make_pair(sp.substr(0, b), b == std::string::npos ? "" : sp.substr(b + 1));
  };
  const auto mine = split(here), theirs = split(space);
  if (theirs.first != mine.first) return Where::kElsewhere;
  return theirs.second.empty() || mine.second.empty() ? Where::kHere : Where::kOtherBoot;
}

// The entry was last written before this boot began (now less the time since boot, a second of
// slack): its writer cannot be running. A clock set wrong at the earlier boot errs towards
// "not before", the age rule's side.
bool WrittenBeforeThisBoot(const fs::path& p) {
  struct stat st {};
  timespec now{}, up{};
  if (::lstat(p.c_str(), &st) != 0 || clock_gettime(CLOCK_REALTIME, &now) != 0 ||
      clock_gettime(CLOCK_BOOTTIME, &up) != 0)
    return false;
  const double boot = double(now.tv_sec - up.tv_sec) + 1e-9 * double(now.tv_nsec - up.tv_nsec);
  return double(st.st_mtim.tv_sec) + 1e-9 * double(st.st_mtim.tv_nsec) < boot - 1.0;
}

// That owner is gone: this boot's process PID (of this host and namespace) is not alive, the
// entry of this host name and namespace was written before this boot, or (another host's,
// namespace's or boot's) it is an hour old.
bool OwnerGone(const fs::directory_entry& e, const Owner& owner) {
  const Where where = WhereOf(owner.space);
  if (where == Where::kHere) return !ProcessAlive(owner.pid);
  if (where == Where::kOtherBoot && WrittenBeforeThisBoot(e.path())) return true;
  std::error_code ec;
  const auto written = e.last_write_time(ec);
  return !ec && fs::file_time_type::clock::now() - written > kForeignTemporaryAge;
}

// A journal name of this process, unique to the call.
fs::path NewJournalPath(const fs::path& dir) {
  return dir / (kJournalPrefix + std::to_string(getpid()) + "-" + std::to_string(g_counter++) +
                "@" + ProcessSpace());
}

[[noreturn]] void CannotFinish(const fs::path& p, const std::error_code& e) {
  throw Error(p.string(), 0, "cannot finish an interrupted write: " + e.message());
}

// Rolls a dead writer's journal forward: its temporaries (complete when the journal was written)
// are renamed into place and the files it was replacing removed, so the set it was committing
// appears whole. The journal is claimed first (renamed to a journal name of this process): two
// finishers never follow one journal (the second finds it gone), and while this one works the
// others take it for a live writer's. A file of the set written after the journal (modification
// time: another program's newer output, a model COLMAP wrote there since) is never overwritten or
// removed: where there is one the journal's set is stale and dropped instead (its temporaries
// removed, nothing renamed), and each file is checked again just before its step.
void FinishJournal(const fs::path& path) {
  const fs::path dir = path.parent_path(), claimed = NewJournalPath(dir);
  std::error_code ec;
  fs::rename(path, claimed, ec);
  if (ec == std::errc::no_such_file_or_directory) return;  // another finisher took it
  if (ec) CannotFinish(path, ec);
  Journal j;
  try {
    j = ReadJournal(claimed, path);
  } catch (const Error&) {
    fs::rename(claimed, path, ec);  // back under its own name, which the error gives
    throw;
  }
  const auto journal_time = fs::last_write_time(claimed, ec);
  if (ec) CannotFinish(claimed, ec);
  const auto newer = [&](const fs::path& p) {
    std::error_code e;
    const auto t = fs::last_write_time(p, e);
    return !e && t > journal_time;
  };
  bool pending = false, superseded = false;
  for (const auto& [from, to] : j.renames)
    pending = pending || fs::exists(dir / from), superseded = superseded || newer(dir / to);
  for (const auto& n : j.removals) superseded = superseded || newer(dir / n);
  if (pending && !superseded) {
    for (const auto& n : j.removals) {
      std::error_code e;
      if (!newer(dir / n)) fs::remove(dir / n, e);
      if (e) CannotFinish(dir / n, e);
    }
    for (const auto& [from, to] : j.renames) {
      std::error_code e;
      if (fs::exists(dir / from) && !newer(dir / to)) fs::rename(dir / from, dir / to, e);
      if (e && e != std::errc::no_such_file_or_directory) CannotFinish(dir / to, e);
    }
  }
  for (const auto& [from, to] : j.renames) fs::remove(dir / from, ec);  // what is left is stale
  SyncFolder(dir);  // the set on the disk before the journal that completes it goes
  std::error_code e;
  fs::remove(claimed, e);
  if (e)
    throw Error(claimed.string(), 0, "cannot remove a finished commit journal: " + e.message());
}

}  // namespace

void SetAfterRenameHookForTest(std::function<void(size_t)> hook) {
  AfterRenameHook() = std::move(hook);
}

FolderLock::FolderLock(const fs::path& dir, bool exclusive) {
  fd_ = ::open(FolderOrCurrent(dir).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) return;
  const int op = exclusive ? LOCK_EX : LOCK_SH;
  int r = ::flock(fd_, op | LOCK_NB);
  if (r != 0 && errno == EWOULDBLOCK) {
    waited_ = true;
    while ((r = ::flock(fd_, op)) != 0 && errno == EINTR) {
    }
  }
  if (r != 0) {  // no locks on this file system: the journals alone
    ::close(fd_);
    fd_ = -1;
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

namespace {

// The commit journals in `d` with their writers.
std::vector<std::pair<fs::directory_entry, Owner>> Journals(const fs::path& d) {
  std::error_code ec;
  std::vector<std::pair<fs::directory_entry, Owner>> journals;
  for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string n = it->path().filename().string();
    if (n.rfind(kJournalPrefix, 0) == 0)
      journals.emplace_back(*it, OwnerOf(n, std::string(kJournalPrefix).size()));
  }
  return journals;
}

// The journals of dead writers in `d`, in name order.
std::vector<fs::path> DeadJournals(const fs::path& d) {
  std::vector<fs::path> dead;
  for (const auto& [e, owner] : Journals(d))
    if (OwnerGone(e, owner)) dead.push_back(e.path());
  std::sort(dead.begin(), dead.end());
  return dead;
}

}  // namespace

void FinishInterruptedWrites(const fs::path& dir) {
  const fs::path d = FolderOrCurrent(dir);  // a model in the current folder
  if (DeadJournals(d).empty()) return;      // the common case takes no lock
  const FolderLock lock(d, true);
  for (const auto& j : DeadJournals(d)) FinishJournal(j);
}

namespace {

// A journal in `d` of another live process of this host and namespace. Under a lock held on `d`,
// its writer is not in its commit (that holds the exclusive lock): it is dying (its locks go
// before it is a zombie), or its commit failed and it lives on.
bool OthersJournalHere(const fs::path& d) {
  for (const auto& [e, o] : Journals(d))
    if (WhereOf(o.space) == Where::kHere && o.pid != long(getpid()) && ProcessAlive(o.pid))
      return true;
  return false;
}

}  // namespace

FolderLock LockForReading(const fs::path& dir) {
  const fs::path d = FolderOrCurrent(dir);
  bool waited = false;
  for (int round = 0;; ++round) {
    FinishInterruptedWrites(d);
    FolderLock lock(d, false);
    waited = waited || lock.waited();
    if (!waited) return lock;  // no writer was in its commit: the common case, one scan
    // The writer this waited for may have been killed between its renames: its journal is now a
    // dead one's (or, for a moment, a dying one's), and its set half renamed. Finish it and lock
    // again; a writer whose commit failed and that lives on is waited for half a second at most.
    if (!DeadJournals(d).empty()) continue;
    if (round >= 100 || !OthersJournalHere(d)) return lock;
    usleep(5000);
  }
}

void WriteTogetherAtomic(const std::vector<FileWriter>& files, bool binary,
                         const std::vector<fs::path>& replaced) {
  if (files.empty()) return;
  const std::ios::openmode mode = binary ? std::ios::binary : std::ios::openmode{};
  const fs::path dir = files.front().path.parent_path();
  std::vector<std::unique_ptr<AtomicFile>> outs;
  for (const FileWriter& w : files) {
    if (w.path.parent_path() != dir)
      throw Error(w.path.string(), 0, "files committed together must share one folder");
    outs.push_back(std::make_unique<AtomicFile>(w.path));
    WriteTemporary(*outs.back(), mode, w.write);
  }
  for (const auto& out : outs) out->Sync();  // on the disk before the journal names them
  // Readers (shared lock) wait for the renames; an earlier, killed commit here goes first.
  const FolderLock lock(dir, true);
  for (const auto& dead : DeadJournals(FolderOrCurrent(dir))) FinishJournal(dead);
  // The journal makes the renames one step: a kill between two of them leaves it, and the next
  // reader or writer of the folder (FinishInterruptedWrites) completes them.
  Journal j;
  for (const fs::path& r : replaced) {
    if (r.parent_path() != dir)
      throw Error(r.string(), 0, "files committed together must share one folder");
    std::error_code ec;
    if (fs::exists(fs::symlink_status(r, ec))) j.removals.push_back(r.filename().string());
  }
  for (const auto& out : outs)
    j.renames.emplace_back(out->temp_path().filename().string(),
                           out->final_path().filename().string());
  const fs::path journal = NewJournalPath(dir);  // "" / NAME: the current folder's
  WriteJournal(journal, j);  // an atomic write: its data and its entry on the disk
  size_t renamed = 0;
  try {
    for (const auto& n : j.removals) {
      std::error_code ec;
      fs::remove(dir / n, ec);
      if (ec)
        throw Error((dir / n).string(), 0, "cannot remove the file it replaces: " + ec.message());
    }
    for (auto& out : outs) {
      out->Rename();
      if (AfterRenameHook()) AfterRenameHook()(++renamed);
    }
    SyncFolder(dir);  // the set on the disk before its journal goes
  } catch (...) {
    // The journal names the temporaries not yet renamed: they stay, so that the set is finished
    // once this process is gone (or the error is the next reader's to see).
    for (auto& out : outs) out->Release();
    throw;
  }
  std::error_code ec;
  fs::remove(journal, ec);
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
  FinishInterruptedWrites(dir);  // a dead commit's temporaries are its new files: renamed first
  std::error_code ec;
  std::vector<std::pair<fs::path, std::string>> dead;  // temporary, owner
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::string n = it->path().filename().string();
    auto p = n.find(".tmp-");
    if (n.empty() || n[0] != '.' || p == std::string::npos) continue;
    const Owner owner = OwnerOf(n, p + 5);
    if (OwnerGone(*it, owner)) dead.emplace_back(it->path(), owner.Key());
  }
  if (dead.empty()) return;
  // A journal of the same owner names them (one FinishInterruptedWrites left: another host's,
  // not an hour old, or one whose writer died after it looked): they stay for it. Gathered after
  // their owners were found gone, so no journal of theirs can appear later.
  std::set<std::string> journal_owners;
  for (const auto& [e, owner] : Journals(dir)) journal_owners.insert(owner.Key());
  for (const auto& [path, owner] : dead)
    if (!journal_owners.count(owner)) fs::remove_all(path, ec);
}

}  // namespace mvtm
