// pickview — the QUERIES argument: a trajectory file (TUM, KITTI, COLMAP images.txt) or "-"
// (standard input, read as a stream), turned into named world-to-camera query poses.
// Kept apart from pickview.cpp so the fuzz harness (tests/fuzz/) can call the parser alone.
#pragma once

#include <cstddef>
#include <istream>
#include <string>
#include <vector>

#include "geometry/rigid.h"

namespace mvtm {

struct PickViewQuery {
  std::string name;
  Rigid3d w2c;
  size_t self = static_cast<size_t>(-1);  // candidate index of the same image (own images only)
};

// Reads `path` ("-": `in`). A pose without a name is named by its index ("000000", ...).
// Throws Error("FILE:LINE: what"), also for a pose whose inverse is not finite.
std::vector<PickViewQuery> ReadPickViewQueries(const std::string& path, std::istream& in);

}  // namespace mvtm
