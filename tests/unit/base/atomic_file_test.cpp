// Atomic outputs: nothing appears under the final name until Commit; stale temporaries go away.
#include "base/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "base/error.h"

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
  RemoveStaleTemporaries(d);
  EXPECT_FALSE(fs::exists(d / ".a.tmp-999999999-0.png"));
  EXPECT_TRUE(fs::exists(d / (".b.tmp-" + std::to_string(getpid()) + "-0.png")));
  fs::remove_all(d);
}

}  // namespace
}  // namespace mvtm
