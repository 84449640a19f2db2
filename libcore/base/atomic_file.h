// mvtm — atomic output files and up-to-date checks.
//
// Every output of every tool is written to a temporary name in the destination folder
// (".STEM.tmp-PID-N@SPACE.EXT": hidden, unique per process and file, SPACE naming the host,
// process-id namespace and boot the PID belongs to, same extension so format-by-extension writers
// still work) and renamed over the final name only once it is complete, so a crash or `kill -9`
// never leaves a half-written output. The temporary's data reach the disk (fdatasync) before the
// rename, and the folder's entry (fsync of the folder) after it, so a power loss or a kernel
// crash leaves the old file or the new one, whole, and a file a tool reported written stays
// written. A re-run skips outputs that exist and are newer than all their inputs (unless the
// tool is given --force).
//
// Thread safety: distinct AtomicFile objects may be used from different threads.
#pragma once

#include <cerrno>
#include <filesystem>
#include <functional>
#include <ios>
#include <ostream>
#include <string>
#include <vector>

#include "base/error.h"

namespace mvtm {

namespace fs = std::filesystem;

class AtomicFile {
 public:
  // Creates the parent folder of `final_path` if needed.
  explicit AtomicFile(const fs::path& final_path);
  ~AtomicFile();  // removes the temporary file unless Commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const fs::path& temp_path() const { return temp_; }
  const fs::path& final_path() const { return final_; }
  // Renames the temporary file over the final path (atomic on POSIX within one filesystem), its
  // data on the disk first and the folder's new entry after (SyncFile, then SyncFolder): Sync(),
  // Rename(), SyncFolder(final's folder). Throws Error naming the final path when a step fails.
  void Commit();
  // The temporary's data on the disk (SyncFile); WriteTogetherAtomic syncs every file of a set,
  // then renames them all (Rename) and syncs their folder once.
  void Sync() const;
  // Renames the temporary over the final path, nothing synced.
  void Rename();
  // Keeps the temporary file (a commit journal names it: FinishInterruptedWrites renames it).
  void Release() { committed_ = true; }

 private:
  fs::path final_;
  fs::path temp_;
  bool committed_ = false;
};

// Writes text through `write` (stream imbued with the classic "C" locale, precision 17) to a
// temporary file and renames it to `path`. Throws Error when the stream fails.
void WriteTextAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write);
// Same for binary content.
void WriteBinaryAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write);

// The error for a failed write of `path`: "write failed: REASON", REASON the system's for `err`
// (an errno: the failed write(2) or close(2)'s), or "write failed (disk full?)" when err is 0.
Error WriteFailed(const fs::path& path, int err);

// Runs `op` (a write to, flush or close of stream `f`) and returns the reason of a failure of
// `f`: a file stream keeps none, but the write(2) or close(2) that failed when its buffer went out
// left it in errno, cleared before `op` so that it is never an earlier call's. 0 when `f` has not
// failed, or failed without a system call (WriteFailed then says "disk full?").
template <class Op>
int StreamFailure(const std::ios& f, Op&& op) {
  errno = 0;
  op();
  return f.fail() ? errno : 0;
}

// Files that only make sense together (a COLMAP model's cameras, images and points3D), in one
// folder: each is written to its temporary, and only when every one is complete are they renamed
// into place, after the files in `replaced` (another format's, say) are removed. So a failed write
// (a full disk) leaves every final file as it was, never a new file beside an old one. The
// removals and renames are one step: a journal (".mvtm-journal-PID-N@SPACE" in the folder) lists
// them before the first is made and goes after the last, so a writer killed between two of them
// leaves the journal, and FinishInterruptedWrites completes its set. On the disk, the order is the
// same: every temporary's data, then the journal (its data and entry), then the removals and
// renames (the folder synced), and only then is the journal removed, so after a power loss the
// folder holds the old set, the new one, or the journal that completes it.
struct FileWriter {
  fs::path path;
  std::function<void(std::ostream&)> write;
};
void WriteTogetherAtomic(const std::vector<FileWriter>& files, bool binary,
                         const std::vector<fs::path>& replaced = {});

// A lock on the folder `dir` itself (flock(2) on the folder: no file is made), held for the
// object's lifetime: exclusive while WriteTogetherAtomic commits there (from its journal to its
// last rename) and while FinishInterruptedWrites rolls a journal forward; shared, through
// LockForReading, by readers of files that go together (the COLMAP model readers of libcore/io,
// densify's depth and confidence). Where the folder cannot be opened (it does not exist yet) or
// its file system has no such locks (NFS gives none on a folder), nothing is held and the
// journals alone keep their guarantees. flock's locks of one process conflict as another's do:
// never take an exclusive lock (nor call FinishInterruptedWrites or WriteTogetherAtomic) on a
// folder while holding a lock on it.
class FolderLock {
 public:
  FolderLock(const fs::path& dir, bool exclusive);
  ~FolderLock();
  FolderLock(FolderLock&& other) noexcept : fd_(other.fd_), waited_(other.waited_) {
    other.fd_ = -1;
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  FolderLock& operator=(FolderLock&&) = delete;
  // It had to wait for another holder (a writer in its commit, for a shared lock).
  bool waited() const { return waited_; }

 private:
  int fd_ = -1;
  bool waited_ = false;
};

// The shared lock a reader of a set in `dir` holds while it reads: the folder's interrupted
// commits finished first (FinishInterruptedWrites), then the lock taken, and taken again when a
// writer it waited for died in the middle of its renames (its journal finished first). So the
// reader sees every set whole: a live writer's renames are waited for, a dead one's completed.
FolderLock LockForReading(const fs::path& dir);

// Completes the commits of WriteTogetherAtomic that a dead process left in `dir` ("" is the
// current folder): of this host and namespace when its process is gone or it was written in an
// earlier boot (another boot id, before this boot began); of another when the journal is an hour
// old. A live writer's journal is left (LockForReading waits for its commit),
// and so is a journal of another host younger than that. Each journal is claimed first (renamed
// to one of this process), so concurrent finishers never follow one journal twice. The whole new
// set is put in place; where a file of the set (a final name or one it was to remove) has a
// modification time after the journal's, another program wrote it since and the stale set is
// dropped instead (the files as they are: possibly a mix of that program's and the set's). Called
// by LockForReading (every COLMAP model reader of libcore/io, densify's pair readers), by
// WriteTogetherAtomic in its folder (the same roll-forward, under its own lock), and by
// RemoveStaleTemporaries, which also keeps any temporary that a journal of the same owner still
// names. Throws Error when a step cannot be made (a read-only folder) or a journal is damaged (the
// error names it: remove it to go on).
void FinishInterruptedWrites(const fs::path& dir);

// For a test of a kill between two renames: called after each rename of WriteTogetherAtomic with
// how many it has made (a test's forked child kills itself there). Empty by default.
void SetAfterRenameHookForTest(std::function<void(size_t)> hook);

// Writes `size` bytes to a temporary file and renames it to `path`. Every write() and the
// close() are checked, so a full disk is an Error and nothing is renamed into place.
void WriteBytesAtomic(const fs::path& path, const void* data, size_t size);

// Waits until the data of the file `path` are on the disk (fdatasync(2)). Throws
// WriteFailed(named, errno) when they cannot be written there (EIO, ENOSPC on a thin or network
// file system), or Error when the file cannot be opened. A file system that keeps no such promise
// (EINVAL: a pipe, some special file systems) is not waited for.
void SyncFile(const fs::path& path, const fs::path& named);
// Waits until the folder `dir`'s entries (the renames and removals made in it) are on the disk
// (fsync(2) of the folder; "" is the current one). Throws Error naming the folder when they
// cannot be written; a folder that cannot be opened for reading, or a file system that cannot sync
// folders (EINVAL), is not waited for.
void SyncFolder(const fs::path& dir);
// Every file (SyncFile) and folder (SyncFolder) under `root`, `root` itself and its entry in its
// parent on the disk: a folder built whole under a temporary name (roadsplit's road) before and
// after it is renamed into place.
void SyncTree(const fs::path& root);
// Puts the folder `built` (made whole under a temporary name beside `dest`) in place of `dest`:
// its tree synced (SyncTree), then exchanged with an existing `dest` in one step
// (renameat2 RENAME_EXCHANGE), the folder synced, the old tree removed: a kill or power loss
// leaves the old `dest` or the new one, whole, the other at most under a temporary name that the
// next sweep removes (RemoveStaleTemporaries). Where the file system has no exchange (NFS), the
// old one is renamed aside first, and a kill between the two renames leaves no `dest` (both under
// temporary names): a rerun makes it again.
void ReplaceFolder(const fs::path& built, const fs::path& dest);
// Creates `dir` and its parents, each new folder's entry synced (SyncFolder of its parent); throws
// Error(dir, "cannot create folder: reason").
void CreateFolder(const fs::path& dir);

// Hard-links the file `from` to the new name `to`, or copies it where a link fails (another file
// system, one without hard links, or `to` exists: the copy overwrites it). True for a link, false
// for a copy; `ec` is set when both fail (the caller words the message: it knows which name a
// user should see).
bool LinkOrCopy(const fs::path& from, const fs::path& to, std::error_code& ec);

// True when `output` exists and is at least as new as every existing input.
bool IsUpToDate(const fs::path& output, const std::vector<fs::path>& inputs);

// A temporary name for `final_path` in its folder, ".STEM.tmp-PID-N@SPACE.EXT", unique to this
// process and call (what AtomicFile writes to; a tool building a whole folder at once, such as
// roadsplit's road, builds it under such a name and renames it into place).
fs::path TemporaryPathFor(const fs::path& final_path);

// Removes stale temporaries ".STEM.tmp-PID-N@SPACE.EXT" (files, or folders with what they hold)
// left in `dir` by processes that died: of this host and namespace when process PID is gone or
// it was written in an earlier boot; of another (a cluster node or a container sharing the
// folder, where PID says nothing) when untouched for an hour. A name without "@SPACE" counts as
// this host's. Finishes the folder's interrupted commits first (FinishInterruptedWrites; its Errors
// pass through) and keeps the temporaries a journal of their owner names.
void RemoveStaleTemporaries(const fs::path& dir);

// This process's SPACE, HOST~NS~BOOT: host name, pid-namespace inode and the boot id's first 12
// hex digits (no boot where it cannot be read), letters, digits, '-' and '~'.
const std::string& ProcessSpace();

}  // namespace mvtm
