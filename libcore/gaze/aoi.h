// mvtm — areas of interest (AOIs) for gaze: semantic classes of the label images, or named 3-D
// boxes, and the dwell-time table over them.
//
//  * Classes: the CamVid 11-class ids the label images use (WS/labels/NAME.png, 8-bit, as mkroad
//    and segtrack read them): 0 sky, 1 building, 2 pole, 3 road, 4 pavement, 5 tree, 6 sign,
//    7 fence, 8 car, 9 pedestrian, 10 bicyclist, 11 unlabelled; any other id is "class-N".
//  * Boxes file: text, '#' comments and blank lines skipped, one box per line
//    "name xmin ymin zmin xmax ymax zmax" (world coordinates of the model, min <= max; names
//    without blanks, unique). A point belongs to the first box (in file order) that contains it
//    (faces included). Errors: Error("FILE:LINE: what").
//  * Dwell time of an AOI = the summed durations of the fixations in it.
// Thread safety: functions are reentrant.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace mvtm {

std::string CamVidClassName(int id);

struct AoiBox {
  std::string name;
  Eigen::AlignedBox3d box;
  long line = 0;
};

std::vector<AoiBox> ReadAoiBoxes(const std::string& path);
// The name of the first box containing X, or "" when none does.
std::string BoxContaining(const std::vector<AoiBox>& boxes, const Eigen::Vector3d& X);

struct DwellRow {
  std::string aoi;
  size_t fixations = 0;
  double dwell = 0;  // seconds
  double share = 0;  // of the total dwell time, 0..1
};

// One row per distinct AOI name, by decreasing dwell time (ties by name).
std::vector<DwellRow> DwellTable(const std::vector<std::string>& aoi,
                                 const std::vector<double>& durations);

}  // namespace mvtm
