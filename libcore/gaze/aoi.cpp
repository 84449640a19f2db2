#include "gaze/aoi.h"

#include <algorithm>
#include <map>
#include <set>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

std::string CamVidClassName(int id) {
  static const char* kNames[] = {"sky",      "building",   "pole",      "road",
                                 "pavement", "tree",       "sign",      "fence",
                                 "car",      "pedestrian", "bicyclist", "unlabelled"};
  if (id >= 0 && id < 12) return kNames[id];
  return "class-" + std::to_string(id);
}

std::vector<AoiBox> ReadAoiBoxes(const std::string& path) {
  LineReader r(path);
  std::vector<AoiBox> boxes;
  std::set<std::string> names;
  std::string line;
  static const char* kFields[] = {"xmin", "ymin", "zmin", "xmax", "ymax", "zmax"};
  while (r.Next(line)) {
    const auto f = SplitBlank(line);
    if (f.size() != 7)
      r.Fail("expected 7 fields 'name xmin ymin zmin xmax ymax zmax', found " +
             std::to_string(f.size()));
    AoiBox b;
    b.name = std::string(f[0]);
    b.line = r.line();
    double v[6];
    for (int k = 0; k < 6; ++k) v[k] = ParseDouble(f[k + 1], r, kFields[k]);
    for (int k = 0; k < 3; ++k)
      if (v[k] > v[k + 3])
        r.Fail(std::string(kFields[k]) + " " + FormatDouble(v[k]) + " is greater than " +
               kFields[k + 3] + " " + FormatDouble(v[k + 3]));
    if (!names.insert(b.name).second) r.Fail("the box '" + b.name + "' is named twice");
    b.box =
        Eigen::AlignedBox3d(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
    boxes.push_back(b);
  }
  if (boxes.empty()) r.Fail("no boxes");
  return boxes;
}

std::string BoxContaining(const std::vector<AoiBox>& boxes, const Eigen::Vector3d& X) {
  for (const AoiBox& b : boxes)
    if (b.box.contains(X)) return b.name;
  return "";
}

std::vector<DwellRow> DwellTable(const std::vector<std::string>& aoi,
                                 const std::vector<double>& durations) {
  std::map<std::string, DwellRow> rows;
  double total = 0;
  for (size_t i = 0; i < aoi.size(); ++i) {
    DwellRow& r = rows[aoi[i]];
    r.aoi = aoi[i];
    ++r.fixations;
    r.dwell += durations[i];
    total += durations[i];
  }
  std::vector<DwellRow> out;
  for (auto& [name, r] : rows) {
    r.share = total > 0 ? r.dwell / total : 0;
    out.push_back(r);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const DwellRow& a, const DwellRow& b) { return a.dwell > b.dwell; });
  return out;
}

}  // namespace mvtm
