#include "io/exposure_tsv.h"

#include <cmath>
#include <ostream>
#include <set>

#include "base/atomic_file.h"
#include "base/text.h"

namespace mvtm {

namespace {

constexpr const char* kHeader = "image\tgain\toffset\tpoints\n";

std::vector<ExposureRow> ReadRows(LineReader& r) {
  std::string line;
  if (!r.Next(line)) r.Fail("empty file: expected the header 'image gain offset points'");
  auto head = SplitBlank(line);
  if (head.size() != 4 || head[0] != "image" || head[1] != "gain" || head[2] != "offset")
    r.Fail("expected the header 'image gain offset points' (exposure)");
  std::vector<ExposureRow> rows;
  std::set<std::string> seen;
  while (r.Next(line)) {
    auto f = SplitChar(line, '\t');
    if (f.size() != 4) r.Fail("expected 4 tab-separated fields, found " + std::to_string(f.size()));
    ExposureRow row;
    row.image = std::string(f[0]);
    row.gain = ParseDouble(f[1], r, "gain");
    row.offset = ParseDouble(f[2], r, "offset");
    row.points = ParseInt(f[3], r, "points");
    if (!(row.gain > 0)) r.Fail("gain must be > 0");
    if (row.points < 0) r.Fail("points must be >= 0");
    if (!seen.insert(row.image).second) r.Fail("image '" + row.image + "' appears twice");
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

std::vector<ExposureRow> ReadExposureTsv(std::istream& in, const std::string& name) {
  LineReader r(in, name);
  return ReadRows(r);
}

std::vector<ExposureRow> ReadExposureTsv(const std::string& path) {
  LineReader r(path);
  return ReadRows(r);
}

void WriteExposureTsv(std::ostream& out, const std::vector<ExposureRow>& rows) {
  std::string text = kHeader;
  for (const ExposureRow& row : rows)
    text += row.image + '\t' + FormatDouble(row.gain) + '\t' + FormatDouble(row.offset) + '\t' +
            std::to_string(row.points) + '\n';
  out << text;
}

void WriteExposureTsv(const std::string& path, const std::vector<ExposureRow>& rows) {
  WriteTextAtomic(path, [&](std::ostream& f) { WriteExposureTsv(f, rows); });
}

}  // namespace mvtm
