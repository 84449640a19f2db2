// mvtm — exposure.tsv: a gain and an offset per image (exposure, radiometry/exposure.h).
//
// Format (man/mvtm-workspace.5): tab-separated text, the header line
//   image<TAB>gain<TAB>offset<TAB>points
// then one row per image of the model in name order: the image name (as in images.txt), the
// gain and the offset of I = gain · L + offset on the 8-bit scale, written with 17 significant
// digits, and the number of point observations of the image (0: not fitted, identity kept).
// Conventions as io/partners.h: classic "C" numbers, '#' comments and blank lines skipped,
// "FILE:LINE: what" errors, atomic path writer. Gains must be finite and > 0, offsets finite.
// Thread safety: functions are reentrant.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace mvtm {

struct ExposureRow {
  std::string image;
  double gain = 1, offset = 0;
  int64_t points = 0;
};

std::vector<ExposureRow> ReadExposureTsv(std::istream& in, const std::string& name);
std::vector<ExposureRow> ReadExposureTsv(const std::string& path);
void WriteExposureTsv(std::ostream& out, const std::vector<ExposureRow>& rows);
void WriteExposureTsv(const std::string& path, const std::vector<ExposureRow>& rows);

}  // namespace mvtm
