// Outputs that know what made them: each case changes one thing a real rerun could change and
// checks the ledger's verdict against what was changed (the reason is the claim).
#include "run/ledger.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/plugin.h"

namespace mvtm {
namespace {

struct Opts {
  double lateral = 0;
  int threads = 1;
};

OptionTable Declare(Opts& o) {
  OptionTable t("demo");
  t.Real("--lateral", &o.lateral, "Lateral");
  t.Integer("--threads", &o.threads, "Threads").Cosmetic();
  return t;
}

void Put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

void SetTime(const fs::path& p, int64_t seconds) {
  fs::last_write_time(p, fs::file_time_type(std::chrono::seconds(seconds)));
}

class LedgerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ledger_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    Put(dir_ / "ws/mesh.ply", "mesh v1");
    Put(dir_ / "ws/images/a.png", "image a");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // One run: checks `outputs`, makes the stale ones, writes the record; returns the reasons.
  std::vector<std::string> Run(Opts o, const std::vector<std::string>& outputs,
                               const std::string& record = "demo",
                               const std::string& independent_of_lateral = "") {
    OptionTable t = Declare(o);
    Ledger ledger(dir_ / "out", record, t, {dir_ / "ws/mesh.ply"}, dir_ / "ws");
    if (!independent_of_lateral.empty())
      ledger.Independent(dir_ / "out" / independent_of_lateral, {"lateral"});
    std::vector<std::string> why;
    for (const std::string& name : outputs) {
      const fs::path out = dir_ / "out" / name;
      why.push_back(ledger.Stale(out, {dir_ / "ws/images/a.png"}));
      if (why.back().empty()) continue;
      Put(out, "frame " + name + " lateral " + std::to_string(o.lateral));
      ledger.Done(out, {dir_ / "ws/images/a.png"});
    }
    ledger.Write();
    summary_ = ledger.Summary();
    return why;
  }

  fs::path dir_;
  std::string summary_;
};

using V = std::vector<std::string>;

TEST_F(LedgerTest, NewThenUpToDate) {
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"new", "new"}));
  EXPECT_EQ(summary_, "");
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"", ""}));
}

TEST_F(LedgerTest, AnOptionThatChangesOutputRedoesAndIsNamed) {
  Run({}, {"f0.png", "f1.png"});
  EXPECT_EQ(Run({0.5, 1}, {"f0.png", "f1.png"}), (V{"--lateral changed", "--lateral changed"}));
  EXPECT_EQ(summary_, "2 redone: --lateral changed");
  EXPECT_EQ(Run({0.5, 1}, {"f0.png", "f1.png"}), (V{"", ""}));
}

TEST_F(LedgerTest, ACosmeticOptionRedoesNothing) {
  Run({}, {"f0.png"});
  EXPECT_EQ(Run({0, 8}, {"f0.png"}), (V{""}));
}

// dynmask's maps (dynamic/) and masks (masks/): the masks depend on an option the maps do not.
TEST_F(LedgerTest, AFolderIndependentOfAnOptionKeepsItsOutputsWhenOnlyThatOptionChanges) {
  const V both{"dynamic/f0.png", "masks/f0.png"};
  EXPECT_EQ(Run({}, both, "demo", "dynamic"), (V{"new", "new"}));
  EXPECT_EQ(Run({0.5, 1}, both, "demo", "dynamic"), (V{"", "--lateral changed"}));
  EXPECT_EQ(summary_, "1 redone: --lateral changed");
  EXPECT_EQ(Run({0.5, 1}, both, "demo", "dynamic"), (V{"", ""}));
  // The map's entry kept its own run (lateral 0), so going back redoes only the mask again.
  EXPECT_EQ(Run({}, both, "demo", "dynamic"), (V{"", "--lateral changed"}));
  // "dynamic" is a folder, not a prefix of names: dynamic2/ depends on every option.
  EXPECT_EQ(Run({}, {"dynamic2/f0.png"}, "demo", "dynamic"), (V{"new"}));
  EXPECT_EQ(Run({0.5, 1}, {"dynamic2/f0.png"}, "demo", "dynamic"), (V{"--lateral changed"}));
  // Without the declaration the map depends on it too.
  EXPECT_EQ(Run({0.5, 1}, both), (V{"--lateral changed", "--lateral changed"}));
}

TEST_F(LedgerTest, IndependentTakesAnOutputFolderOnlyAndBeforeAnyVerdict) {
  Opts o;
  OptionTable t = Declare(o);
  Ledger ledger(dir_ / "out", "demo", t, {}, dir_ / "ws");
  EXPECT_THROW(ledger.Independent(dir_ / "out", {"lateral"}), Error);
  EXPECT_THROW(ledger.Independent(dir_ / "out/.", {"lateral"}), Error);
  ledger.Independent(dir_ / "out/dynamic/", {"lateral"});  // a trailing separator is the folder
  Run({}, {"dynamic/f0.png"});
  Ledger again(dir_ / "out", "demo", t, {}, dir_ / "ws");
  again.Stale(dir_ / "out/dynamic/f0.png");
  EXPECT_THROW(again.Independent(dir_ / "out/dynamic", {"lateral"}), Error);
}

// What a run's options resolved to is kept in its own entry, which each of its outputs names.
TEST_F(LedgerTest, ARunsNoteStaysWithTheOutputsItMade) {
  const auto note_of = [&](const std::string& output) {
    const nlohmann::json j =
        nlohmann::json::parse(std::ifstream(dir_ / "out/provenance/demo.json"));
    return j["runs"][j["outputs"][output]["run"].get<std::string>()].value("size", -1);
  };
  Opts o;
  OptionTable t = Declare(o);
  {
    Ledger ledger(dir_ / "out", "demo", t, {}, dir_ / "ws");
    ledger.NoteRun("size", 621);
    for (const char* f : {"f0.png", "f1.png"}) {
      Put(dir_ / "out" / f, "map");
      ledger.Done(dir_ / "out" / f);
    }
    ledger.Write();
  }
  // Another run of the same options with another note (what they resolved to differs: the
  // cameras, say), one output remade.
  {
    Ledger ledger(dir_ / "out", "demo", t, {}, dir_ / "ws");
    ledger.NoteRun("size", 319);
    EXPECT_EQ(ledger.Stale(dir_ / "out/f1.png"), "");  // the note does not count in staleness
    Put(dir_ / "out/f0.png", "map 2");
    ledger.Done(dir_ / "out/f0.png");
    ledger.Write();
  }
  EXPECT_EQ(note_of("f0.png"), 319);
  EXPECT_EQ(note_of("f1.png"), 621);
}

TEST_F(LedgerTest, AnInputRewrittenRedoesATouchedOneDoesNot) {
  Run({}, {"f0.png"});
  SetTime(dir_ / "ws/mesh.ply", 2000000000);  // same bytes, another time: a copy, a touch
  EXPECT_EQ(Run({}, {"f0.png"}), (V{""}));
  Put(dir_ / "ws/mesh.ply", "mesh v2");  // same size, other bytes
  SetTime(dir_ / "ws/mesh.ply", 2000000100);
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"input changed: mesh.ply"}));
  Put(dir_ / "ws/images/a.png", "image A");
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"input changed: images/a.png"}));
}

TEST_F(LedgerTest, AnInputRewrittenInTheTickItWasRecordedIsCaughtByItsContent) {
  // mesh.ply was written just now (SetUp): its time cannot vouch for it ("racy").
  Run({}, {"f0.png"});
  const auto t = fs::last_write_time(dir_ / "ws/mesh.ply");
  Put(dir_ / "ws/mesh.ply", "mesh v9");  // same size, other bytes, and the time put back
  fs::last_write_time(dir_ / "ws/mesh.ply", t);
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"input changed: mesh.ply"}));
}

TEST_F(LedgerTest, AnOutputEditedOrMadeElsewhereHasNoRecord) {
  Run({}, {"f0.png"});
  Put(dir_ / "out/f0.png", "edited by hand");
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"no record"}));
  fs::remove_all(dir_ / "out/provenance");
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"no record"}));
}

// The record as another build of the tool (or an mvtm before builds were recorded) left it.
void SetRecordedBuild(const fs::path& record, const char* build) {
  nlohmann::json j = nlohmann::json::parse(std::ifstream(record));
  for (auto& [id, run] : j["runs"].items()) {
    if (build)
      run["build"] = build;
    else
      run.erase("build");
  }
  std::ofstream(record) << j.dump(1);
}

TEST_F(LedgerTest, OutputsOfAnotherBuildOfTheToolAreRedone) {
  ASSERT_EQ(ProgramChecksum().size(), 16u);  // /proc/self/exe read: not "version ..."
  Run({}, {"f0.png", "f1.png"});
  const fs::path record = dir_ / "out/provenance/demo.json";
  SetRecordedBuild(record, "0123456789abcdef");
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"another build of demo", "another build of demo"}));
  EXPECT_EQ(summary_, "2 redone: another build of demo");
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"", ""}));
  SetRecordedBuild(record, nullptr);
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"another build of demo"}));
}

TEST_F(LedgerTest, AnyStaleAsksAboutEveryOutput) {
  Run({}, {"f0.png", "f1.png", "f2.png"});
  Put(dir_ / "out/f0.png", "edited by hand");
  Put(dir_ / "out/f2.png", "edited too");
  Opts o;
  const OptionTable t = Declare(o);
  Ledger ledger(dir_ / "out", "demo", t, {dir_ / "ws/mesh.ply"}, dir_ / "ws");
  const fs::path a = dir_ / "ws/images/a.png";
  EXPECT_FALSE(ledger.AnyStale({dir_ / "out/f1.png"}, {a}));
  EXPECT_TRUE(
      ledger.AnyStale({dir_ / "out/f0.png", dir_ / "out/f1.png", dir_ / "out/f2.png"}, {a}));
  EXPECT_EQ(ledger.Summary(), "2 redone: no record");  // the third was asked about too
}

TEST_F(LedgerTest, APartialRunKeepsTheOtherOutputsHistory) {
  Run({}, {"f0.png", "f1.png", "f2.png"});
  EXPECT_EQ(Run({0.5, 1}, {"f0.png"}), (V{"--lateral changed"}));  // like --frames 0:1
  // f1, f2 were made at lateral 0 and say so; f0 at 0.5.
  EXPECT_EQ(Run({}, {"f0.png", "f1.png", "f2.png"}), (V{"--lateral changed", "", ""}));
}

TEST_F(LedgerTest, ShardsKeepTheirOwnRecordsAndTheFileDecidesWhichMadeIt) {
  Run({}, {"f0.png", "f1.png"});
  Run({0.5, 1}, {"f1.png"}, "demo-shard-1");  // a shard rewrote f1 with other options
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"", "--lateral changed"}));
  EXPECT_EQ(Run({}, {"f0.png", "f1.png"}), (V{"", ""}));
}

TEST_F(LedgerTest, ARecordOfAnotherFormatVouchesForNothing) {
  Run({}, {"f0.png"});
  Put(dir_ / "out/provenance/demo.json", "{\"tool\": \"demo\", \"options\": {}}");
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"no record"}));
  Put(dir_ / "out/provenance/demo.json", "not json");
  EXPECT_EQ(Run({}, {"f0.png"}), (V{"no record"}));
}

TEST_F(LedgerTest, TheRecordIsTheProvenance) {
  Run({0.25, 3}, {"f0.png"});
  std::ifstream in(dir_ / "out/provenance/demo.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["tool"], "demo");
  EXPECT_EQ(j["options"]["lateral"], 0.25);
  EXPECT_EQ(j["options"]["threads"], 3);
  ASSERT_EQ(j["inputs"].size(), 1u);
  EXPECT_EQ(j["inputs"][0]["path"], "mesh.ply");
  EXPECT_EQ(j["inputs"][0]["bytes"], 7);
  EXPECT_EQ(j["outputs"]["f0.png"]["in"].begin().key(), "images/a.png");
}

// The outputs are written from their kept text, after the other members: names that JSON must
// escape, and a record without outputs, read back as JSON.
TEST_F(LedgerTest, TheRecordStaysJsonWithEscapedNamesAndNoOutputs) {
  const std::string odd = "a \"b\"\\c\t\xc3\xa9.png";
  EXPECT_EQ(Run({0, 1}, {odd, "g.png"}), (V{"new", "new"}));
  EXPECT_EQ(Run({0, 1}, {odd, "g.png"}), (V{"", ""}));
  std::ifstream in(dir_ / "out/provenance/demo.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["outputs"].size(), 2u);
  EXPECT_TRUE(j["outputs"].contains(odd));
  EXPECT_EQ(j["runs"].size(), 1u);
  Opts o;
  OptionTable t = Declare(o);
  Ledger(dir_ / "empty", "demo", t, {}, dir_ / "ws").Write();
  std::ifstream in2(dir_ / "empty/provenance/demo.json");
  const nlohmann::json e = nlohmann::json::parse(in2);
  EXPECT_TRUE(e["outputs"].is_object() && e["outputs"].empty());
}

TEST_F(LedgerTest, AKilledRunsTemporariesGoEvenWhenAllIsUpToDate) {
  Run({}, {"f0.png", "sub/f1.png"});
  // What kill -9 leaves: a half-written record and half-written outputs (pid 999999999: dead).
  const fs::path record_tmp = dir_ / "out/provenance/.demo.tmp-999999999-0.json";
  const fs::path out_tmp = dir_ / "out/.f0.tmp-999999999-1.png";
  const fs::path sub_tmp = dir_ / "out/sub/.f1.tmp-999999999-2.png";
  const fs::path live_tmp = dir_ / ("out/.f2.tmp-" + std::to_string(::getpid()) + "-3.png");
  for (const fs::path& p : {record_tmp, out_tmp, sub_tmp, live_tmp}) Put(p, "half");
  EXPECT_EQ(Run({}, {"f0.png", "sub/f1.png"}), (V{"", ""}));
  EXPECT_FALSE(fs::exists(record_tmp));
  EXPECT_FALSE(fs::exists(out_tmp));
  EXPECT_FALSE(fs::exists(sub_tmp));
  EXPECT_TRUE(fs::exists(live_tmp));  // a running writer's is never touched
}

}  // namespace
}  // namespace mvtm
