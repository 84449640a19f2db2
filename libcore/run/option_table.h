// mvtm — one declared option table per tool.
//
// A tool declares each option once, bound to a field of its Options struct: its names, help,
// default (the field's value when the table is built), range or choices, and whether it changes
// the tool's outputs. From that one table come
//   - the command line and --help (cli/options.h puts a table into CLI11),
//   - the range and choice checks (Check(), throwing UsageError that names the flag),
//   - the provenance record (Json(): every option --help shows, keyed by its long name without
//     dashes, '-' as '_'),
//   - the staleness key of the outputs (OutputJson(): the options that change them; run/ledger.h),
//   - a machine-readable description (Describe()) that the option-walking test iterates over.
//
// Values are set from text with mvtm's own strict parsers (std::from_chars, classic locale), so
// "1,5" is an error in every locale. Choices are enums with a name table; --help lists the names.
// Defaults are the fields' values when the table is declared: declare on a default-constructed
// Options for the command line. Not thread-safe; a table holds pointers into the Options it was
// built on and must not outlive them.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace mvtm {

class OptionTable;

struct OptionSpec {
  std::string names;  // "--lateral", "-q,--quiet", or a positional's name ("WS")
  std::string flag;   // the long name ("--lateral") or the positional's name
  std::string key;    // provenance key: "lateral", "quiet", "ws"
  std::string help;
  std::string type;          // FLAG, INT, FLOAT, TEXT, FILE, DIR, or the choice list "a|b"
  std::string default_text;  // the value when declared ("" for an empty text)
  bool positional = false;
  bool required = false;
  bool changes_output = true;  // false: cosmetic (progress, threads, which items are selected)
  bool hidden = false;         // not in --help (nor in provenance)
  bool is_flag = false;
  bool is_list = false;  // a positional taking one or more values (set_list)
  bool has_range = false;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  std::vector<std::string> choices;   // allowed texts of a choice option
  std::vector<std::string> excludes;  // flags that may not be given together with this one
  std::vector<std::string> fields;    // library field names it sets besides its key
  std::string alternative;            // another valid value, for the option-walking test
  std::function<void(const std::string&)> set;  // parses and stores a value (flags: "1"/"0")
  std::function<void(const std::vector<std::string>&)> set_list;  // a list positional's values
  std::function<std::string()> text;                              // the current value as text
  std::function<nlohmann::json()> json;                           // the current value as JSON
  std::function<void()> check;  // extra check of the current value (may be empty)
};

// A fluent handle to one declared option.
class OptionRef {
 public:
  explicit OptionRef(OptionSpec& s) : s_(&s) {}
  // Allowed range [lo, hi]; lo_open/hi_open exclude the bound.
  OptionRef& Range(double lo, double hi, bool lo_open = false, bool hi_open = false);
  OptionRef& AtLeast(double lo) { return Range(lo, std::numeric_limits<double>::infinity()); }
  OptionRef& Above(double lo) { return Range(lo, std::numeric_limits<double>::infinity(), true); }
  // Does not change the outputs (progress, threads, selection): never makes an output stale.
  OptionRef& Cosmetic();
  // Names a file or folder: "FILE"/"DIR" in --help; the tool lists the file among its inputs
  // (its content, not its name, is what makes outputs stale), so the name itself is cosmetic.
  OptionRef& File();
  OptionRef& Dir();
  OptionRef& Required();
  OptionRef& Hidden();
  // Another valid value for the option-walking test (default: derived from kind and range).
  OptionRef& Alternative(std::string value);
  // A further check of the value; throws UsageError naming the flag.
  OptionRef& Check(std::function<void()> check);
  OptionRef& Excludes(const std::string& flag);
  // The library field this option sets, when its name differs from the option's key
  // (--neighbours sets NeighbourOptions::count): a FieldError("count", ...) names --neighbours.
  OptionRef& Field(const std::string& field);
  const OptionSpec& spec() const { return *s_; }

 private:
  OptionSpec* s_;
};

class OptionTable {
 public:
  explicit OptionTable(std::string tool) : tool_(std::move(tool)) {}
  OptionTable(const OptionTable&) = delete;
  OptionTable& operator=(const OptionTable&) = delete;
  OptionTable(OptionTable&&) = default;

  const std::string& tool() const { return tool_; }
  const std::deque<OptionSpec>& options() const { return options_; }

  // A required positional (a workspace, an output folder, a file).
  OptionRef Positional(const std::string& name, std::string* field, const std::string& help);
  // A required positional of one or more values ("PATHS...").
  OptionRef PositionalList(const std::string& name, std::vector<std::string>* field,
                           const std::string& help);
  // An optional positional.
  OptionRef OptionalPositional(const std::string& name, std::string* field,
                               const std::string& help);
  OptionRef Flag(const std::string& names, bool* field, const std::string& help);
  OptionRef Real(const std::string& names, double* field, const std::string& help);
  OptionRef Text(const std::string& names, std::string* field, const std::string& help);
  template <class T>
  OptionRef Integer(const std::string& names, T* field, const std::string& help) {
    static_assert(std::is_integral_v<T>, "Integer options bind integer fields");
    OptionSpec& s = Add(names, help, "INT");
    s.set = [field, flag = s.flag](const std::string& v) {
      *field =
          static_cast<T>(ParseIntegerOption(v, flag, std::numeric_limits<T>::min(),
                                            static_cast<double>(std::numeric_limits<T>::max())));
    };
    s.text = [field] { return std::to_string(*field); };
    s.json = [field] { return nlohmann::json(*field); };
    return Finish(s);
  }
  // A choice among an enum's values, named by `names` (value, text) in the order --help lists.
  template <class E>
  OptionRef Choice(const std::string& flag, E* field,
                   const std::vector<std::pair<E, std::string>>& names, const std::string& help) {
    OptionSpec& s = Add(flag, help, "");
    for (const auto& [e, n] : names) s.choices.push_back(n);
    s.set = [field, names, f = s.flag, list = s.choices](const std::string& v) {
      for (const auto& [e, n] : names)
        if (n == v) {
          *field = e;
          return;
        }
      ChoiceError(f, v, list);
    };
    s.text = [field, names] {
      for (const auto& [e, n] : names)
        if (e == *field) return n;
      return std::string();
    };
    s.json = [t = s.text] { return nlohmann::json(t()); };
    return Finish(s);
  }

  // Checks every option's current value (ranges, required, extra checks; exclusions are the
  // command line's, cross-option rules the tool's own Check()). Throws
  // UsageError("--flag: must be in [lo, hi]") for the first bad one.
  void Check() const;
  // Every option --help shows and its current value.
  nlohmann::json Json() const;
  // The options that change the outputs and their current values (the staleness key).
  nlohmann::json OutputJson() const;
  // The long flag of a provenance key ("lateral" → "--lateral"); the key itself when unknown.
  std::string FlagOf(const std::string& key) const;
  // The flag that sets a library field (FieldError::field(): a key, or a declared Field()); ""
  // when no option does.
  std::string FlagOfField(const std::string& field) const;
  // The table as JSON for tests: one object per option (names, key, type, default, range,
  // choices, changes_output, alternative).
  nlohmann::json Describe() const;
  // A positional or option by flag; nullptr when absent.
  const OptionSpec* Find(const std::string& flag) const;

 private:
  OptionSpec& Add(const std::string& names, const std::string& help, const std::string& type);
  OptionRef Finish(OptionSpec& s);
  [[noreturn]] static void ChoiceError(const std::string& flag, const std::string& v,
                                       const std::vector<std::string>& choices);
  static int64_t ParseIntegerOption(const std::string& v, const std::string& flag, double lo,
                                    double hi);

  std::string tool_;
  std::deque<OptionSpec> options_;  // a deque: OptionRef handles stay valid as options are added
};

// Checks an Options struct through its table: DeclareOptions(copy).Check() on a copy (the table
// binds non-const fields; found by argument-dependent lookup next to the Options type).
template <class Options>
void CheckDeclared(const Options& o) {
  Options copy = o;
  DeclareOptions(copy).Check();
}

}  // namespace mvtm
