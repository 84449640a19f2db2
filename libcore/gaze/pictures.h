// mvtm — gaze pictures: fixations drawn on a photograph, and a top-down heat map of fixations on
// the road.
//
//  * DrawFixations: each mark a circle (radius 1/25 of the image's smaller side, at least 3 px)
//    around the COLMAP pixel (u, v) with its label (the fixation's number) beside it; the image is
//    made 8-bit RGB (grey is repeated, alpha dropped).
//  * RenderHeatmap: an orthographic view straight down (along −up) onto the mesh. Map axes: e1 =
//    the world x axis (or y when x is nearly along up) made perpendicular to up, to the right;
//    e2 = up × e1, towards the top of the picture. The map covers the render path and the points,
//    padded by 15 % of the larger side (at least sigma·4); its larger side is `size` pixels. Each
//    pixel shows the mesh's vertex colour where a ray from above hits (grey 150 without colours,
//    dark grey 30 where there is no surface), the render path as white dots, and the heat: a sum
//    of Gaussians (sigma in model units; 0: 1 % of the map's larger side) weighted by the points'
//    weights (fixation durations), normalised to its maximum and blended from yellow to red.
// Thread safety: functions are reentrant.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "raycast/mesh_raycaster.h"
#include "scene/mesh.h"

namespace mvtm {

struct FixationMark {
  double u = 0, v = 0;
  std::string label;
};

void DrawFixations(Image& image, const std::vector<FixationMark>& marks);

struct HeatPoint {
  Eigen::Vector3d point;
  double weight = 1;
};

struct HeatmapOptions {
  int size = 1024;   // pixels of the larger side
  double sigma = 0;  // model units; 0: 1 % of the map's larger side
};

Image RenderHeatmap(const Mesh& mesh, const MeshRaycaster& raycaster, const Eigen::Vector3d& up,
                    const std::vector<Eigen::Vector3d>& path, const std::vector<HeatPoint>& points,
                    const HeatmapOptions& options);

// RenderHeatmap with the mesh given part by part (a road's fragments, one resident at a time):
// each pixel shows the highest surface of any part under it (the same picture as RenderHeatmap on
// the parts' union, up to hits exactly at the parts' shared edges). Throws Error as RenderHeatmap.
class HeatmapPainter {
 public:
  HeatmapPainter(const Eigen::Vector3d& up, std::vector<Eigen::Vector3d> path,
                 std::vector<HeatPoint> points, const HeatmapOptions& options);
  ~HeatmapPainter();
  // True when an axis-aligned box, seen from above, overlaps the map.
  bool CoversBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  void AddSurface(const Mesh& mesh, const MeshRaycaster& raycaster);
  // The map: the surfaces added (dark grey where none), the path and the heat.
  Image Finish() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace mvtm
