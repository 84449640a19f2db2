// libmvtm_vdb.so: the TSDF volume on OpenVDB (see tsdf_backend.h), opened by TsdfVolume with
// dlopen on first use so that programs not fusing depth maps do not load OpenVDB.
#include <openvdb/math/DDA.h>
#include <openvdb/math/Ray.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "fusion/tsdf_backend.h"

namespace mvtm {
namespace {

using RayD = openvdb::math::Ray<double>;
using DdaD = openvdb::math::DDA<RayD, 0>;

double PixelWeight(const DepthView& v, int x, int y) {
  return v.confidence.empty() ? 1.0 : static_cast<double>(v.confidence.at(x, y));
}

// Keeps a polygon only where every vertex lies in a cell whose 8 corner voxels were observed:
// next to unobserved voxels (background +truncation) the sign change is an artefact of the band's
// edge, not a surface.
bool ObservedCell(const openvdb::FloatGrid::ConstAccessor& weights, const openvdb::Vec3s& p,
                  double min_weight) {
  const openvdb::Coord c = openvdb::Coord::floor(p);
  for (int dz = 0; dz <= 1; ++dz) {
    for (int dy = 0; dy <= 1; ++dy) {
      for (int dx = 0; dx <= 1; ++dx) {
        if (!(weights.getValue(c.offsetBy(dx, dy, dz)) > min_weight)) return false;
      }
    }
  }
  return true;
}

// Runs `body`; any exception becomes the returned message (none crosses the module boundary).
template <class F>
std::string Guard(F&& body) {
  try {
    body();
    return "";
  } catch (const std::bad_alloc&) {
    return "out of memory in the TSDF volume";
  } catch (const std::exception& e) {
    return std::string("TSDF volume: ") + e.what();
  }
}

class VdbTsdf : public TsdfBackend {
 public:
  VdbTsdf(const Eigen::Vector3d& o, double voxel_size, double truncation_voxels)
      : origin(o), voxel(voxel_size), truncation(truncation_voxels) {
    openvdb::initialize();
    tsdf = openvdb::FloatGrid::create(static_cast<float>(truncation_voxels));
    weight = openvdb::FloatGrid::create(0.f);
  }

  std::string Integrate(const DepthView& view, double max_depth) override {
    return Guard([&] {
      const Eigen::Matrix3d r_t = view.world_to_camera.R().transpose();
      const Eigen::Vector3d c = (view.world_to_camera.Centre() - origin) / voxel;
      auto tacc = tsdf->getAccessor();
      auto wacc = weight->getAccessor();
      for (int y = 0; y < view.depth.height; ++y) {
        for (int x = 0; x < view.depth.width; ++x) {
          const float z = view.depth.at(x, y);
          const float w = static_cast<float>(PixelWeight(view, x, y));
          if (!(std::isfinite(z) && z > 0 && z < max_depth && w > 0)) continue;
          const Eigen::Vector3d ray = r_t * view.camera.Unproject({x + 0.5, y + 0.5}, z) / voxel;
          const double d = ray.norm();
          IntegrateRay(c, ray / d, d, w, tacc, wacc);
        }
      }
    });
  }

  std::string ExtractMesh(double min_weight, Mesh* out) const override {
    return Guard([&] {
      std::vector<openvdb::Vec3s> points;
      std::vector<openvdb::Vec3I> triangles;
      std::vector<openvdb::Vec4I> quads;
      openvdb::tools::volumeToMesh(*tsdf, points, triangles, quads, 0.0, 0.0);
      const auto wacc = weight->getConstAccessor();
      std::vector<char> observed(points.size());
      for (size_t i = 0; i < points.size(); ++i)
        observed[i] = ObservedCell(wacc, points[i], min_weight);
      std::vector<uint32_t> remap(points.size(), UINT32_MAX);
      Mesh mesh;
      auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (!observed[a] || !observed[b] || !observed[c]) return;
        std::array<uint32_t, 3> f{a, b, c};
        for (uint32_t& i : f) {
          if (remap[i] == UINT32_MAX) {
            remap[i] = static_cast<uint32_t>(mesh.vertices.size());
            const openvdb::Vec3s& p = points[i];
            mesh.vertices.push_back(origin + voxel * Eigen::Vector3d(p.x(), p.y(), p.z()));
          }
          i = remap[i];
        }
        mesh.faces.push_back(f);  // volumeToMesh winds counter-clockwise seen from the free side
      };
      for (const openvdb::Vec3I& t : triangles) add(t[0], t[1], t[2]);
      for (const openvdb::Vec4I& q : quads) {
        add(q[0], q[1], q[2]);
        add(q[0], q[2], q[3]);
      }
      if (!mesh.faces.empty()) mesh.ComputeNormals();
      *out = std::move(mesh);
    });
  }

  size_t ActiveVoxels() const override { return tsdf->activeVoxelCount(); }

 private:
  Eigen::Vector3d origin;
  double voxel = 1;
  double truncation = 3;  // voxels
  openvdb::FloatGrid::Ptr tsdf;
  openvdb::FloatGrid::Ptr weight;

  // One ray in index space: from the camera centre c along the unit direction u, the surface at
  // distance d (voxels). Voxel cells are centred on integer coordinates, hence the half shift.
  void IntegrateRay(const Eigen::Vector3d& c, const Eigen::Vector3d& u, double d, float w,
                    openvdb::FloatGrid::Accessor& tacc, openvdb::FloatGrid::Accessor& wacc) {
    const double t0 = std::max(0.0, d - truncation), t1 = d + truncation;
    const RayD ray(openvdb::Vec3d(c.x() + 0.5, c.y() + 0.5, c.z() + 0.5),
                   openvdb::Vec3d(u.x(), u.y(), u.z()));
    DdaD dda(ray, t0, t1);
    do {
      const openvdb::Coord& v = dda.voxel();
      const double dist = (Eigen::Vector3d(v.x(), v.y(), v.z()) - c).norm();
      const double sdf = d - dist;
      if (sdf < -truncation) continue;
      const float value = static_cast<float>(std::min(sdf, truncation));
      const float w_old = wacc.getValue(v);
      const float w_new = w_old + w;
      tacc.setValue(v, (tacc.getValue(v) * w_old + value * w) / w_new);
      wacc.setValue(v, w_new);
    } while (dda.step());
  }
};

const VdbPlugin kPlugin{kVdbPluginAbi,
                        [](const Eigen::Vector3d& origin, double voxel, double truncation,
                           std::string* error) -> TsdfBackend* {
                          TsdfBackend* made = nullptr;
                          *error = Guard([&] { made = new VdbTsdf(origin, voxel, truncation); });
                          return made;
                        }};

}  // namespace
}  // namespace mvtm

extern "C" __attribute__((visibility("default"))) const mvtm::VdbPlugin* mvtm_vdb_plugin() {
  return &mvtm::kPlugin;
}
