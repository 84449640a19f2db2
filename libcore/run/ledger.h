// mvtm — outputs that know what made them.
//
// An output is up to date only when it exists, the inputs it was made from are unchanged, the
// options that change it (OptionTable::OutputJson) are those it was written with and the tool is
// the same build (ProgramChecksum: an upgraded or rebuilt tool redoes what the old one made). A
// Ledger keeps that record for one output root (a tool's output folder, or the workspace for
// outputs inside it) in ROOT/provenance/RECORD.json, RECORD being the tool's name ("ptmrender") or,
// for a shard of a job array, "TOOL-shard-I", so shards never overwrite each other's record. The
// file is the tool's provenance too: tool, version, time, every option --help shows, the inputs
// with their checksums — and, per output, the stamp it was written with and which run made it:
//
//   { "tool", "version", "time", "options": {...all...}, "inputs": [{path, bytes, fnv1a64}],
//     "runs": { "ID": { "options": {...changing output...}, "build", "inputs": { PATH: STAMP },
//                       NoteRun's keys } },
//     "outputs": { "REL/PATH": { "run": "ID", "bytes", "mtime_ns", "fnv1a64", "in": {PATH: STAMP}}
//     } }
//
// Staleness. Every record of the tool in ROOT/provenance is read; the one whose entry matches the
// output file as it is now (size and modification time, else size and content checksum) made it.
// None matches: the output was made by another run or edited since ("no record"). Its run's
// options are compared with this run's (the flags that differ are named: "--lateral changed"),
// then the build of the tool ("another build of TOOL"), then its inputs: an input is unchanged when
// its size and modification time are, else when its content checksum is (so `touch` or a copy redo
// nothing, a rewrite with new content does). The outputs of a folder declared Independent() of
// some options ignore those (dynmask's maps and its tracking options). Measured choice: stat first,
// checksum only on a changed time — the up-to-date check of 10,000 outputs with unchanged inputs
// costs one stat each (bench_ledger).
//
// Robustness. The record is written atomically (temporary + rename) at the end of the run and
// every 10 s during it, so kill -9 loses at most the last seconds' entries (those outputs are
// redone). Entries of outputs this run did not touch are carried forward from the record of the
// same name with their own run's options, so `--frames 0:2` after a full run keeps the others'
// history. Concurrent runs writing one record: the last rename wins and outputs the others wrote
// later no longer match it, so they are redone next time — never handed back wrongly. A killed
// run's temporaries are swept from ROOT/provenance and from each output's folder the first time
// Stale() sees it (RemoveStaleTemporaries: only those of dead processes).
//
// Thread safety: Stale() and Done() may be called from several threads.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "base/file_stamp.h"
#include "run/option_table.h"

namespace mvtm {

namespace fs = std::filesystem;

class Ledger {
 public:
  // root:   the folder whose outputs this ledger records (outputs are named relative to it)
  // record: "TOOL" or "TOOL-shard-I" (WorkOptions::ProvenanceName)
  // table:  the tool's options (OutputJson is the key; Json goes into the provenance)
  // inputs: the files every output depends on; missing ones are left out
  // base:   inputs are named relative to it when inside it (the workspace), else as given
  Ledger(fs::path root, std::string record, const OptionTable& table, std::vector<fs::path> inputs,
         fs::path base);
  ~Ledger();
  Ledger(const Ledger&) = delete;
  Ledger& operator=(const Ledger&) = delete;

  // Why `output` must be (re)made, or "" when it is up to date. `item_inputs` are the files this
  // output alone depends on (a projector's image, a mask). Reasons: "new", "--force",
  // "--lateral changed", "another build of ptmrender", "input changed: mesh.ply",
  // "no record" (made by another run, or edited).
  std::string Stale(const fs::path& output, const std::vector<fs::path>& item_inputs = {},
                    bool force = false);
  // True when any of `outputs` must be (re)made, all from the same `item_inputs`: a tool whose
  // outputs are made together (a model's three files, masks coupled by tracking). Asks about
  // every output, so each one's reason counts in Summary().
  bool AnyStale(const std::vector<fs::path>& outputs, const std::vector<fs::path>& item_inputs = {},
                bool force = false);
  // The outputs inside `folder` do not depend on the options of `keys` (provenance keys): a
  // change of them alone leaves those outputs up to date (dynmask's probability maps and its
  // tracking options, which only its masks depend on). `folder` is an output folder under the
  // root (else Error); call it before Stale().
  void Independent(const fs::path& folder, std::set<std::string> keys);
  // Adds `key` to this run's entry in the record, beside its options: what they resolved to
  // (densify's map sizes from --scale 0). Each output's run says it for that output; it does not
  // count in staleness. Call it before Done().
  void NoteRun(const std::string& key, nlohmann::json value);
  // Records that `output` (now complete on disk) was made by this run from `item_inputs`.
  void Done(const fs::path& output, const std::vector<fs::path>& item_inputs = {});
  // Writes the record now (atomically). `extra` is merged into the top level (e.g. a plan).
  void Write(const nlohmann::json& extra = nlohmann::json::object());

  // "6 redone: --lateral changed" for the existing outputs Stale() sent to be remade (empty when
  // none was: new outputs need no reason).
  std::string Summary() const;
  // The reasons and their counts.
  const std::map<std::string, size_t>& reasons() const { return reasons_; }

 private:
  struct Record;
  // One output's entry, kept as its compact JSON text: a long render holds thousands, and a
  // parsed entry costs about 7 times its text in memory (issue 22's flat-memory target).
  struct Entry {
    std::string run;   // the run that made it
    std::string text;  // {"run", "bytes", "mtime_ns", "fnv1a64", "in"} as JSON
  };
  std::string Name(const fs::path& p, const fs::path& base) const;
  std::string StaleExisting(const std::string& rel, const fs::path& output, const FileStamp& now,
                            const std::vector<fs::path>& item_inputs);
  std::string CompareRun(const nlohmann::json& run, const std::set<std::string>& ignored);
  using IndependentFolder = std::pair<const std::string, std::set<std::string>>;
  const IndependentFolder* FolderOf(const std::string& rel) const;
  bool Unchanged(const std::string& name, const fs::path& path, const nlohmann::json& stamp);
  const FileStamp& Current(const std::string& name, const fs::path& path, bool checksum);
  nlohmann::json StampJson(const std::string& name, const fs::path& path);
  void MaybeFlush();
  const std::string& RunId();

  fs::path root_, base_;
  std::string record_, tool_;
  const OptionTable& table_;
  nlohmann::json options_key_;
  std::string build_;  // ProgramChecksum() (base/plugin.h): another build's outputs are redone
  std::vector<std::pair<std::string, fs::path>> inputs_;
  std::vector<Record> records_;                      // this tool's records in ROOT/provenance
  std::map<std::string, std::string> run_verdicts_;  // "FOLDER\nRUN ID" → "" or a reason
  std::map<std::string, std::set<std::string>> independent_;  // rel folder + "/" → keys
  std::map<std::string, FileStamp> stamps_;                   // this run's view of files, by name
  std::map<std::string, Entry> kept_;  // entries carried into this run's record, by rel path
  nlohmann::json kept_runs_;           // the runs those entries refer to
  nlohmann::json run_notes_ = nlohmann::json::object();  // NoteRun: into this run's entry
  std::string run_id_;
  std::map<std::string, size_t> reasons_;
  std::set<fs::path> swept_;  // output folders whose stale temporaries are gone
  mutable std::recursive_mutex mutex_;
  int64_t last_flush_ns_ = 0;
};

}  // namespace mvtm
