#include "drive/controls_tsv.h"

#include <array>
#include <charconv>
#include <istream>
#include <map>

#include "base/text.h"

namespace mvtm {

namespace {

constexpr const char* kColumns[] = {"time", "steer", "speed"};

// Column index of time, steer and speed; the other names go to `ignored`.
std::array<size_t, 3> ReadHeader(LineReader& r, size_t& fields, std::vector<std::string>& ignored) {
  std::string line;
  if (!r.Next(line)) r.Fail("empty file: expected a header naming the columns 'time steer speed'");
  const auto head = SplitBlank(line);
  fields = head.size();
  double number = 0;
  if (!head.empty() &&
      std::from_chars(head[0].data(), head[0].data() + head[0].size(), number).ec == std::errc())
    r.Fail("expected a header naming the columns 'time steer speed', found a row of numbers");
  std::map<std::string, size_t> at;
  for (size_t i = 0; i < head.size(); ++i)
    if (!at.emplace(std::string(head[i]), i).second)
      r.Fail("the header names the column '" + std::string(head[i]) + "' twice");
  std::array<size_t, 3> idx{};
  for (size_t k = 0; k < 3; ++k) {
    const auto it = at.find(kColumns[k]);
    if (it == at.end())
      r.Fail(std::string("the header has no column '") + kColumns[k] +
             "' (expected a header naming 'time steer speed')");
    idx[k] = it->second;
    at.erase(it);
  }
  for (size_t i = 0; i < head.size(); ++i)
    if (at.count(std::string(head[i]))) ignored.emplace_back(head[i]);
  return idx;
}

ControlsLog ReadLog(LineReader& r) {
  ControlsLog log;
  size_t fields = 0;
  const auto idx = ReadHeader(r, fields, log.ignored);
  std::string line;
  while (r.Next(line)) {
    const auto f = SplitBlank(line);
    if (f.size() != fields)
      r.Fail("expected " + std::to_string(fields) + " fields as in the header, found " +
             std::to_string(f.size()));
    ControlSample c;
    c.time = ParseDouble(f[idx[0]], r, "time");
    c.steer_deg = ParseDouble(f[idx[1]], r, "steer");
    c.speed = ParseDouble(f[idx[2]], r, "speed");
    c.line = r.line();
    if (!log.samples.empty()) {
      const ControlSample& prev = log.samples.back();
      if (c.time == prev.time)
        r.Fail("time " + FormatDouble(c.time) + " repeats line " + std::to_string(prev.line));
      if (c.time < prev.time)
        r.Fail("time " + FormatDouble(c.time) + " is before line " + std::to_string(prev.line) +
               "'s " + FormatDouble(prev.time) + ": samples must be in time order");
    }
    log.samples.push_back(c);
  }
  if (log.samples.size() < 2)
    r.Fail("needs at least two samples (the first and the last time), found " +
           std::to_string(log.samples.size()));
  return log;
}

}  // namespace

ControlsLog ReadControlsTsv(std::istream& in, const std::string& name) {
  LineReader r(in, name);
  return ReadLog(r);
}

ControlsLog ReadControlsTsv(const std::string& path) {
  LineReader r(path);
  return ReadLog(r);
}

}  // namespace mvtm
