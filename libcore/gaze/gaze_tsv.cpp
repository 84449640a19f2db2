#include "gaze/gaze_tsv.h"

#include <charconv>
#include <cmath>
#include <istream>
#include <map>

#include "base/text.h"

namespace mvtm {

namespace {

// Shortest text that reads back as v ("0.1", not FormatDouble's "0.10000000000000001").
std::string Short(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

struct Columns {
  size_t fields = 0;
  size_t time = 0, x = 0, y = 0;
  long valid = -1;  // -1: no `valid` column
};

Columns ReadHeader(LineReader& r, std::vector<std::string>& ignored) {
  std::string line;
  if (!r.Next(line)) r.Fail("empty file: expected a header naming the columns 'time x y [valid]'");
  const auto head = SplitBlank(line);
  double number = 0;
  if (!head.empty() &&
      std::from_chars(head[0].data(), head[0].data() + head[0].size(), number).ec == std::errc())
    r.Fail("expected a header naming the columns 'time x y [valid]', found a row of numbers");
  std::map<std::string, size_t> at;
  for (size_t i = 0; i < head.size(); ++i)
    if (!at.emplace(std::string(head[i]), i).second)
      r.Fail("the header names the column '" + std::string(head[i]) + "' twice");
  Columns c;
  c.fields = head.size();
  auto take = [&](const char* name, bool required) -> long {
    const auto it = at.find(name);
    if (it == at.end()) {
      if (required)
        r.Fail(std::string("the header has no column '") + name +
               "' (expected a header naming 'time x y [valid]')");
      return -1;
    }
    const long i = static_cast<long>(it->second);
    at.erase(it);
    return i;
  };
  c.time = static_cast<size_t>(take("time", true));
  c.x = static_cast<size_t>(take("x", true));
  c.y = static_cast<size_t>(take("y", true));
  c.valid = take("valid", false);
  for (size_t i = 0; i < head.size(); ++i)
    if (at.count(std::string(head[i]))) ignored.emplace_back(head[i]);
  return c;
}

GazeTrace ReadTrace(LineReader& r) {
  GazeTrace g;
  const Columns c = ReadHeader(r, g.ignored);
  std::string line;
  while (r.Next(line)) {
    const auto f = SplitBlank(line);
    if (f.size() != c.fields)
      r.Fail("expected " + std::to_string(c.fields) + " fields as in the header, found " +
             std::to_string(f.size()));
    GazeSample s;
    s.time = ParseDouble(f[c.time], r, "time");
    s.x = ParseDouble(f[c.x], r, "x", true);
    s.y = ParseDouble(f[c.y], r, "y", true);
    s.line = r.line();
    if (c.valid >= 0) {
      const auto v = f[static_cast<size_t>(c.valid)];
      if (v != "0" && v != "1") r.Fail("valid: '" + std::string(v) + "' is not 0 or 1");
      s.valid = v == "1";
    }
    if (!s.valid) {
      ++g.invalid_flagged;
    } else if (!std::isfinite(s.x) || !std::isfinite(s.y)) {
      s.valid = false;
      ++g.invalid_nonfinite;
    }
    if (!g.samples.empty()) {
      const GazeSample& prev = g.samples.back();
      if (s.time == prev.time)
        r.Fail("time " + Short(s.time) + " repeats line " + std::to_string(prev.line));
      if (s.time < prev.time)
        r.Fail("time " + Short(s.time) + " is before line " + std::to_string(prev.line) + "'s " +
               Short(prev.time) + ": samples must be in time order");
    }
    g.samples.push_back(s);
  }
  if (g.samples.size() < 2)
    r.Fail("needs at least two samples, found " + std::to_string(g.samples.size()));
  return g;
}

}  // namespace

GazeTrace ReadGazeTsv(std::istream& in, const std::string& name) {
  LineReader r(in, name);
  return ReadTrace(r);
}

GazeTrace ReadGazeTsv(const std::string& path) {
  LineReader r(path);
  return ReadTrace(r);
}

}  // namespace mvtm
