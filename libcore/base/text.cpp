#include "base/text.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>

#include "base/error.h"

namespace mvtm {

LineReader::LineReader(const std::string& path)
    : owned_(std::make_unique<std::ifstream>(path, std::ios::binary)), name_(path) {
  if (!*owned_) throw Error(path, 0, "cannot open");
  in_ = owned_.get();
}

LineReader::LineReader(std::istream& in, std::string name) : in_(&in), name_(std::move(name)) {}

bool LineReader::NextRaw(std::string& line) {
  if (!std::getline(*in_, line)) return false;
  ++line_no_;
  // A UTF-8 byte-order mark (Windows editors write one) is not part of the first field.
  if (line_no_ == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

bool LineReader::Next(std::string& line, bool skip_comments) {
  std::string raw;
  while (NextRaw(raw)) {
    std::string_view t = Trim(raw);
    if (t.empty()) continue;
    if (skip_comments && t.front() == '#') continue;
    line.assign(t);
    return true;
  }
  return false;
}

void LineReader::Fail(const std::string& what) const { throw Error(name_, line_no_, what); }

std::string_view Trim(std::string_view s) {
  const char* ws = " \t\r\n\v\f";
  size_t b = s.find_first_not_of(ws);
  if (b == std::string_view::npos) return {};
  size_t e = s.find_last_not_of(ws);
  return s.substr(b, e - b + 1);
}

std::vector<std::string_view> SplitBlank(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::vector<std::string_view> SplitChar(std::string_view s, char c) {
  std::vector<std::string_view> out;
  size_t i = 0;
  for (;;) {
    size_t j = s.find(c, i);
    if (j == std::string_view::npos) {
      out.push_back(s.substr(i));
      return out;
    }
    out.push_back(s.substr(i, j - i));
    i = j + 1;
  }
}

namespace {

// Returns false when `token` is not entirely a number.
bool ToDouble(std::string_view token, double& v) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  auto r = std::from_chars(token.data(), token.data() + token.size(), v);
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

bool ToInt(std::string_view token, int64_t& v) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  auto r = std::from_chars(token.data(), token.data() + token.size(), v);
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

}  // namespace

double ParseDouble(std::string_view token, const LineReader& at, const char* field,
                   bool allow_nonfinite) {
  double v = 0;
  if (!ToDouble(token, v))
    at.Fail(std::string(field) + ": '" + std::string(token) + "' is not a number");
  if (!allow_nonfinite && !std::isfinite(v))
    at.Fail(std::string(field) + ": '" + std::string(token) + "' is not finite");
  return v;
}

int64_t ParseInt(std::string_view token, const LineReader& at, const char* field) {
  int64_t v = 0;
  if (!ToInt(token, v))
    at.Fail(std::string(field) + ": '" + std::string(token) + "' is not an integer");
  return v;
}

double ParseDoubleArg(std::string_view token, const std::string& what) {
  double v = 0;
  if (!ToDouble(Trim(token), v) || !std::isfinite(v))
    throw UsageError(what + ": '" + std::string(token) + "' is not a finite number");
  return v;
}

int64_t ParseIntArg(std::string_view token, const std::string& what) {
  int64_t v = 0;
  if (!ToInt(Trim(token), v))
    throw UsageError(what + ": '" + std::string(token) + "' is not an integer");
  return v;
}

std::string FormatDouble(double v) {
  char buf[40];
  // to_chars is locale-independent; with a precision of 17 it prints like "%.17g".
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17);
  return std::string(buf, r.ptr);
}

std::string FormatShort(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

void CheckTimeAfter(const LineReader& r, double t, double prev_time, long prev_line) {
  if (t == prev_time)
    r.Fail("time " + FormatShort(t) + " repeats line " + std::to_string(prev_line));
  if (t < prev_time)
    r.Fail("time " + FormatShort(t) + " is before line " + std::to_string(prev_line) + "'s " +
           FormatShort(prev_time) + ": samples must be in time order");
}

ColumnHeader ReadColumnHeader(LineReader& r, const std::vector<std::string>& required,
                              const std::vector<std::string>& optional,
                              const std::string& expected) {
  const std::string want = "a header naming the columns '" + expected + "'";
  std::string line;
  if (!r.Next(line)) r.Fail("empty file: expected " + want);
  const auto head = SplitBlank(line);
  double number = 0;
  if (!head.empty() && ToDouble(head[0], number))
    r.Fail("expected " + want + ", found a row of numbers");
  std::map<std::string, size_t> at;
  for (size_t i = 0; i < head.size(); ++i)
    if (!at.emplace(std::string(head[i]), i).second)
      r.Fail("the header names the column '" + std::string(head[i]) + "' twice");
  ColumnHeader h;
  h.fields = head.size();
  auto take = [&](const std::string& name, bool needed) {
    const auto it = at.find(name);
    if (it == at.end()) {
      if (needed)
        r.Fail("the header has no column '" + name + "' (expected a header naming '" + expected +
               "')");
      h.index.push_back(-1);
      return;
    }
    h.index.push_back(static_cast<long>(it->second));
    at.erase(it);
  };
  for (const auto& name : required) take(name, true);
  for (const auto& name : optional) take(name, false);
  for (const auto& name : head)
    if (at.count(std::string(name))) h.ignored.emplace_back(name);
  return h;
}

}  // namespace mvtm
