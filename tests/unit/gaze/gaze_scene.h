// Hand-built geometry shared by the gaze tests: cameras looking along ±x, a pinhole camera, and a
// ground plane with a wall ahead.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "scene/mesh.h"

namespace mvtm::gaze_test {

// Camera at C looking along sign·x: x right, y down (world −z), z forward.
inline Rigid3d LookAlongX(const Eigen::Vector3d& C, double sign = 1) {
  Eigen::Matrix3d c2w;
  c2w.col(0) = Eigen::Vector3d(0, -sign, 0);
  c2w.col(1) = Eigen::Vector3d(0, 0, -1);
  c2w.col(2) = Eigen::Vector3d(sign, 0, 0);
  const Eigen::Matrix3d R = c2w.transpose();
  return Rigid3d(Eigen::Quaterniond(R), -R * C);
}

inline Camera Pinhole(uint64_t w, uint64_t h, double f) {
  Camera c;
  c.model = CameraModel::kPinhole;
  c.width = w;
  c.height = h;
  c.params = {f, f, w / 2.0, h / 2.0};
  return c;
}

inline void Quad(Mesh& m, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                 const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const uint32_t i = static_cast<uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c, d});
  m.faces.push_back({i, i + 1, i + 2});
  m.faces.push_back({i, i + 2, i + 3});
}

// Ground z = 0 over [-50, 50]²; a wall x = 5, |y| <= 5, 0 <= z <= wall_height.
inline Mesh Scene(double wall_height) {
  Mesh m;
  Quad(m, {-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0});
  Quad(m, {5, -5, 0}, {5, 5, 0}, {5, 5, wall_height}, {5, -5, wall_height});
  return m;
}

}  // namespace mvtm::gaze_test
