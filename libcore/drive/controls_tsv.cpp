#include "drive/controls_tsv.h"

#include <istream>

#include "base/text.h"

namespace mvtm {

namespace {

ControlsLog ReadLog(LineReader& r) {
  ControlsLog log;
  const ColumnHeader h = ReadColumnHeader(r, {"time", "steer", "speed"}, {}, "time steer speed");
  log.ignored = h.ignored;
  const size_t fields = h.fields;
  const size_t idx[3] = {size_t(h.index[0]), size_t(h.index[1]), size_t(h.index[2])};
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
    if (!log.samples.empty())
      CheckTimeAfter(r, c.time, log.samples.back().time, log.samples.back().line);
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
