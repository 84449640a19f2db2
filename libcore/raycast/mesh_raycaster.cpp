#include "raycast/mesh_raycaster.h"

#include <embree3/rtcore.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "base/error.h"

namespace mvtm {

namespace {

void Check(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE)
    throw Error(std::string("Embree: ") + what + " failed (error " + std::to_string(e) + ")");
}

}  // namespace

struct MeshRaycaster::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> vertices;  // double, world coordinates
  std::vector<std::array<uint32_t, 3>> faces;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void Build() {
    device = rtcNewDevice(nullptr);
    if (!device) throw Error("Embree: cannot create a device");
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    if (!faces.empty()) {
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
      auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
          g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), faces.size()));
      Check(device, "allocating the mesh buffers");
      for (size_t i = 0; i < vertices.size(); ++i) {
        const Eigen::Vector3d local = vertices[i] - centre;  // re-centred in double first
        for (int k = 0; k < 3; ++k) vb[3 * i + k] = static_cast<float>(local[k]);
      }
      for (size_t f = 0; f < faces.size(); ++f)
        for (int k = 0; k < 3; ++k) ib[3 * f + k] = faces[f][k];
      rtcCommitGeometry(g);
      rtcAttachGeometry(scene, g);
      rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene);
    Check(device, "building the ray-casting structure");
  }

  RTCRay Ray(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0, double t1) const {
    const Eigen::Vector3d local = o - centre;
    RTCRay r{};
    r.org_x = static_cast<float>(local.x());
    r.org_y = static_cast<float>(local.y());
    r.org_z = static_cast<float>(local.z());
    r.dir_x = static_cast<float>(d.x());
    r.dir_y = static_cast<float>(d.y());
    r.dir_z = static_cast<float>(d.z());
    r.tnear = static_cast<float>(std::max(t0, 0.0));
    r.tfar = t1 >= static_cast<double>(std::numeric_limits<float>::max())
                 ? std::numeric_limits<float>::infinity()
                 : static_cast<float>(t1);
    r.mask = 0xFFFFFFFFu;
    r.time = 0;
    r.flags = 0;
    return r;
  }

  // Möller–Trumbore in double against triangle `f`, starting from Embree's float answer.
  RayHit Refine(const Eigen::Vector3d& o, const Eigen::Vector3d& d, uint32_t f, float t_float,
                float u_float, float v_float) const {
    const Eigen::Vector3d& A = vertices[faces[f][0]];
    const Eigen::Vector3d& B = vertices[faces[f][1]];
    const Eigen::Vector3d& C = vertices[faces[f][2]];
    const Eigen::Vector3d e1 = B - A, e2 = C - A;
    RayHit h;
    h.triangle = f;
    h.normal = e1.cross(e2).normalized();
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (det != 0 && std::isfinite(det)) {
      const double inv = 1.0 / det;
      const Eigen::Vector3d T = o - A;
      const Eigen::Vector3d q = T.cross(e1);
      h.u = T.dot(p) * inv;
      h.v = d.dot(q) * inv;
      h.t = e2.dot(q) * inv;
    }
    // A ray in (or nearly in) the triangle's plane makes the plane intersection ill-conditioned:
    // keep the double answer only where it refines the float one (1e-3 relative), else
    // Embree's hit stands.
    if (!(det != 0 && std::isfinite(h.t) &&
          std::abs(h.t - double(t_float)) <= 1e-3 * std::abs(double(t_float)) + 1e-9)) {
      h.u = u_float;
      h.v = v_float;
      h.t = t_float;
    }
    // An edge hit may land a hair outside the triangle the float traversal chose: clamp.
    h.u = std::clamp(h.u, 0.0, 1.0);
    h.v = std::clamp(h.v, 0.0, 1.0);
    if (h.u + h.v > 1) {
      const double s = h.u + h.v;
      h.u /= s;
      h.v /= s;
    }
    h.point = o + h.t * d;
    return h;
  }
};

MeshRaycaster::MeshRaycaster(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->vertices = mesh.vertices;
  impl_->faces = mesh.faces;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (uint32_t i : mesh.faces[f])
      if (i >= mesh.vertices.size())
        throw Error("mesh face " + std::to_string(f) + " refers to vertex " + std::to_string(i) +
                    " of " + std::to_string(mesh.vertices.size()));
  if (!mesh.faces.empty()) {
    Eigen::Vector3d lo, hi;
    mesh.Bounds(lo, hi);
    impl_->centre = 0.5 * (lo + hi);
  }
  impl_->Build();
}

MeshRaycaster::~MeshRaycaster() = default;
MeshRaycaster::MeshRaycaster(MeshRaycaster&&) noexcept = default;
MeshRaycaster& MeshRaycaster::operator=(MeshRaycaster&&) noexcept = default;

std::optional<RayHit> MeshRaycaster::Closest(const Eigen::Vector3d& origin,
                                             const Eigen::Vector3d& direction, double t_min,
                                             double t_max) const {
  if (impl_->faces.empty() || !(t_max >= t_min)) return std::nullopt;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray = impl_->Ray(origin, direction, t_min, t_max);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return impl_->Refine(origin, direction, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
}

bool MeshRaycaster::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double t_min, double t_max) const {
  if (impl_->faces.empty() || !(t_max >= t_min)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = impl_->Ray(origin, direction, t_min, t_max);
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar == -std::numeric_limits<float>::infinity();
}

const Eigen::Vector3d& MeshRaycaster::centre() const { return impl_->centre; }
size_t MeshRaycaster::triangles() const { return impl_->faces.size(); }

}  // namespace mvtm
