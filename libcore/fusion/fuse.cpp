#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "base/error.h"
#include "base/stats.h"
#include "fusion/fusion.h"

namespace mvtm {
namespace {

void RequirePositive(const char* name, double v) {
  if (!(v > 0) || !std::isfinite(v)) {
    throw UsageError(std::string(name) + " must be positive, got " + std::to_string(v));
  }
}

bool AnyDepth(const std::vector<DepthView>& views) {
  for (const DepthView& v : views) {
    for (float z : v.depth.data) {
      if (std::isfinite(z) && z > 0) return true;
    }
  }
  return false;
}

}  // namespace

void TsdfOptions::Check() const {
  if (voxel_size != 0) RequirePositive("voxel_size", voxel_size);
  RequirePositive("voxel_per_spacing", voxel_per_spacing);
  if (!(truncation_voxels >= 1) || !std::isfinite(truncation_voxels)) {
    throw UsageError("truncation_voxels must be >= 1, got " + std::to_string(truncation_voxels));
  }
  if (!(min_weight >= 0) || !std::isfinite(min_weight)) {
    throw UsageError("min_weight must be >= 0, got " + std::to_string(min_weight));
  }
  if (max_depth_spacings != 0) RequirePositive("max_depth_spacings", max_depth_spacings);
}

void FusionOptions::Check() const {
  consistency.Check();
  tsdf.Check();
}

double MedianCameraSpacing(const std::vector<DepthView>& views) {
  std::vector<Eigen::Vector3d> centres;
  for (const DepthView& v : views) centres.push_back(v.world_to_camera.Centre());
  std::vector<double> nearest;
  for (size_t i = 0; i < centres.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < centres.size(); ++j) {
      const double d = (centres[i] - centres[j]).norm();
      if (j != i && d > 0) best = std::min(best, d);
    }
    if (std::isfinite(best)) nearest.push_back(best);
  }
  if (nearest.empty()) {
    throw Error(
        "fewer than two distinct camera centres: no camera spacing to derive the voxel "
        "size from (give it explicitly)");
  }
  return Median(std::move(nearest));
}

Eigen::Vector3d MeanCameraCentre(const std::vector<DepthView>& views) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const DepthView& v : views) sum += v.world_to_camera.Centre();
  return views.empty() ? sum : Eigen::Vector3d(sum / static_cast<double>(views.size()));
}

Mesh FuseDepthViews(const std::vector<DepthView>& views, const FusionOptions& options) {
  options.Check();
  for (size_t i = 0; i < views.size(); ++i) CheckDepthView(views[i], i);
  if (!AnyDepth(views)) return {};
  const TsdfOptions& t = options.tsdf;
  const bool need_spacing = t.voxel_size == 0 || t.max_depth_spacings > 0;
  const double spacing = need_spacing ? MedianCameraSpacing(views) : 0;
  const double voxel = t.voxel_size > 0 ? t.voxel_size : t.voxel_per_spacing * spacing;
  const double max_depth = t.max_depth_spacings > 0 ? t.max_depth_spacings * spacing
                                                    : std::numeric_limits<double>::infinity();
  TsdfVolume volume(MeanCameraCentre(views), voxel, t.truncation_voxels);
  if (!options.filter) {
    for (const DepthView& v : views) volume.Integrate(v, max_depth);
    return volume.ExtractMesh(t.min_weight);
  }
  std::vector<Image> filtered = FilterConsistentDepth(views, options.consistency);
  for (size_t i = 0; i < views.size(); ++i) {
    DepthView v{views[i].camera, views[i].world_to_camera, std::move(filtered[i]),
                views[i].confidence};
    volume.Integrate(v, max_depth);
  }
  return volume.ExtractMesh(t.min_weight);
}

}  // namespace mvtm
