#include "io/tracks.h"

#include <charconv>
#include <climits>
#include <fstream>
#include <tuple>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "io/text_file.h"

namespace mvtm {

namespace {

constexpr const char* kHeader =
    "frame\tname\ttrack\tstate\tx\ty\tw\th\tcx\tcy\tarea\tscx\tscy\tsw\tsh";
constexpr size_t kFields = 15;

// "%.3f" without the C locale: to_chars is exact, like printf.
void AppendFixed(std::string& s, double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, 3);
  s.append(buf, r.ptr);
}

int ParseIntIn(std::string_view token, const LineReader& in, const char* field, int lo) {
  const int64_t v = ParseInt(token, in, field);
  if (v < lo || v > INT_MAX)
    in.Fail(std::string(field) + ": " + std::to_string(v) + " is out of range " +
            std::to_string(lo) + ".." + std::to_string(INT_MAX));
  return static_cast<int>(v);
}

RowState ParseState(std::string_view token, const LineReader& in) {
  for (int i = 0; i < 3; ++i)
    if (token == kRowStateNames[i]) return static_cast<RowState>(i);
  in.Fail("state: '" + std::string(token) + "' is not detected, interpolated or rejected");
}

TracksTsvRow ParseRow(const std::string& line, const LineReader& in) {
  const auto tok = SplitChar(line, '\t');
  if (tok.size() != kFields)
    in.Fail("row needs " + std::to_string(kFields) + " tab-separated fields, found " +
            std::to_string(tok.size()));
  TracksTsvRow out;
  TrackRow& r = out.row;
  r.frame = ParseIntIn(tok[0], in, "frame", 0);
  out.name = std::string(tok[1]);
  if (out.name.empty()) in.Fail("name is empty");
  r.track = ParseIntIn(tok[2], in, "track", 1);
  r.state = ParseState(tok[3], in);
  r.x = ParseIntIn(tok[4], in, "x", INT_MIN);
  r.y = ParseIntIn(tok[5], in, "y", INT_MIN);
  r.w = ParseIntIn(tok[6], in, "w", 0);
  r.h = ParseIntIn(tok[7], in, "h", 0);
  r.cx = ParseDouble(tok[8], in, "cx");
  r.cy = ParseDouble(tok[9], in, "cy");
  r.area = ParseIntIn(tok[10], in, "area", 0);
  r.scx = ParseDouble(tok[11], in, "scx");
  r.scy = ParseDouble(tok[12], in, "scy");
  r.sw = ParseDouble(tok[13], in, "sw");
  r.sh = ParseDouble(tok[14], in, "sh");
  return out;
}

}  // namespace

void WriteTracksTsv(std::ostream& out, const std::vector<TracksTsvRow>& rows) {
  // Built as text first: the stream's locale must not group or localise the numbers.
  std::string line;
  out << kHeader << '\n';
  for (const TracksTsvRow& tr : rows) {
    const TrackRow& r = tr.row;
    line = std::to_string(r.frame) + '\t' + tr.name + '\t' + std::to_string(r.track) + '\t' +
           RowStateName(r.state);
    for (int v : {r.x, r.y, r.w, r.h}) line += '\t' + std::to_string(v);
    for (double v : {r.cx, r.cy}) AppendFixed(line += '\t', v);
    line += '\t' + std::to_string(r.area);
    for (double v : {r.scx, r.scy, r.sw, r.sh}) AppendFixed(line += '\t', v);
    line += '\n';
    out << line;
  }
}

void WriteTracksTsv(const std::string& path, const std::vector<TracksTsvRow>& rows) {
  WriteTextAtomic(path, [&](std::ostream& out) { WriteTracksTsv(out, rows); });
}

std::vector<TracksTsvRow> ReadTracksTsv(std::istream& stream, const std::string& name) {
  LineReader in(stream, name);
  std::string line;
  if (!in.Next(line, false)) throw Error(name, 0, "no header line");
  if (line != kHeader)
    in.Fail(
        "not a tracks.tsv header: expected the tab-separated columns frame name track state x "
        "y w h cx cy area scx scy sw sh");
  std::vector<TracksTsvRow> rows;
  while (in.Next(line, false)) {
    TracksTsvRow r = ParseRow(line, in);
    if (!rows.empty() && std::tie(r.row.frame, r.row.track) <=
                             std::tie(rows.back().row.frame, rows.back().row.track))
      in.Fail("rows must be sorted by frame, then track: frame " + std::to_string(r.row.frame) +
              " track " + std::to_string(r.row.track) + " follows frame " +
              std::to_string(rows.back().row.frame) + " track " +
              std::to_string(rows.back().row.track));
    rows.push_back(std::move(r));
  }
  return rows;
}

std::vector<TracksTsvRow> ReadTracksTsv(const std::string& path) {
  std::ifstream in = OpenTextFile(path);
  return ReadTracksTsv(in, path);
}

}  // namespace mvtm
