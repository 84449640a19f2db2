#include "scene/upright.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinDepression = 2.0 * kPi / 180;  // below the optical axis
constexpr double kMaxDepression = 60.0 * kPi / 180;
constexpr double kMaxLateral = 2.0;  // |x| ≤ 2·y (camera frame): the plane's support
constexpr double kOwnLane = 1.0;     // |x| ≤ y: the lane under the car, for the height
constexpr size_t kMinOwnLane = 8;
constexpr double kMaxTilt = 25.0 * kPi / 180;  // ground normal from the camera's up
constexpr double kInlierFraction = 0.05;       // of the plane's height below the camera
constexpr size_t kMinInliers = 12;
constexpr double kMinInlierShare = 0.3;
constexpr int kRansacRounds = 300;
constexpr size_t kNeighbours = 3;  // images before and after whose points count too

double Sq(double v) { return v * v; }

// A plane n·p + h = 0 in camera coordinates, n unit and pointing up (n·(0,−1,0) > 0), so h > 0
// is the camera's height above it for a plane below the camera.
struct Plane {
  Eigen::Vector3d n = -Eigen::Vector3d::UnitY();
  double h = 0;
  double Distance(const Eigen::Vector3d& p) const { return std::abs(n.dot(p) + h); }
};

// The least-squares plane through `pts` oriented up; false when degenerate.
bool FitPlane(const std::vector<Eigen::Vector3d>& pts, Plane& out) {
  if (pts.size() < 3) return false;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - c) * (p - c).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU);
  Eigen::Vector3d n = svd.matrixU().col(2);
  if (!n.allFinite() || n.norm() < 0.5) return false;
  n.normalize();
  if (n.y() > 0) n = -n;
  out.n = n;
  out.h = -n.dot(c);
  return true;
}

struct CameraGround {
  bool ok = false;
  Plane plane;
  size_t inliers = 0;
};

// The ground plane under one camera from the points it observes (camera coordinates).
CameraGround GroundUnder(const std::vector<Eigen::Vector3d>& pts, uint32_t seed) {
  CameraGround g;
  if (pts.size() < kMinInliers) return g;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
  const double cos_tilt = std::cos(kMaxTilt);
  // MSAC: each point costs its squared distance, capped at the tolerance, relative to the
  // plane's height (scale-free). Counting inliers alone would favour a plane tilted to take in
  // the pavement beside the road at the edge of the tolerance along with the road itself.
  double best = std::numeric_limits<double>::infinity();
  Plane best_plane;
  bool found = false;
  for (int r = 0; r < kRansacRounds; ++r) {
    const size_t a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    Eigen::Vector3d n = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
    if (n.norm() <= 0) continue;
    n.normalize();
    if (n.y() > 0) n = -n;
    if (-n.y() < cos_tilt) continue;
    Plane pl{n, -n.dot(pts[a])};
    if (pl.h <= 0) continue;  // the plane must lie below the camera
    double cost = 0;
    for (const auto& p : pts) cost += std::min(Sq(pl.Distance(p) / pl.h), Sq(kInlierFraction));
    if (cost < best) {
      best = cost;
      best_plane = pl;
      found = true;
    }
  }
  if (!found) return g;
  // Least squares on the points well inside the tolerance, a few rounds (each refit may move
  // the plane onto more of the road and off what lies beside it).
  Plane pl = best_plane;
  std::vector<Eigen::Vector3d> in;
  for (int round = 0; round < 3; ++round) {
    in.clear();
    for (const auto& p : pts)
      if (pl.Distance(p) < 0.5 * kInlierFraction * pl.h) in.push_back(p);
    Plane refit;
    if (!FitPlane(in, refit) || -refit.n.y() < cos_tilt || refit.h <= 0) break;
    pl = refit;
  }
  in.clear();
  for (const auto& p : pts)
    if (pl.Distance(p) < kInlierFraction * pl.h) in.push_back(p);
  if (in.size() < kMinInliers ||
      static_cast<double>(in.size()) < kMinInlierShare * static_cast<double>(pts.size()))
    return g;
  // The height from the lane under the car alone, along the plane's normal: the wide plane's
  // normal is well supported, but kerbs and pavements beside the road (10–15 cm up) pull its
  // height; the camera height is defined over the asphalt below the camera.
  std::vector<double> lane;
  for (const auto& p : pts) {
    const double h = -pl.n.dot(p);
    if (std::abs(p.x()) <= kOwnLane * p.y() && h > 0.8 * pl.h && h < 1.25 * pl.h) lane.push_back(h);
  }
  if (lane.size() >= kMinOwnLane) pl.h = Median(lane);
  g.ok = true;
  g.plane = pl;
  g.inliers = in.size();
  return g;
}

// The points that may be ground under image `i` of `images` (camera coordinates): observed by it
// or by its neighbours in drive order (a dashcam sees little of the asphalt right under it, its
// neighbours ahead and behind see that stretch at a better angle), below its optical axis, not
// far to the side.
std::vector<Eigen::Vector3d> GroundCandidates(const Reconstruction& rec,
                                              const std::vector<const ImageRecord*>& images,
                                              size_t i) {
  const ImageRecord& im = *images[i];
  std::vector<uint64_t> ids;
  const size_t lo = i >= kNeighbours ? i - kNeighbours : 0,
               hi = std::min(images.size(), i + kNeighbours + 1);
  for (size_t k = lo; k < hi; ++k)
    for (const Point2D& p2 : images[k]->points2D)
      if (p2.point3D_id != kInvalidPoint3DId) ids.push_back(p2.point3D_id);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<Eigen::Vector3d> pts;
  for (uint64_t id : ids) {
    auto it = rec.points3D.find(id);
    if (it == rec.points3D.end()) continue;
    const Eigen::Vector3d p = im.world_to_camera * it->second.xyz;
    if (p.z() <= 0 || p.y() <= 0) continue;
    const double dep = std::atan2(p.y(), p.z());
    if (dep < kMinDepression || dep > kMaxDepression) continue;
    if (std::abs(p.x()) > kMaxLateral * p.y()) continue;
    pts.push_back(p);
  }
  return pts;
}

}  // namespace

GroundFit FitGround(const Reconstruction& rec) {
  const auto images = rec.ImagesByName();
  if (images.empty()) throw Error("", 0, "the model has no registered image");
  GroundFit fit;
  fit.cameras = images.size();
  Eigen::Vector3d cam_up = Eigen::Vector3d::Zero();
  Eigen::Vector3d ground_up = Eigen::Vector3d::Zero();
  std::vector<double> heights;
  uint32_t seed = 1;
  for (size_t i = 0; i < images.size(); ++i) {
    const ImageRecord* im = images[i];
    const Eigen::Matrix3d Rt = im->world_to_camera.q.normalized().toRotationMatrix().transpose();
    cam_up += Rt * -Eigen::Vector3d::UnitY();
    const CameraGround g = GroundUnder(GroundCandidates(rec, images, i), seed++);
    if (!g.ok) continue;
    ++fit.cameras_with_ground;
    fit.ground_points += g.inliers;
    ground_up += static_cast<double>(g.inliers) * (Rt * g.plane.n);
    heights.push_back(g.plane.h);
  }
  if (cam_up.norm() < 1e-9) throw Error("", 0, "the cameras' up axes cancel out");
  fit.camera_up = cam_up.normalized();
  fit.up = ground_up.norm() > 0 ? ground_up.normalized() : fit.camera_up;
  if (!heights.empty()) {
    fit.camera_height = Median(heights);
    std::vector<double> dev;
    for (double h : heights) dev.push_back(std::abs(h - fit.camera_height));
    fit.height_spread = Median(dev);
  }
  return fit;
}

Sim3 UprightTransform(const Reconstruction& rec, const GroundFit& fit,
                      double camera_height_metres) {
  const auto images = rec.ImagesByName();
  if (images.empty()) throw Error("", 0, "the model has no registered image");
  if (camera_height_metres > 0 && !(fit.camera_height > 0))
    throw Error("", 0,
                "no camera sees the road below it (too few sparse points on the ground): the "
                "camera height cannot give the scale");
  const ImageRecord& first = *images.front();
  const Eigen::Matrix3d Rt = first.world_to_camera.q.normalized().toRotationMatrix().transpose();
  const Eigen::Vector3d centre = -(Rt * first.world_to_camera.t);
  const Eigen::Vector3d z = fit.up.normalized();
  Eigen::Vector3d x = Rt * Eigen::Vector3d::UnitZ();
  x -= x.dot(z) * z;
  if (x.norm() < 1e-6) throw Error("", 0, "the first camera looks straight up or down");
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Sim3 T;
  T.R.row(0) = x.transpose();
  T.R.row(1) = y.transpose();
  T.R.row(2) = z.transpose();
  T.scale = camera_height_metres > 0 ? camera_height_metres / fit.camera_height : 1.0;
  const Eigen::Vector3d origin = centre - fit.camera_height * z;
  T.t = -T.scale * (T.R * origin);
  return T;
}

void TransformModel(Reconstruction& rec, const Sim3& T) {
  for (auto& [id, p] : rec.points3D) p.xyz = T * p.xyz;
  const Eigen::Quaterniond qT(T.R);
  for (auto& [id, im] : rec.images) {
    const Eigen::Quaterniond qi = im.world_to_camera.q.normalized();
    const Eigen::Quaterniond q = (qi * qT.conjugate()).normalized();
    const Eigen::Vector3d t = T.scale * im.world_to_camera.t - (q * T.t);
    im.world_to_camera = Rigid3d(q, t);
  }
}

}  // namespace mvtm
