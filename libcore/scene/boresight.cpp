#include "scene/boresight.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Obs {
  size_t image = 0;                                // index into Problem::R / C / cam
  Eigen::Vector3d ray = Eigen::Vector3d::UnitZ();  // camera frame, z = 1
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
};

struct Problem {
  std::vector<Eigen::Matrix3d> R;  // recorded world-to-camera rotations
  std::vector<Eigen::Vector3d> C;  // centres
  std::vector<const Camera*> cam;
  std::vector<Obs> obs;       // grouped by point
  std::vector<size_t> start;  // point k: obs[start[k] .. start[k + 1])
  size_t Points() const { return start.empty() ? 0 : start.size() - 1; }
};

Eigen::Matrix3d RotationOf(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-300) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// Least squares point of the rays (world directions d through centres), relative to `origin`.
bool Triangulate(const std::vector<Eigen::Vector3d>& d, const std::vector<Eigen::Vector3d>& c_rel,
                 Eigen::Vector3d& x_rel) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < d.size(); ++j) {
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d[j] * d[j].transpose();
    A += P;
    b += P * c_rel[j];
  }
  Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
  if (!lu.isInvertible()) return false;
  x_rel = lu.solve(b);
  return x_rel.allFinite();
}

double MaxRayAngle(const std::vector<Eigen::Vector3d>& d) {
  double best = 0;
  for (size_t j = 1; j < d.size(); ++j)
    best = std::max(best, std::atan2(d[0].cross(d[j]).norm(), d[0].dot(d[j])));
  return best;
}

// Residuals (2 per observation, pixels) with every camera turned by Rb; points triangulated again.
Eigen::VectorXd Residuals(const Problem& p, const Eigen::Matrix3d& Rb, double behind_px) {
  Eigen::VectorXd r(2 * p.obs.size());
  std::vector<Eigen::Vector3d> d, c_rel;
  for (size_t k = 0; k < p.Points(); ++k) {
    const size_t s = p.start[k], e = p.start[k + 1];
    const Eigen::Vector3d& origin = p.C[p.obs[s].image];
    d.clear();
    c_rel.clear();
    for (size_t j = s; j < e; ++j) {
      const Obs& o = p.obs[j];
      d.push_back(((Rb * p.R[o.image]).transpose() * o.ray).normalized());
      c_rel.push_back(p.C[o.image] - origin);
    }
    Eigen::Vector3d x_rel;
    const bool ok = Triangulate(d, c_rel, x_rel);
    for (size_t j = s; j < e; ++j) {
      const Obs& o = p.obs[j];
      const Eigen::Vector3d xc = Rb * p.R[o.image] * (x_rel - c_rel[j - s]);
      if (!ok || !(xc.z() > 0)) {
        r.segment<2>(2 * j).setConstant(behind_px);
        continue;
      }
      r.segment<2>(2 * j) = p.cam[o.image]->Project(xc) - o.uv;
    }
  }
  return r;
}

std::vector<double> Norms(const Eigen::VectorXd& r) {
  std::vector<double> n(r.size() / 2);
  for (size_t j = 0; j < n.size(); ++j) n[j] = r.segment<2>(2 * j).norm();
  return n;
}

double MeanOf(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

double RobustCost(const Eigen::VectorXd& r, double h) {
  double c = 0;
  for (double e : Norms(r)) c += e <= h ? e * e : 2 * h * e - h * h;
  return c;
}

// Observations of the fitted images, grouped by point; outliers at the start dropped.
Problem Gather(const Reconstruction& rec, const BoresightOptions& o, BoresightFit& fit) {
  Problem p;
  std::map<uint32_t, size_t> index;
  for (const auto& [id, im] : rec.images) {
    if (o.exclude.count(im.name)) continue;
    const Camera& cam = rec.cameras.at(im.camera_id);
    cam.RequireUndistorted();
    index[id] = p.R.size();
    p.R.push_back(im.world_to_camera.R());
    p.C.push_back(im.world_to_camera.Centre());
    p.cam.push_back(&cam);
  }
  std::vector<Obs> all;
  std::vector<size_t> all_start{0};
  for (const auto& [pid, pt] : rec.points3D) {
    for (const TrackElement& t : pt.track) {
      const auto it = index.find(t.image_id);
      if (it == index.end()) continue;
      const ImageRecord& im = rec.images.at(t.image_id);
      if (t.point2D_idx >= im.points2D.size()) continue;
      Obs ob;
      ob.image = it->second;
      ob.uv = im.points2D[t.point2D_idx].xy;
      ob.ray = p.cam[ob.image]->Unproject(ob.uv, 1.0);
      all.push_back(ob);
    }
    if (all.size() - all_start.back() < std::max<size_t>(2, o.min_track))
      all.resize(all_start.back());
    else
      all_start.push_back(all.size());
  }
  // Outliers at the recorded attitude, then parallax; a point keeps min_track inliers or goes.
  Problem first = p;
  first.obs = all;
  first.start = all_start;
  const std::vector<double> e0 = Norms(Residuals(first, Eigen::Matrix3d::Identity(), 1e9));
  p.start.push_back(0);
  std::vector<Eigen::Vector3d> d;
  std::vector<bool> used(p.R.size(), false);
  for (size_t k = 0; k + 1 < all_start.size(); ++k) {
    const size_t before = p.obs.size();
    d.clear();
    for (size_t j = all_start[k]; j < all_start[k + 1]; ++j) {
      if (!(e0[j] <= o.max_error_px)) {
        ++fit.outliers;
        continue;
      }
      p.obs.push_back(all[j]);
      d.push_back((p.R[all[j].image].transpose() * all[j].ray).normalized());
    }
    if (p.obs.size() - before < std::max<size_t>(2, o.min_track) ||
        MaxRayAngle(d) < o.min_angle_deg * kPi / 180) {
      p.obs.resize(before);
      continue;
    }
    for (size_t j = before; j < p.obs.size(); ++j) used[p.obs[j].image] = true;
    p.start.push_back(p.obs.size());
  }
  fit.images = std::count(used.begin(), used.end(), true);
  return p;
}

}  // namespace

namespace {

// Gauss-Newton normal equations at w (Huber weights, Jacobian by central differences).
void NormalEquations(const Problem& p, const Eigen::Vector3d& w, const Eigen::VectorXd& r,
                     double behind, double huber, Eigen::Matrix3d& H, Eigen::Vector3d& g) {
  const double eps = 1e-6;
  Eigen::MatrixXd J(r.size(), 3);
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d dw = Eigen::Vector3d::Zero();
    dw[k] = eps;
    J.col(k) =
        (Residuals(p, RotationOf(w + dw), behind) - Residuals(p, RotationOf(w - dw), behind)) /
        (2 * eps);
  }
  Eigen::VectorXd wt(r.size());
  const std::vector<double> n = Norms(r);
  for (size_t j = 0; j < n.size(); ++j)
    wt.segment<2>(2 * j).setConstant(n[j] <= huber ? 1.0 : huber / n[j]);
  H = J.transpose() * wt.asDiagonal() * J;
  g = J.transpose() * wt.asDiagonal() * r;
}

// The eigenvectors of H as columns, the free directions (curvature >= conditioning times the
// largest) first; the frozen ones and the eigenvalues go to fit. Returns the free count.
int FreeDirections(const Eigen::Matrix3d& H, double conditioning, Eigen::Matrix3d& basis,
                   BoresightFit& fit) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H);
  fit.curvature = es.eigenvalues();
  const double top = es.eigenvalues()(2);
  auto is_free = [&](int k) { return top > 0 && es.eigenvalues()(k) >= conditioning * top; };
  int free_dirs = 0;
  for (int k = 2; k >= 0; --k)
    if (is_free(k)) basis.col(free_dirs++) = es.eigenvectors().col(k);
  int f = free_dirs;
  for (int k = 0; k < 3; ++k)
    if (!is_free(k)) {
      basis.col(f++) = es.eigenvectors().col(k);
      fit.frozen.push_back(es.eigenvectors().col(k));
    }
  return free_dirs;
}

// Standard error (degrees) along the least determined of the free directions.
double SigmaDegrees(const std::vector<double>& n, double huber, const Eigen::Matrix3d& H,
                    const Eigen::Matrix3d& basis, int free_dirs) {
  double s2 = 0, wsum = 0;
  for (double e : n) {
    const double wt = e <= huber ? 1.0 : huber / e;
    s2 += wt * e * e;
    wsum += wt;
  }
  s2 /= std::max(1.0, 2 * wsum - free_dirs);
  double sigma = 0;
  for (int k = 0; k < free_dirs; ++k) {
    const double lam = basis.col(k).dot(H * basis.col(k));
    if (lam > 0) sigma = std::max(sigma, std::sqrt(s2 / lam) * 180 / kPi);
  }
  return sigma;
}

}  // namespace

BoresightFit FitBoresight(const Reconstruction& rec, const BoresightOptions& o) {
  BoresightFit fit;
  const Problem p = Gather(rec, o, fit);
  fit.points = p.Points();
  fit.observations = p.obs.size();
  if (fit.points < 10 || fit.images < 2)
    throw Error("boresight: " + std::to_string(fit.points) + " points seen under " +
                std::to_string(o.min_angle_deg) + " degrees of parallax or more by " +
                std::to_string(fit.images) +
                " fitted images: too few to fit a rotation (10 points and 2 images at least)");
  const double behind = 4 * o.max_error_px;  // a point turned behind a camera: a large residual
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  Eigen::VectorXd r = Residuals(p, Eigen::Matrix3d::Identity(), behind);
  fit.mean_before = MeanOf(Norms(r));
  fit.median_before = Median(Norms(r));
  double cost = RobustCost(r, o.huber_px);
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();  // columns: free directions first
  int free_dirs = 3;
  Eigen::Matrix3d H;
  Eigen::Vector3d g;
  for (int it = 0; it < 30; ++it) {
    fit.iterations = it + 1;
    NormalEquations(p, w, r, behind, o.huber_px, H, g);
    if (it == 0) free_dirs = FreeDirections(H, o.conditioning, basis, fit);
    if (free_dirs == 0) break;
    const Eigen::MatrixXd B = basis.leftCols(free_dirs);
    const Eigen::MatrixXd Hs = B.transpose() * H * B;
    const Eigen::VectorXd step = -(B * Hs.ldlt().solve(B.transpose() * g));
    double scale = 1;
    bool better = false;
    for (int halve = 0; halve < 8 && !better; ++halve, scale *= 0.5) {
      const Eigen::Vector3d wn = w + scale * step;
      const Eigen::VectorXd rn = Residuals(p, RotationOf(wn), behind);
      const double cn = RobustCost(rn, o.huber_px);
      if (cn < cost) {
        w = wn;
        r = rn;
        cost = cn;
        better = true;
      }
    }
    if (!better || scale * step.norm() < 1e-10) break;
  }
  fit.rotation = w;
  fit.R = RotationOf(w);
  const std::vector<double> n = Norms(r);
  fit.mean_after = MeanOf(n);
  fit.median_after = Median(n);
  fit.sigma_deg = SigmaDegrees(n, o.huber_px, H, basis, free_dirs);
  return fit;
}

void ApplyBoresight(Reconstruction& rec, const Eigen::Matrix3d& R, double min_angle_deg) {
  std::map<uint32_t, Eigen::Matrix3d> before;
  for (auto& [id, im] : rec.images) {
    const Eigen::Matrix3d Ri = im.world_to_camera.R();
    const Eigen::Vector3d C = im.world_to_camera.Centre();
    before[id] = Ri;
    const Eigen::Matrix3d Rn = R * Ri;
    im.world_to_camera = Rigid3d(NormalizedQuaternion(Eigen::Quaterniond(Rn)), -Rn * C);
  }
  std::vector<Eigen::Vector3d> d, c_rel;
  for (auto& [pid, pt] : rec.points3D) {
    if (pt.track.empty()) continue;
    const auto first = rec.images.find(pt.track[0].image_id);
    if (first == rec.images.end()) continue;
    const Eigen::Vector3d origin = first->second.world_to_camera.Centre();
    // Fixed to its first camera: the same ray and depth there.
    Eigen::Vector3d x_rel =
        first->second.world_to_camera.R().transpose() * (before[first->first] * (pt.xyz - origin));
    // Refined over its track where its rays meet at an angle.
    d.clear();
    c_rel.clear();
    std::vector<std::pair<const ImageRecord*, Eigen::Vector2d>> seen;
    for (const TrackElement& t : pt.track) {
      const auto it = rec.images.find(t.image_id);
      if (it == rec.images.end() || t.point2D_idx >= it->second.points2D.size()) continue;
      const ImageRecord& im = it->second;
      const Camera& cam = rec.cameras.at(im.camera_id);
      const Eigen::Vector2d uv = im.points2D[t.point2D_idx].xy;
      if (!cam.IsUndistorted()) continue;
      d.push_back((im.world_to_camera.R().transpose() * cam.Unproject(uv, 1.0)).normalized());
      c_rel.push_back(im.world_to_camera.Centre() - origin);
      seen.emplace_back(&im, uv);
    }
    if (seen.size() >= 2 && MaxRayAngle(d) >= min_angle_deg * kPi / 180) {
      for (int it = 0; it < 5; ++it) {
        Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
        Eigen::Vector3d g = Eigen::Vector3d::Zero();
        for (size_t j = 0; j < seen.size(); ++j) {
          const Camera& cam = rec.cameras.at(seen[j].first->camera_id);
          const Eigen::Matrix3d Rj = seen[j].first->world_to_camera.R();
          const Eigen::Vector3d xc = Rj * (x_rel - c_rel[j]);
          if (!(xc.z() > 0)) continue;
          const Eigen::Vector2d res = cam.Project(xc) - seen[j].second;
          Eigen::Matrix<double, 2, 3> dp;
          dp << cam.fx() / xc.z(), 0, -cam.fx() * xc.x() / (xc.z() * xc.z()), 0, cam.fy() / xc.z(),
              -cam.fy() * xc.y() / (xc.z() * xc.z());
          const Eigen::Matrix<double, 2, 3> Jx = dp * Rj;
          H += Jx.transpose() * Jx;
          g += Jx.transpose() * res;
        }
        Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
        if (!lu.isInvertible()) break;
        const Eigen::Vector3d step = -lu.solve(g);
        if (!step.allFinite()) break;
        x_rel += step;
        if (step.norm() < 1e-12 * (1 + x_rel.norm())) break;
      }
    }
    pt.xyz = origin + x_rel;
    double sum = 0;
    size_t cnt = 0;
    for (size_t j = 0; j < seen.size(); ++j) {
      const Camera& cam = rec.cameras.at(seen[j].first->camera_id);
      const Eigen::Vector3d xc = seen[j].first->world_to_camera.R() * (x_rel - c_rel[j]);
      if (!(xc.z() > 0)) continue;
      sum += (cam.Project(xc) - seen[j].second).norm();
      ++cnt;
    }
    if (cnt > 0) pt.error = sum / cnt;
  }
}

}  // namespace mvtm
