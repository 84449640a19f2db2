#include "drive/ground.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "base/error.h"

namespace mvtm {

namespace {

// A time for messages: 6 significant digits ("3.5", "12.1").
std::string Seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", t);
  return buf;
}

}  // namespace

Eigen::Vector3d RoadFrame::ToWorld(double x, double y, double h) const {
  return origin + scale * (x * x_axis + y * y_axis + h * up);
}

Eigen::Vector2d RoadFrame::ToPlane(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - origin;
  return Eigen::Vector2d(d.dot(x_axis), d.dot(y_axis)) / scale;
}

double RoadFrame::Height(const Eigen::Vector3d& p) const { return (p - origin).dot(up) / scale; }

double RoadFrame::Heading(const Eigen::Vector3d& direction) const {
  const double x = direction.dot(x_axis), y = direction.dot(y_axis);
  if (std::hypot(x, y) < 1e-6 * direction.norm())
    throw Error("a camera looks straight up or down: no heading in the road plane");
  return std::atan2(y, x);
}

Eigen::Vector3d RoadFrame::Direction(double heading) const {
  return std::cos(heading) * x_axis + std::sin(heading) * y_axis;
}

Eigen::Vector3d RecordedUp(const std::vector<Rigid3d>& w2c) {
  const Eigen::Vector3d sum = UpSum(w2c);
  if (w2c.empty() || sum.norm() < 1e-6 * static_cast<double>(w2c.size()))
    throw Error("the recorded cameras give no up direction");
  return sum.normalized();
}

RoadFrame FrameAtCamera(const Rigid3d& w2c, const Eigen::Vector3d& up, double scale) {
  RoadFrame f;
  f.origin = w2c.Centre();
  f.up = up;
  f.scale = scale;
  const Eigen::Vector3d view = w2c.q.normalized().toRotationMatrix().row(2).transpose();
  const Eigen::Vector3d level = view - view.dot(up) * up;
  if (level.norm() < 1e-6) throw Error("the start camera looks straight up or down");
  f.x_axis = level.normalized();
  f.y_axis = up.cross(f.x_axis);
  return f;
}

PlanarPose PlanarCamera(const RoadFrame& frame, const Rigid3d& w2c) {
  const Eigen::Vector2d xy = frame.ToPlane(w2c.Centre());
  PlanarPose p;
  p.x = xy.x();
  p.y = xy.y();
  p.heading = frame.Heading(w2c.q.normalized().toRotationMatrix().row(2).transpose());
  return p;
}

std::vector<double> CameraHeights(const MeshRaycaster& mesh, const std::vector<Rigid3d>& w2c,
                                  const Eigen::Vector3d& up) {
  std::vector<double> h;
  for (const Rigid3d& p : w2c)
    if (const auto hit = mesh.Closest(p.Centre(), -up, 0, 1e6)) h.push_back(hit->t);
  return h;
}

PlanarPose RearAxleUnder(const PlanarPose& foot, const CarGeometry& car) {
  const double c = std::cos(foot.heading), s = std::sin(foot.heading);
  const double ox = car.camera_offset.x(), oy = car.camera_offset.y();
  return {foot.x - ox * c + oy * s, foot.y - ox * s - oy * c, foot.heading};
}

GroundPlacer::GroundPlacer(const MeshRaycaster& mesh, const RoadFrame& frame,
                           const CarGeometry& car)
    : mesh_(&mesh), frame_(frame), car_(car) {}

void GroundPlacer::StartFromGround(double height) {
  first_ = false;
  std::fill(last_, last_ + 4, height);
}

Placement GroundPlacer::Place(const PlanarPose& rear, double time) {
  static const char* kWheel[4] = {"rear-left", "rear-right", "front-left", "front-right"};
  const Eigen::Vector2d f(std::cos(rear.heading), std::sin(rear.heading));
  const Eigen::Vector2d l(-f.y(), f.x());
  const Eigen::Vector2d r0(rear.x, rear.y);
  const double half = car_.track / 2, L = car_.wheelbase;
  const Eigen::Vector2d wheel[4] = {r0 + half * l, r0 - half * l, r0 + L * f + half * l,
                                    r0 + L * f - half * l};
  double h[4];
  for (int k = 0; k < 4; ++k) {
    const double start = first_ ? 0.0 : last_[k] + kClearance;
    const Eigen::Vector3d o = frame_.ToWorld(wheel[k].x(), wheel[k].y(), start);
    const double reach = (first_ ? kMaxDrop : kClearance + kMaxDrop) * frame_.scale;
    const auto hit = mesh_->Closest(o, -frame_.up, 0, reach);
    if (!hit) {
      char where[160];
      std::snprintf(where, sizeof where, " wheel at x = %.2f, y = %.2f m from the start",
                    wheel[k].x(), wheel[k].y());
      throw Error("leaves the mesh at t = " + Seconds(time) + " s: no surface under the " +
                  kWheel[k] + where);
    }
    h[k] = start - hit->t / frame_.scale;
  }
  first_ = false;
  std::copy(h, h + 4, last_);
  const double pitch_slope = ((h[2] + h[3]) - (h[0] + h[1])) / (2 * L);
  const double roll_slope = ((h[0] + h[2]) - (h[1] + h[3])) / (2 * car_.track);
  const Eigen::Vector3d up = frame_.up;
  const Eigen::Vector3d F = (frame_.Direction(rear.heading) + pitch_slope * up).normalized();
  Eigen::Vector3d Lw = frame_.Direction(rear.heading + M_PI / 2) + roll_slope * up;
  Lw = (Lw - Lw.dot(F) * F).normalized();
  const Eigen::Vector3d U = F.cross(Lw);
  Placement p;
  p.pitch = std::atan(pitch_slope);
  p.roll = std::atan(roll_slope);
  p.rear_ground = frame_.ToWorld(rear.x, rear.y, 0.5 * (h[0] + h[1]));
  const Eigen::Vector3d& o = car_.camera_offset;
  Eigen::Matrix3d R;
  R.col(0) = -Lw;
  R.col(1) = -U;
  R.col(2) = F;
  p.camera_to_world.q = Eigen::Quaterniond(R).normalized();
  p.camera_to_world.t = p.rear_ground + frame_.scale * (o.x() * F + o.y() * Lw + o.z() * U);
  return p;
}

}  // namespace mvtm
