#include "run/ledger.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/plugin.h"
#include "base/version.h"

namespace mvtm {

struct Ledger::Record {
  std::string file;  // record file name ("ptmrender.json")
  nlohmann::json runs;
  std::map<std::string, Entry> outputs;  // by rel path
};

namespace {

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// True when `name` is TOOL.json or TOOL-shard-N.json.
bool IsRecordOf(const std::string& name, const std::string& tool) {
  if (name == tool + ".json") return true;
  const std::string pre = tool + "-shard-";
  if (name.size() <= pre.size() + 5 || name.compare(0, pre.size(), pre) != 0) return false;
  if (name.compare(name.size() - 5, 5, ".json") != 0) return false;
  const std::string n = name.substr(pre.size(), name.size() - pre.size() - 5);
  return std::all_of(n.begin(), n.end(), [](char c) { return c >= '0' && c <= '9'; });
}

nlohmann::json ReadJsonOrNull(const fs::path& p) {
  std::ifstream in(p);
  if (!in) return nullptr;
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() || !j.is_object() ? nlohmann::json(nullptr) : j;
}

}  // namespace

Ledger::Ledger(fs::path root, std::string record, const OptionTable& table,
               std::vector<fs::path> inputs, fs::path base)
    : root_(std::move(root)),
      base_(std::move(base)),
      record_(std::move(record)),
      tool_(table.tool()),
      table_(table),
      options_key_(table.OutputJson()),
      build_(ProgramChecksum()),
      kept_runs_(nlohmann::json::object()) {
  std::sort(inputs.begin(), inputs.end());
  inputs.erase(std::unique(inputs.begin(), inputs.end()), inputs.end());
  for (const fs::path& p : inputs) {
    const std::string name = Name(p, base_);
    if (Current(name, p, false).exists) inputs_.emplace_back(name, p);
  }
  std::error_code ec;
  const fs::path dir = root_ / "provenance";
  if (!fs::is_directory(dir, ec)) return;
  RemoveStaleTemporaries(dir);  // a killed run's half-written record
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (IsRecordOf(e.path().filename().string(), tool_)) files.push_back(e.path().filename());
  std::sort(files.begin(), files.end());
  for (const std::string& f : files) {
    nlohmann::json j = ReadJsonOrNull(dir / f);
    if (j.is_null() || !j.contains("outputs") || !j["outputs"].is_object() || !j.contains("runs") ||
        !j["runs"].is_object())
      continue;  // a record of an older mvtm, or damaged: it vouches for nothing
    Record r{f, std::move(j["runs"]), {}};
    for (auto& [rel, e] : j["outputs"].items())
      if (e.is_object()) {
        const nlohmann::json* run = e.contains("run") ? &e["run"] : nullptr;
        r.outputs[rel] = {run && run->is_string() ? run->get<std::string>() : "", e.dump()};
        e = nullptr;  // freed as it is taken
      }
    records_.push_back(std::move(r));
  }
}

Ledger::~Ledger() = default;

std::string Ledger::Name(const fs::path& p, const fs::path& base) const {
  if (!base.empty()) {
    const fs::path rel = p.lexically_proximate(base);
    const std::string r = rel.generic_string();
    if (!rel.empty() && r.compare(0, 2, "..") != 0 && !rel.is_absolute()) return r;
  }
  return p.generic_string();
}

const FileStamp& Ledger::Current(const std::string& name, const fs::path& path, bool checksum) {
  auto it = stamps_.find(name);
  if (it == stamps_.end()) it = stamps_.emplace(name, StatFile(path)).first;
  if (checksum && it->second.exists && it->second.fnv1a64.empty())
    it->second.fnv1a64 = FileChecksum(path);
  return it->second;
}

bool Ledger::Unchanged(const std::string& name, const fs::path& path, const nlohmann::json& stamp) {
  if (!stamp.is_object()) return false;
  const FileStamp& s = Current(name, path, false);
  if (!s.exists || s.bytes != stamp.value("bytes", uint64_t(0))) return false;
  // A time recorded within a clock tick of the file's last write cannot vouch for it (a second
  // write in the same tick keeps the time: git's "racy clean" case); its checksum decides.
  if (s.mtime_ns == stamp.value("mtime_ns", int64_t(0)) && !stamp.value("racy", false)) return true;
  return Current(name, path, true).fnv1a64 == stamp.value("fnv1a64", std::string());
}

// Identifies this run by what makes its outputs (options and the inputs' content), so identical
// runs anywhere share it. Computed on first need: a run with everything up to date reads no input.
const std::string& Ledger::RunId() {
  if (run_id_.empty()) {
    std::string id = options_key_.dump() + "\nbuild " + build_;
    if (!run_notes_.empty()) id += "\nnotes " + run_notes_.dump();
    for (const auto& [name, path] : inputs_)
      id += "\n" + name + " " + Current(name, path, true).fnv1a64;
    run_id_ = Hex64(Fnv1a64(id.data(), id.size()));
  }
  return run_id_;
}

nlohmann::json Ledger::StampJson(const std::string& name, const fs::path& path) {
  const FileStamp& s = Current(name, path, true);
  nlohmann::json j = {{"bytes", s.bytes}, {"mtime_ns", s.mtime_ns}, {"fnv1a64", s.fnv1a64}};
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  if (now - s.mtime_ns < 2'000'000'000LL) j["racy"] = true;  // written within 2 s of stamping
  return j;
}

void Ledger::Independent(const fs::path& folder, std::set<std::string> keys) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  std::string rel = Name(folder.lexically_normal(), root_);
  while (!rel.empty() && rel.back() == '/') rel.pop_back();
  // A folder that names no output folder (the root, or nothing) would set options aside for
  // outputs that depend on them.
  if (rel.empty() || rel == "." || !run_verdicts_.empty())
    throw Error("Ledger::Independent: " + folder.string() +
                ": give an output folder, before any output is judged");
  independent_[rel + "/"] = std::move(keys);
}

// The innermost folder declared Independent() that holds the output `rel`, with the options its
// outputs do not depend on; nullptr when none does.
const Ledger::IndependentFolder* Ledger::FolderOf(const std::string& rel) const {
  const IndependentFolder* found = nullptr;
  for (const IndependentFolder& f : independent_)
    if ((!found || f.first.size() > found->first.size()) &&
        rel.compare(0, f.first.size(), f.first) == 0)
      found = &f;
  return found;
}

// "" when a recorded run had this run's options (but `ignored`) and inputs; else what differs.
std::string Ledger::CompareRun(const nlohmann::json& run, const std::set<std::string>& ignored) {
  if (!run.is_object() || !run.contains("options") || !run.contains("inputs")) return "no record";
  const nlohmann::json& opts = run["options"];
  std::string changed;
  std::set<std::string> keys;
  for (const auto& [k, v] : options_key_.items()) keys.insert(k);
  if (opts.is_object())
    for (const auto& [k, v] : opts.items()) keys.insert(k);
  for (const std::string& k : keys) {
    if (ignored.count(k)) continue;
    const bool same = opts.is_object() && opts.contains(k) && options_key_.contains(k) &&
                      opts[k] == options_key_[k];
    if (!same) changed += (changed.empty() ? "" : ", ") + table_.FlagOf(k);
  }
  if (!changed.empty()) return changed + " changed";
  const auto build = run.find("build");
  if (build == run.end() || !build->is_string() || build->get<std::string>() != build_)
    return "another build of " + tool_;
  const nlohmann::json& ins = run["inputs"];
  if (!ins.is_object()) return "no record";
  for (const auto& [name, path] : inputs_)
    if (!ins.contains(name) || !Unchanged(name, path, ins[name])) return "input changed: " + name;
  for (const auto& [name, stamp] : ins.items()) {
    const bool listed = std::any_of(inputs_.begin(), inputs_.end(),
                                    [&n = name](const auto& in) { return in.first == n; });
    if (!listed) return "input changed: " + name;
  }
  return "";
}

std::string Ledger::Stale(const fs::path& output, const std::vector<fs::path>& item_inputs,
                          bool force) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  // A killed run's leftovers beside this output go, once per folder, even when all is up to date.
  const fs::path folder = output.has_parent_path() ? output.parent_path() : fs::path(".");
  if (swept_.insert(folder).second) RemoveStaleTemporaries(folder);
  const FileStamp now = StatFile(output);
  const std::string why = force ? "--force"
                          : !now.exists
                              ? "new"
                              : StaleExisting(Name(output, root_), output, now, item_inputs);
  if (!why.empty()) ++reasons_[why];
  return why;
}

bool Ledger::AnyStale(const std::vector<fs::path>& outputs,
                      const std::vector<fs::path>& item_inputs, bool force) {
  bool stale = false;
  for (const fs::path& p : outputs) stale = !Stale(p, item_inputs, force).empty() || stale;
  return stale;
}

std::string Ledger::StaleExisting(const std::string& rel, const fs::path& output,
                                  const FileStamp& now, const std::vector<fs::path>& item_inputs) {
  // The record whose entry matches the file as it is made it.
  nlohmann::json entry;
  const Record* maker = nullptr;
  std::string sum;
  for (const Record& r : records_) {
    auto it = r.outputs.find(rel);
    if (it == r.outputs.end()) continue;
    nlohmann::json e = nlohmann::json::parse(it->second.text, nullptr, false);
    if (!e.is_object() || e.value("bytes", uint64_t(0)) != now.bytes) continue;
    bool match = e.value("mtime_ns", int64_t(0)) == now.mtime_ns;
    if (!match) {
      if (sum.empty()) sum = FileChecksum(output);
      match = e.value("fnv1a64", std::string()) == sum;
    }
    if (match) entry = std::move(e), maker = &r;
  }
  if (!maker) return "no record";
  const std::string run = entry.value("run", std::string());
  // A run's verdict differs between folders that ignore different options.
  static const std::set<std::string> every_option_counts;
  const IndependentFolder* folder = FolderOf(rel);
  const std::set<std::string>& ignored = folder ? folder->second : every_option_counts;
  const std::string verdict_key = folder ? folder->first + "\n" + run : run;  // ids hold no \n
  auto v = run_verdicts_.find(verdict_key);
  if (v == run_verdicts_.end()) {
    auto rit = maker->runs.find(run);
    const nlohmann::json no_run;
    v = run_verdicts_
            .emplace(verdict_key, CompareRun(rit == maker->runs.end() ? no_run : *rit, ignored))
            .first;
  }
  if (!v->second.empty()) return v->second;
  const nlohmann::json in = entry.contains("in") ? entry["in"] : nlohmann::json::object();
  if (!in.is_object()) return "no record";
  std::set<std::string> names;
  for (const fs::path& p : item_inputs) {
    const std::string n = Name(p, base_);
    if (!in.contains(n) && !Current(n, p, false).exists) continue;  // absent then and now
    names.insert(n);
    if (!in.contains(n) || !Unchanged(n, p, in[n])) return "input changed: " + n;
  }
  for (const auto& [n, s] : in.items())
    if (!names.count(n)) return "input changed: " + n;
  // Up to date: it stays in this run's record, with its own run.
  entry["mtime_ns"] = now.mtime_ns;
  kept_[rel] = {run, entry.dump()};
  kept_runs_[run] = maker->runs.at(run);
  return "";
}

void Ledger::NoteRun(const std::string& key, nlohmann::json value) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  if (!run_id_.empty()) throw Error("Ledger::NoteRun: " + key + ": noted after an output was done");
  run_notes_[key] = std::move(value);
}

void Ledger::Done(const fs::path& output, const std::vector<fs::path>& item_inputs) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  const FileStamp s = StatFile(output);
  if (!s.exists) throw Error(output.string(), 0, "output missing after it was written");
  nlohmann::json in = nlohmann::json::object();
  for (const fs::path& p : item_inputs) {
    const std::string n = Name(p, base_);
    if (Current(n, p, false).exists) in[n] = StampJson(n, p);
  }
  const nlohmann::json e = {{"run", RunId()},
                            {"bytes", s.bytes},
                            {"mtime_ns", s.mtime_ns},
                            {"fnv1a64", FileChecksum(output)},
                            {"in", std::move(in)}};
  kept_[Name(output, root_)] = {RunId(), e.dump()};
  MaybeFlush();
}

void Ledger::MaybeFlush() {
  const int64_t now = NowNs();
  if (last_flush_ns_ == 0) last_flush_ns_ = now;
  if (now - last_flush_ns_ < 10'000'000'000LL) return;
  Write();
  last_flush_ns_ = now;
}

void Ledger::Write(const nlohmann::json& extra) {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  nlohmann::json run = {
      {"options", options_key_}, {"build", build_}, {"inputs", nlohmann::json::object()}};
  for (const auto& [k, v] : run_notes_.items()) run[k] = v;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [name, path] : inputs_) {
    run["inputs"][name] = StampJson(name, path);
    list.push_back(
        {{"path", name}, {"bytes", stamps_[name].bytes}, {"fnv1a64", stamps_[name].fnv1a64}});
  }
  // This record's earlier entries are carried forward; this run's checks and outputs override.
  std::map<std::string, const Entry*> outputs;
  nlohmann::json runs = nlohmann::json::object();
  for (const Record& r : records_)
    if (r.file == record_ + ".json") {
      for (const auto& [k, v] : r.outputs) outputs[k] = &v;
      runs = r.runs;
    }
  for (const auto& [k, v] : kept_) outputs[k] = &v;
  for (const auto& [k, v] : kept_runs_.items()) runs[k] = v;
  runs[RunId()] = run;
  std::set<std::string> used;
  for (const auto& [k, v] : outputs) used.insert(v->run);
  nlohmann::json pruned = nlohmann::json::object();
  for (const auto& [k, v] : runs.items())
    if (used.count(k)) pruned[k] = v;

  nlohmann::json j;
  j["tool"] = tool_;
  j["version"] = kVersion;
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  j["time"] = stamp;
  j["options"] = table_.Json();
  j["inputs"] = list;
  for (const auto& [k, v] : extra.items()) j[k] = v;
  j["runs"] = std::move(pruned);
  // The outputs are streamed from their kept text, one line each, after the other members: a
  // record of thousands of outputs is the largest thing a long render holds.
  std::string head = j.dump(1);
  head.resize(head.rfind('}'));  // the closing brace goes after the outputs
  head.resize(head.find_last_not_of(" \n") + 1);
  WriteTextAtomic(root_ / "provenance" / (record_ + ".json"), [&](std::ostream& o) {
    o << head << ",\n \"outputs\": {";
    bool first = true;
    for (const auto& [k, v] : outputs) {
      o << (first ? "\n  " : ",\n  ") << nlohmann::json(k).dump() << ": " << v->text;
      first = false;
    }
    o << "\n }\n}\n";
  });
}

std::string Ledger::Summary() const {
  std::lock_guard<std::recursive_mutex> lock(mutex_);
  size_t redone = 0;
  std::string why;
  for (const auto& [r, n] : reasons_) {
    if (r == "new") continue;
    redone += n;
    why += (why.empty() ? "" : "; ") + r;
  }
  return redone ? std::to_string(redone) + " redone: " + why : "";
}

}  // namespace mvtm
