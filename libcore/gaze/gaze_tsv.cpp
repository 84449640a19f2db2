#include "gaze/gaze_tsv.h"

#include <charconv>
#include <cmath>
#include <istream>

#include "base/text.h"

namespace mvtm {

namespace {

struct Columns {
  size_t fields = 0;
  size_t time = 0, x = 0, y = 0;
  long valid = -1;  // -1: no `valid` column
};

Columns ReadHeader(LineReader& r, std::vector<std::string>& ignored) {
  const ColumnHeader h = ReadColumnHeader(r, {"time", "x", "y"}, {"valid"}, "time x y [valid]");
  ignored = h.ignored;
  Columns c;
  c.fields = h.fields;
  c.time = static_cast<size_t>(h.index[0]);
  c.x = static_cast<size_t>(h.index[1]);
  c.y = static_cast<size_t>(h.index[2]);
  c.valid = h.index[3];
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
    if (!g.samples.empty()) CheckTimeAfter(r, s.time, g.samples.back().time, g.samples.back().line);
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
