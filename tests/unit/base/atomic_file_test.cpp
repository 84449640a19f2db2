// Atomic outputs: nothing appears under the final name until Commit; stale temporaries go away.
#include "base/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <future>
#include <sstream>

#include "base/error.h"
#include "support/killed_commit.h"

namespace mvtm {
namespace {

fs::path TempDir(const char* name) {
  fs::path d =
      fs::temp_directory_path() / ("mvtm-atomic-" + std::string(name) + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(AtomicFile, FinalNameAppearsOnlyOnCommit) {
  fs::path d = TempDir("commit");
  {
    AtomicFile f(d / "sub" / "out.png");
    EXPECT_EQ(f.temp_path().extension(), ".png");  // format-by-extension writers still work
    std::ofstream(f.temp_path()) << "data";
    EXPECT_FALSE(fs::exists(d / "sub" / "out.png"));
    f.Commit();
  }
  EXPECT_TRUE(fs::exists(d / "sub" / "out.png"));
  EXPECT_EQ(std::distance(fs::directory_iterator(d / "sub"), fs::directory_iterator()), 1);
  fs::remove_all(d);
}

TEST(AtomicFile, AbandonedWriteLeavesNothing) {
  fs::path d = TempDir("abandon");
  std::ofstream(d / "out.txt") << "old";
  try {
    WriteTextAtomic(d / "out.txt", [](std::ostream& o) {
      o << "half";
      throw Error("simulated crash");
    });
  } catch (const Error&) {
  }
  std::ifstream in(d / "out.txt");
  std::string s;
  in >> s;
  EXPECT_EQ(s, "old");  // the previous output is intact
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);
  fs::remove_all(d);
}

TEST(AtomicFile, UpToDateComparesTimes) {
  fs::path d = TempDir("uptodate");
  std::ofstream(d / "in") << "x";
  EXPECT_FALSE(IsUpToDate(d / "out", {d / "in"}));
  std::ofstream(d / "out") << "y";
  fs::last_write_time(d / "out", fs::last_write_time(d / "in") + std::chrono::seconds(2));
  EXPECT_TRUE(IsUpToDate(d / "out", {d / "in"}));
  fs::last_write_time(d / "in", fs::last_write_time(d / "out") + std::chrono::seconds(2));
  EXPECT_FALSE(IsUpToDate(d / "out", {d / "in"}));
  fs::remove_all(d);
}

TEST(AtomicFile, RemovesTemporariesOfDeadProcesses) {
  fs::path d = TempDir("stale");
  std::ofstream(d / ".a.tmp-999999999-0.png") << "x";                           // no such pid
  std::ofstream(d / (".b.tmp-" + std::to_string(getpid()) + "-0.png")) << "x";  // alive: kept
  // This host's, named as written now: dead pid removed, live kept.
  const std::string here = "@" + ProcessSpace();
  std::ofstream(d / (".c.tmp-999999999-1" + here + ".exr")) << "x";
  std::ofstream(d / (".d.tmp-" + std::to_string(getpid()) + "-1" + here + ".exr")) << "x";
  // Another host's (a cluster node sharing the folder): its pid says nothing here, so it stays
  // while recent, even with a pid that is not alive here, and goes once untouched for an hour.
  std::ofstream(d / ".e.tmp-999999999-2@node7~4026531836.png") << "x";
  std::ofstream(d / ".f.tmp-999999999-3@node7~4026531836.png") << "x";
  fs::last_write_time(d / ".f.tmp-999999999-3@node7~4026531836.png",
                      fs::file_time_type::clock::now() - std::chrono::minutes(61));
  // A folder built under a temporary name (roadsplit's road) goes with what it holds.
  fs::create_directories(d / ".g.tmp-999999999-4" / "Models" / "A");
  std::ofstream(d / ".g.tmp-999999999-4" / "Models" / "A" / "x.txt") << "x";
  fs::create_directories(d / (".h.tmp-" + std::to_string(getpid()) + "-5" + here) / "Models");
  RemoveStaleTemporaries(d);
  EXPECT_FALSE(fs::exists(d / ".g.tmp-999999999-4"));
  EXPECT_TRUE(fs::exists(d / (".h.tmp-" + std::to_string(getpid()) + "-5" + here)));
  EXPECT_FALSE(fs::exists(d / ".a.tmp-999999999-0.png"));
  EXPECT_TRUE(fs::exists(d / (".b.tmp-" + std::to_string(getpid()) + "-0.png")));
  EXPECT_FALSE(fs::exists(d / (".c.tmp-999999999-1" + here + ".exr")));
  EXPECT_TRUE(fs::exists(d / (".d.tmp-" + std::to_string(getpid()) + "-1" + here + ".exr")));
  EXPECT_TRUE(fs::exists(d / ".e.tmp-999999999-2@node7~4026531836.png"));
  EXPECT_FALSE(fs::exists(d / ".f.tmp-999999999-3@node7~4026531836.png"));
  fs::remove_all(d);
}

TEST(AtomicFile, TemporaryNamesCarryTheProcessSpaceAndKeepTheExtension) {
  fs::path d = TempDir("space");
  AtomicFile f(d / "frame.png");
  const std::string n = f.temp_path().filename().string();
  EXPECT_EQ(n.rfind(".frame.tmp-" + std::to_string(getpid()) + "-", 0), 0u) << n;
  EXPECT_NE(n.find("@" + ProcessSpace() + ".png"), std::string::npos) << n;
  EXPECT_EQ(f.temp_path().extension(), ".png");
  EXPECT_EQ(ProcessSpace().find_first_not_of(
                "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-~"),
            std::string::npos);
  fs::remove_all(d);
}

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<FileWriter> NewSet(const fs::path& d) {
  std::vector<FileWriter> files;
  for (const char* n : {"a.txt", "b.txt", "c.txt"})
    files.push_back({d / n, [n](std::ostream& f) { f << "new " << n; }});
  return files;
}

// Commits NewSet(d) over the old set in a forked child killed right after its first rename;
// true when it died so.
bool CommitKilledAfterFirstRename(const fs::path& d) {
  return test::CommitKilledAfterFirstRename(
      [&d] { WriteTogetherAtomic(NewSet(d), false, {d / "x.bin"}); });
}

fs::path OldSetIn(const char* name) {
  fs::path d = TempDir(name);
  for (const char* n : {"a.txt", "b.txt", "c.txt", "x.bin"}) std::ofstream(d / n) << "old " << n;
  return d;
}

size_t Entries(const fs::path& d) {
  return size_t(std::distance(fs::directory_iterator(d), fs::directory_iterator()));
}

// A kill between two renames of a set: the folder holds one new file beside two old ones and a
// journal; the next reader's FinishInterruptedWrites (or RemoveStaleTemporaries, which would
// otherwise delete the dead writer's temporaries, its new files) puts the whole new set in place.
TEST(AtomicFile, KillBetweenRenamesIsFinishedByTheNextReader) {
  for (int finish_by_sweep : {0, 1}) {
    fs::path d = OldSetIn("kill");
    ASSERT_TRUE(CommitKilledAfterFirstRename(d));
    EXPECT_EQ(Slurp(d / "a.txt"), "new a.txt");  // the mixed set a kill used to leave
    EXPECT_EQ(Slurp(d / "b.txt"), "old b.txt");
    EXPECT_FALSE(fs::exists(d / "x.bin"));  // the replaced file went before the renames
    EXPECT_EQ(Entries(d), 6u);              // a, b, c, b's and c's temporaries, the journal
    if (finish_by_sweep)
      RemoveStaleTemporaries(d);
    else
      FinishInterruptedWrites(d);
    for (const char* n : {"a.txt", "b.txt", "c.txt"})
      EXPECT_EQ(Slurp(d / n), std::string("new ") + n);
    EXPECT_EQ(Entries(d), 3u);
    FinishInterruptedWrites(d);  // nothing left to do
    EXPECT_EQ(Entries(d), 3u);
    fs::remove_all(d);
  }
}

// Resumes a paused writer when the test leaves its scope early (declared after the futures that
// wait for it, so it runs before their destructors would wait forever).
struct ResumeOnExit {
  test::PausedCommit& writer;
  ~ResumeOnExit() { writer.Resume(); }
};

std::string SetOf(const fs::path& d) {
  return Slurp(d / "a.txt") + "|" + Slurp(d / "b.txt") + "|" + Slurp(d / "c.txt");
}

// A live writer in the middle of its renames holds the folder's exclusive lock: a reader
// (LockForReading) waits and then reads one set whole, never the mix the folder holds while the
// writer is paused; a second commit into the folder waits too, so the two never interleave.
TEST(AtomicFile, ReadersAndWritersWaitForALiveCommit) {
  fs::path d = OldSetIn("live");
  test::PausedCommit writer([&d] { WriteTogetherAtomic(NewSet(d), false, {d / "x.bin"}); });
  ASSERT_TRUE(writer.Paused());
  EXPECT_EQ(SetOf(d), "new a.txt|old b.txt|old c.txt");  // the mix is there meanwhile
  auto reader = std::async(std::launch::async, [&d] {
    const FolderLock lock = LockForReading(d);
    return SetOf(d);
  });
  auto second = std::async(std::launch::async, [&d] {
    std::vector<FileWriter> files;
    for (const char* n : {"a.txt", "b.txt", "c.txt"})
      files.push_back({d / n, [n](std::ostream& f) { f << "second " << n; }});
    WriteTogetherAtomic(files, false);
  });
  const ResumeOnExit guard{writer};
  EXPECT_EQ(reader.wait_for(std::chrono::milliseconds(300)), std::future_status::timeout);
  EXPECT_EQ(second.wait_for(std::chrono::milliseconds(0)), std::future_status::timeout);
  writer.Resume();
  // One whole set: the paused writer's, or the second's had it gone first once the writer was
  // done; never a mix.
  const std::string seen = reader.get();
  EXPECT_TRUE(seen == "new a.txt|new b.txt|new c.txt" ||
              seen == "second a.txt|second b.txt|second c.txt")
      << seen;
  second.get();
  ASSERT_TRUE(writer.Finished());
  EXPECT_EQ(SetOf(d), "second a.txt|second b.txt|second c.txt");  // after the first, whole
  EXPECT_EQ(Entries(d), 3u);
  const FolderLock none(d / "missing", false);  // a folder that does not exist: nothing held
  fs::remove_all(d);
}

// The writer a reader waits for is killed between its renames: the reader's lock comes free on a
// half-renamed set, and LockForReading finishes the dead writer's journal before it reads.
TEST(AtomicFile, AReaderWaitingForAWriterThatIsKilledReadsItsSetWhole) {
  fs::path d = OldSetIn("killed-live");
  test::PausedCommit writer([&d] { WriteTogetherAtomic(NewSet(d), false, {d / "x.bin"}); });
  ASSERT_TRUE(writer.Paused());
  auto reader = std::async(std::launch::async, [&d] {
    const FolderLock lock = LockForReading(d);
    return SetOf(d);
  });
  const ResumeOnExit guard{writer};
  EXPECT_EQ(reader.wait_for(std::chrono::milliseconds(300)), std::future_status::timeout);
  writer.Kill();
  EXPECT_FALSE(writer.Finished());
  EXPECT_EQ(reader.get(), "new a.txt|new b.txt|new c.txt");
  EXPECT_EQ(Entries(d), 3u);
  fs::remove_all(d);
}

// A file of the set written again after the dead writer's journal is never overwritten or
// removed by the dead set: a final name (another program's new output) or a file it was to remove
// (COLMAP writing a binary model into the folder after the kill). The set is dropped, its
// temporaries and journal with it, and the files stay as they are.
TEST(AtomicFile, InterruptedSetOlderThanANewerWriteIsDropped) {
  for (const char* later : {"c.txt", "x.bin"}) {
    fs::path d = OldSetIn("superseded");
    ASSERT_TRUE(CommitKilledAfterFirstRename(d));
    fs::path journal;
    for (const auto& e : fs::directory_iterator(d))
      if (e.path().filename().string().rfind(".mvtm-journal-", 0) == 0) journal = e.path();
    ASSERT_FALSE(journal.empty());
    std::ofstream(d / later) << "later";
    fs::last_write_time(d / later, fs::last_write_time(journal) + std::chrono::seconds(2));
    FinishInterruptedWrites(d);
    EXPECT_EQ(Slurp(d / later), "later") << later;
    EXPECT_EQ(Slurp(d / "b.txt"), "old b.txt") << later;
    EXPECT_EQ(Entries(d), fs::path(later).extension() == ".bin" ? 4u : 3u) << later;
    fs::remove_all(d);
  }
}

// A journal of another host that is not an hour old is left to its writer (or to a finisher an
// hour on), and the sweep of stale temporaries keeps the temporaries it names, however old:
// they are that set's new files.
TEST(AtomicFile, SweepKeepsTheTemporariesOfAJournal) {
  fs::path d = TempDir("sweep-journal");
  const std::string owner = "999999999-7@node7~4026531836";
  std::ofstream(d / ".mvtm-journal-999999999-8@node7~4026531836")
      << "mvtm-journal 1\nrename\n.a.tmp-" << owner << ".txt\na.txt\n";
  std::ofstream(d / (".a.tmp-" + owner + ".txt")) << "new a";
  std::ofstream(d / ".b.tmp-999999999-9@node8~1.txt") << "stale";  // no journal: goes
  for (const char* n : {".b.tmp-999999999-9@node8~1.txt"})
    fs::last_write_time(d / n, fs::file_time_type::clock::now() - std::chrono::minutes(61));
  fs::last_write_time(d / (".a.tmp-" + owner + ".txt"),
                      fs::file_time_type::clock::now() - std::chrono::minutes(61));
  RemoveStaleTemporaries(d);
  EXPECT_TRUE(fs::exists(d / (".a.tmp-" + owner + ".txt")));
  EXPECT_FALSE(fs::exists(d / ".b.tmp-999999999-9@node8~1.txt"));
  EXPECT_FALSE(fs::exists(d / "a.txt"));
  fs::remove_all(d);
}

// A rename that fails half-way (b.txt is a folder here) leaves the journal and the temporaries
// not yet renamed: once the writer is gone (its journal renamed to a dead pid's below) and the
// obstacle too, the next reader finishes the set.
TEST(AtomicFile, FailedRenameKeepsTheJournalsTemporaries) {
  fs::path d = OldSetIn("failed");
  fs::remove(d / "b.txt");
  fs::create_directories(d / "b.txt" / "in");
  EXPECT_THROW(WriteTogetherAtomic(NewSet(d), false, {d / "x.bin"}), Error);
  EXPECT_EQ(Slurp(d / "a.txt"), "new a.txt");
  EXPECT_EQ(Slurp(d / "c.txt"), "old c.txt");
  fs::path journal;
  for (const auto& e : fs::directory_iterator(d))
    if (e.path().filename().string().rfind(".mvtm-journal-", 0) == 0) journal = e.path();
  ASSERT_FALSE(journal.empty());
  FinishInterruptedWrites(d);  // this process's: left alone
  EXPECT_EQ(Entries(d), 6u);   // a, b/, c, b's and c's temporaries, the journal
  fs::remove_all(d / "b.txt");
  fs::rename(journal, d / (".mvtm-journal-999999999-0@" + ProcessSpace()));
  FinishInterruptedWrites(d);
  for (const char* n : {"a.txt", "b.txt", "c.txt"})
    EXPECT_EQ(Slurp(d / n), std::string("new ") + n);
  EXPECT_EQ(Entries(d), 3u);
  fs::remove_all(d);
}

// A live writer's journal (this process's) is its own business; a damaged journal is an error
// naming it, not a guess.
TEST(AtomicFile, LiveOrDamagedJournalsAreNotRolledForward) {
  fs::path d = TempDir("journal");
  const std::string mine = ".mvtm-journal-" + std::to_string(getpid()) + "-0@" + ProcessSpace();
  std::ofstream(d / mine) << "mvtm-journal 1\nrename\n.a.tmp-1\na.txt\n";
  std::ofstream(d / ".a.tmp-1") << "x";
  FinishInterruptedWrites(d);
  EXPECT_TRUE(fs::exists(d / mine));
  EXPECT_FALSE(fs::exists(d / "a.txt"));
  const std::string dead = ".mvtm-journal-999999999-0@" + ProcessSpace();
  std::ofstream(d / dead) << "mvtm-journal 1\nrename\n.a.tmp-1\n";
  try {
    FinishInterruptedWrites(d);
    ADD_FAILURE() << "a truncated journal was followed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dead + ":4: truncated or damaged"), std::string::npos)
        << e.what();
  }
  // Never a name outside its folder, the folder itself, or a rename of what is no temporary.
  for (const char* bad : {"rename\n../a\nb\n", "remove\n..\n", "remove\n.\n",
                          "rename\n.a.tmp-1\n..\n", "rename\nimages.txt\nb\n"}) {
    std::ofstream(d / dead) << "mvtm-journal 1\n" << bad;
    EXPECT_THROW(FinishInterruptedWrites(d), Error) << bad;
  }
  EXPECT_FALSE(fs::exists(d / "a.txt"));
  fs::remove_all(d);
}

// After a reboot (a power loss) pids start again, so a journal's pid may now be a live process
// that never wrote it: a journal and a temporary of an earlier boot of this host and namespace
// (another boot id, written before this boot began) are a dead writer's, whatever holds the pid.
// Named here with this very process's pid, alive. Another boot id on an entry written since this
// boot began is another machine of the same host name sharing the folder: judged by age, kept.
TEST(AtomicFile, AnEarlierBootsJournalIsFinishedWhateverHoldsItsPidNow) {
  const std::string space = ProcessSpace();
  if (std::count(space.begin(), space.end(), '~') != 2) GTEST_SKIP() << "no boot id: " << space;
  std::string earlier = space;
  earlier.back() = earlier.back() == '0' ? '1' : '0';
  double uptime = 0;
  std::ifstream("/proc/uptime") >> uptime;
  ASSERT_GT(uptime, 0);
  const auto before_boot =
      fs::file_time_type::clock::now() - std::chrono::seconds(static_cast<long>(uptime) + 120);
  fs::path d = TempDir("reboot");
  const std::string pid = std::to_string(getpid());
  std::ofstream(d / "a.txt") << "old";
  const std::string tmp = ".a.tmp-" + pid + "-1@" + earlier + ".txt";
  const std::string journal = ".mvtm-journal-" + pid + "-0@" + earlier;
  std::ofstream(d / tmp) << "new";
  std::ofstream(d / journal) << "mvtm-journal 1\nrename\n" << tmp << "\na.txt\n";
  std::ofstream(d / (".b.tmp-" + pid + "-2@" + earlier + ".txt")) << "stale";
  fs::last_write_time(d / "a.txt", before_boot - std::chrono::minutes(5));
  for (const std::string& n : {tmp, journal, ".b.tmp-" + pid + "-2@" + earlier + ".txt"})
    fs::last_write_time(d / n, before_boot);
  RemoveStaleTemporaries(d);
  EXPECT_EQ(Slurp(d / "a.txt"), "new");
  EXPECT_EQ(Entries(d), 1u);
  // Written now under another boot id: another machine's live run. This boot's: this process's.
  std::ofstream(d / (".c.tmp-" + pid + "-3@" + earlier + ".txt")) << "theirs";
  std::ofstream(d / (".d.tmp-" + pid + "-4@" + space + ".txt")) << "mine";
  RemoveStaleTemporaries(d);
  EXPECT_EQ(Entries(d), 3u);
  fs::remove_all(d);
}

// A link within one file system; a copy across two (/dev/shm is a tmpfs where Linux has one; the
// copy case is skipped when it shares the temporary folder's file system); both fail for a
// missing source.
TEST(AtomicFile, LinkOrCopyLinksWithinAFileSystemAndCopiesAcrossOnes) {
  fs::path d = TempDir("link");
  std::ofstream(d / "a.ply") << "mesh";
  std::error_code ec;
  EXPECT_TRUE(LinkOrCopy(d / "a.ply", d / "b.ply", ec));
  EXPECT_FALSE(ec);
  EXPECT_TRUE(fs::equivalent(d / "a.ply", d / "b.ply"));
  EXPECT_EQ(fs::hard_link_count(d / "a.ply"), 2u);
  EXPECT_FALSE(LinkOrCopy(d / "missing.ply", d / "c.ply", ec));
  EXPECT_TRUE(ec);
  EXPECT_FALSE(fs::exists(d / "c.ply"));
  const fs::path shm = "/dev/shm";
  struct stat a {
  }, b{};
  if (stat(shm.c_str(), &a) == 0 && stat(d.c_str(), &b) == 0 && a.st_dev != b.st_dev) {
    const fs::path other = shm / ("mvtm-link-" + std::to_string(getpid()) + ".ply");
    ec.clear();
    EXPECT_FALSE(LinkOrCopy(d / "a.ply", other, ec));
    EXPECT_FALSE(ec) << ec.message();
    EXPECT_FALSE(fs::equivalent(d / "a.ply", other));
    std::ifstream in(other);
    std::string text;
    in >> text;
    EXPECT_EQ(text, "mesh");
    fs::remove(other);
  }
  fs::remove_all(d);
}

}  // namespace
}  // namespace mvtm
