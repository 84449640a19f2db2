// mvtm — the TSDF volume's backend, in the plugin module libmvtm_vdb.so.
//
// OpenVDB (with TBB, Blosc, Boost, ...) adds some 50 ms to the start of any program that links
// it; roadmesh needs it only with --dense. So the OpenVDB code lives in a module opened with
// dlopen on first use (base/plugin.h) and TsdfVolume (tsdf.cpp) talks to it through this
// interface. The methods never throw: they return "" or a one-line message.
#pragma once

#include <Eigen/Core>
#include <string>

#include "fusion/fusion.h"

namespace mvtm {

inline constexpr int kVdbPluginAbi = 1;

class TsdfBackend {
 public:
  virtual ~TsdfBackend() = default;
  // `view` has passed CheckDepthView.
  virtual std::string Integrate(const DepthView& view, double max_depth) = 0;
  virtual std::string ExtractMesh(double min_weight, Mesh* mesh) const = 0;
  virtual size_t ActiveVoxels() const = 0;
};

struct VdbPlugin {
  int abi = kVdbPluginAbi;
  // A volume at `origin` with cubic voxels of `voxel` model units and a truncation band of
  // `truncation` voxels; nullptr with *error set on failure.
  TsdfBackend* (*create)(const Eigen::Vector3d& origin, double voxel, double truncation,
                         std::string* error);
};

}  // namespace mvtm

extern "C" const mvtm::VdbPlugin* mvtm_vdb_plugin();
