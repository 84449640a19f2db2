#include "run/option_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

namespace {

// "-q,--quiet" → "--quiet"; "WS" → "WS".
std::string LongName(const std::string& names) {
  const auto p = names.rfind("--");
  return p == std::string::npos ? names : names.substr(p);
}

// "--min-baseline" → "min_baseline"; "WS" → "ws".
std::string KeyOf(const std::string& flag) {
  std::string k;
  for (char c : flag) {
    if (c == '-' && k.empty()) continue;
    k += c == '-' ? '_' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return k;
}

// "in [0, 1)", or "> 0" / ">= 0" for a range without an upper bound.
std::string RangeText(const OptionSpec& s) {
  char buf[96];
  if (std::isinf(s.hi))
    std::snprintf(buf, sizeof buf, "%s %.15g", s.lo_open ? ">" : ">=", s.lo);
  else
    std::snprintf(buf, sizeof buf, "in %s%.15g, %.15g%s", s.lo_open ? "(" : "[", s.lo, s.hi,
                  s.hi_open ? ")" : "]");
  return buf;
}

// A value inside the range, other than the default, for the option-walking test.
std::string DerivedAlternative(const OptionSpec& s) {
  if (s.is_flag) return s.default_text == "1" ? "0" : "1";
  if (!s.choices.empty()) {
    for (const auto& c : s.choices)
      if (c != s.default_text) return c;
    return "";
  }
  if (s.type != "INT" && s.type != "FLOAT") return "";
  double d = 0;
  try {
    d = ParseDoubleArg(s.default_text, s.flag);
  } catch (const UsageError&) {
    return "";
  }
  // Nudge the default by a quarter (or by one unit for integers and zero), kept in range.
  double step = s.type == "INT" ? std::max(1.0, std::round(std::fabs(d) * 0.25))
                                : (d == 0 ? 0.5 : std::fabs(d) * 0.25);
  for (double v : {d + step, d - step}) {
    bool ok = v <= s.hi && v >= s.lo && !(s.lo_open && v == s.lo) && !(s.hi_open && v == s.hi);
    if (ok) return s.type == "INT" ? std::to_string(static_cast<int64_t>(v)) : FormatShort(v);
  }
  return "";
}

}  // namespace

OptionRef& OptionRef::Range(double lo, double hi, bool lo_open, bool hi_open) {
  s_->has_range = true;
  s_->lo = lo;
  s_->hi = hi;
  s_->lo_open = lo_open;
  s_->hi_open = hi_open;
  return *this;
}

OptionRef& OptionRef::Cosmetic() {
  s_->changes_output = false;
  return *this;
}

OptionRef& OptionRef::File() {
  s_->type = "FILE";
  s_->changes_output = false;
  return *this;
}

OptionRef& OptionRef::Dir() {
  s_->type = "DIR";
  s_->changes_output = false;
  return *this;
}

OptionRef& OptionRef::Required() {
  s_->required = true;
  return *this;
}

OptionRef& OptionRef::Hidden() {
  s_->hidden = true;
  s_->changes_output = false;
  return *this;
}

OptionRef& OptionRef::Alternative(std::string value) {
  s_->alternative = std::move(value);
  return *this;
}

OptionRef& OptionRef::Check(std::function<void()> check) {
  s_->check = std::move(check);
  return *this;
}

OptionRef& OptionRef::Field(const std::string& field) {
  s_->fields.push_back(field);
  return *this;
}

OptionRef& OptionRef::Excludes(const std::string& flag) {
  s_->excludes.push_back(flag);
  return *this;
}

OptionSpec& OptionTable::Add(const std::string& names, const std::string& help,
                             const std::string& type) {
  OptionSpec& s = options_.emplace_back();
  s.names = names;
  s.flag = LongName(names);
  s.key = KeyOf(s.flag);
  s.help = help;
  s.type = type;
  return s;
}

OptionRef OptionTable::Finish(OptionSpec& s) {
  s.default_text = s.text();
  if (!s.choices.empty()) {
    s.type.clear();
    for (const auto& c : s.choices) s.type += (s.type.empty() ? "" : "|") + c;
  }
  return OptionRef(s);
}

void OptionTable::ChoiceError(const std::string& flag, const std::string& v,
                              const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  throw UsageError(flag + ": '" + v + "' is not one of " + list);
}

int64_t OptionTable::ParseIntegerOption(const std::string& v, const std::string& flag, double lo,
                                        double hi) {
  const int64_t n = ParseIntArg(v, flag);
  if (static_cast<double>(n) < lo || static_cast<double>(n) > hi)
    throw UsageError(flag + ": '" + v + "' is out of range");
  return n;
}

OptionRef OptionTable::Positional(const std::string& name, std::string* field,
                                  const std::string& help) {
  OptionRef r = OptionalPositional(name, field, help);
  return r.Required();
}

OptionRef OptionTable::PositionalList(const std::string& name, std::vector<std::string>* field,
                                      const std::string& help) {
  OptionSpec& s = Add(name, help, "TEXT");
  s.positional = true;
  s.is_list = true;
  s.changes_output = false;  // paths: what they name are inputs (or the outputs' place)
  s.set = [field](const std::string& v) { field->push_back(v); };
  s.set_list = [field](const std::vector<std::string>& v) { *field = v; };
  s.text = [field] {
    std::string t;
    for (const auto& v : *field) t += (t.empty() ? "" : " ") + v;
    return t;
  };
  s.json = [field] { return nlohmann::json(*field); };
  return Finish(s).Required();
}

OptionRef OptionTable::OptionalPositional(const std::string& name, std::string* field,
                                          const std::string& help) {
  OptionSpec& s = Add(name, help, "TEXT");
  s.positional = true;
  s.changes_output = false;  // a path: what it names is an input (or the output's place)
  s.set = [field](const std::string& v) { *field = v; };
  s.text = [field] { return *field; };
  s.json = [field] { return nlohmann::json(*field); };
  return Finish(s);
}

OptionRef OptionTable::Flag(const std::string& names, bool* field, const std::string& help) {
  OptionSpec& s = Add(names, help, "FLAG");
  s.is_flag = true;
  s.set = [field](const std::string& v) { *field = v == "1" || v == "true"; };
  s.text = [field] { return std::string(*field ? "1" : "0"); };
  s.json = [field] { return nlohmann::json(*field); };
  return Finish(s);
}

OptionRef OptionTable::Real(const std::string& names, double* field, const std::string& help) {
  OptionSpec& s = Add(names, help, "FLOAT");
  s.set = [field, flag = s.flag](const std::string& v) { *field = ParseDoubleArg(v, flag); };
  s.text = [field] { return FormatShort(*field); };
  s.json = [field] { return nlohmann::json(*field); };
  return Finish(s);
}

OptionRef OptionTable::Text(const std::string& names, std::string* field, const std::string& help) {
  OptionSpec& s = Add(names, help, "TEXT");
  s.set = [field](const std::string& v) { *field = v; };
  s.text = [field] { return *field; };
  s.json = [field] { return nlohmann::json(*field); };
  return Finish(s);
}

void OptionTable::Check() const {
  for (const OptionSpec& s : options_) {
    if (s.required && s.text().empty()) throw UsageError(s.flag + " is required");
    if (s.has_range) {
      const double v = s.json().get<double>();
      const bool ok = std::isfinite(v) ? v >= s.lo && v <= s.hi && !(s.lo_open && v == s.lo) &&
                                             !(s.hi_open && v == s.hi)
                                       : false;
      if (!ok) throw UsageError(s.flag + ": must be " + RangeText(s));
    } else if (s.type == "FLOAT" && !std::isfinite(s.json().get<double>())) {
      throw UsageError(s.flag + ": must be finite");
    }
    if (s.check) s.check();
  }
}

nlohmann::json OptionTable::Json() const {
  nlohmann::json j = nlohmann::json::object();
  for (const OptionSpec& s : options_)
    if (!s.hidden) j[s.key] = s.json();
  return j;
}

nlohmann::json OptionTable::OutputJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (const OptionSpec& s : options_)
    if (s.changes_output) j[s.key] = s.json();
  return j;
}

std::string OptionTable::FlagOf(const std::string& key) const {
  for (const OptionSpec& s : options_)
    if (s.key == key) return s.flag;
  return key;
}

std::string OptionTable::FlagOfField(const std::string& field) const {
  for (const OptionSpec& s : options_)
    if (s.key == field || std::find(s.fields.begin(), s.fields.end(), field) != s.fields.end())
      return s.flag;
  return "";
}

const OptionSpec* OptionTable::Find(const std::string& flag) const {
  for (const OptionSpec& s : options_)
    if (s.flag == flag || s.key == flag) return &s;
  return nullptr;
}

nlohmann::json OptionTable::Describe() const {
  nlohmann::json all = nlohmann::json::array();
  for (const OptionSpec& s : options_) {
    if (s.hidden) continue;
    nlohmann::json j = {
        {"names", s.names},
        {"flag", s.flag},
        {"key", s.key},
        {"type", s.type},
        {"default", s.default_text},
        {"positional", s.positional},
        {"required", s.required},
        {"changes_output", s.changes_output},
        {"alternative", s.alternative.empty() ? DerivedAlternative(s) : s.alternative}};
    if (s.has_range) j["range"] = RangeText(s);
    if (!s.choices.empty()) j["choices"] = s.choices;
    all.push_back(j);
  }
  return {{"tool", tool_}, {"options", all}};
}

}  // namespace mvtm
