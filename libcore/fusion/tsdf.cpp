// TsdfVolume: argument checks here, the volume itself in libmvtm_vdb.so (tsdf_backend.h).
#include <cmath>
#include <string>

#include "base/error.h"
#include "base/plugin.h"
#include "fusion/fusion.h"
#include "fusion/tsdf_backend.h"

namespace mvtm {

namespace {
const VdbPlugin& Plugin() {
  static std::string failure;
  static const VdbPlugin* plugin =
      PluginTable<VdbPlugin>("libmvtm_vdb.so", "mvtm_vdb_plugin", kVdbPluginAbi, &failure);
  if (!plugin) throw Error("depth fusion needs OpenVDB, which could not be loaded: " + failure);
  return *plugin;
}

void Check(const std::string& error) {
  if (!error.empty()) throw Error(error);
}
}  // namespace

struct TsdfVolume::Impl {
  std::unique_ptr<TsdfBackend> backend;
  Eigen::Vector3d origin;
  double voxel = 1;
};

TsdfVolume::TsdfVolume(const Eigen::Vector3d& origin, double voxel_size, double truncation_voxels)
    : impl_(std::make_unique<Impl>()) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size)) {
    throw UsageError("voxel size must be positive, got " + std::to_string(voxel_size));
  }
  if (!(truncation_voxels >= 1) || !std::isfinite(truncation_voxels)) {
    throw UsageError("truncation must be >= 1 voxel, got " + std::to_string(truncation_voxels));
  }
  std::string error;
  impl_->backend.reset(Plugin().create(origin, voxel_size, truncation_voxels, &error));
  Check(error);
  impl_->origin = origin;
  impl_->voxel = voxel_size;
}

TsdfVolume::~TsdfVolume() = default;
TsdfVolume::TsdfVolume(TsdfVolume&&) noexcept = default;
TsdfVolume& TsdfVolume::operator=(TsdfVolume&&) noexcept = default;

void TsdfVolume::Integrate(const DepthView& view, double max_depth) {
  CheckDepthView(view, 0);
  Check(impl_->backend->Integrate(view, max_depth));
}

Mesh TsdfVolume::ExtractMesh(double min_weight) const {
  Mesh mesh;
  Check(impl_->backend->ExtractMesh(min_weight, &mesh));
  return mesh;
}

size_t TsdfVolume::ActiveVoxels() const { return impl_->backend->ActiveVoxels(); }
double TsdfVolume::voxel_size() const { return impl_->voxel; }
const Eigen::Vector3d& TsdfVolume::origin() const { return impl_->origin; }

}  // namespace mvtm
