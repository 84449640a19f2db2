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

// The largest angle between any two of the rays (unit directions).
double MaxRayAngle(const std::vector<Eigen::Vector3d>& d) {
  double best = 0;
  for (size_t i = 0; i < d.size(); ++i)
    for (size_t j = i + 1; j < d.size(); ++j)
      best = std::max(best, std::atan2(d[i].cross(d[j]).norm(), d[i].dot(d[j])));
  return best;
}

size_t DistinctImages(const std::vector<Obs>& obs, size_t s, size_t e) {
  std::vector<size_t> ims;
  for (size_t j = s; j < e; ++j) ims.push_back(obs[j].image);
  std::sort(ims.begin(), ims.end());
  return static_cast<size_t>(std::unique(ims.begin(), ims.end()) - ims.begin());
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

// Huber's loss of a residual norm e with scale h (e^2 inside, linear outside), and the weight
// that makes weighted least squares minimise it.
double HuberCost(double e, double h) { return e <= h ? e * e : 2 * h * e - h * h; }
double HuberWeight(double e, double h) { return e <= h ? 1.0 : h / e; }

double RobustCost(const Eigen::VectorXd& r, double h) {
  double c = 0;
  for (double e : Norms(r)) c += HuberCost(e, h);
  return c;
}

// Observations of the fitted images, grouped by point; outliers (judged with every camera turned
// by R0) dropped, then points without min_track images or without parallax.
Problem Gather(const Reconstruction& rec, const BoresightOptions& o, const Eigen::Matrix3d& R0,
               BoresightFit& fit) {
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
  const size_t need = std::max<size_t>(2, o.min_track);
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
    if (DistinctImages(all, all_start.back(), all.size()) < need)
      all.resize(all_start.back());
    else
      all_start.push_back(all.size());
  }
  Problem first = p;
  first.obs = all;
  first.start = all_start;
  const std::vector<double> e0 = Norms(Residuals(first, R0, 1e9));
  p.start.push_back(0);
  std::vector<Eigen::Vector3d> d;
  std::vector<bool> used(p.R.size(), false);
  fit.outliers = 0;
  for (size_t k = 0; k + 1 < all_start.size(); ++k) {
    const size_t before = p.obs.size();
    size_t outliers = 0;
    d.clear();
    for (size_t j = all_start[k]; j < all_start[k + 1]; ++j) {
      if (!(e0[j] <= o.max_error_px)) {
        ++outliers;
        continue;
      }
      p.obs.push_back(all[j]);
      d.push_back(((R0 * p.R[all[j].image]).transpose() * all[j].ray).normalized());
    }
    if (DistinctImages(p.obs, before, p.obs.size()) < need ||
        MaxRayAngle(d) < o.min_angle_deg * kPi / 180) {
      p.obs.resize(before);
      continue;
    }
    fit.outliers += outliers;
    for (size_t j = before; j < p.obs.size(); ++j) used[p.obs[j].image] = true;
    p.start.push_back(p.obs.size());
  }
  fit.images = std::count(used.begin(), used.end(), true);
  return p;
}

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
  for (size_t j = 0; j < n.size(); ++j) wt.segment<2>(2 * j).setConstant(HuberWeight(n[j], huber));
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

// Standard error (degrees) of the rotation along its least determined free direction: the
// Huber-weighted residual variance (each point's three coordinates and the free directions
// counted as spent) times the largest eigenvalue of the inverse normal matrix on the free
// directions.
double SigmaDegrees(const std::vector<double>& n, double huber, const Eigen::Matrix3d& H,
                    const Eigen::Matrix3d& basis, int free_dirs, size_t points) {
  if (free_dirs == 0) return 0;
  double s2 = 0, wsum = 0;
  for (double e : n) {
    const double wt = HuberWeight(e, huber);
    s2 += wt * e * e;
    wsum += wt;
  }
  s2 /= std::max(1.0, 2 * wsum - 3.0 * points - free_dirs);
  const Eigen::MatrixXd B = basis.leftCols(free_dirs);
  const Eigen::MatrixXd Hs = B.transpose() * H * B;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hs);
  const double lam = es.eigenvalues()(0);
  return lam > 0 ? std::sqrt(s2 / lam) * 180 / kPi : 0;
}

// Gauss-Newton (with step halving) from w along the free columns of basis; r holds the
// residuals at w on entry and at the returned rotation on exit.
Eigen::Vector3d Solve(const Problem& p, Eigen::Vector3d w, Eigen::VectorXd& r,
                      const Eigen::Matrix3d& basis, int free_dirs, double behind, double huber,
                      int& iterations) {
  if (free_dirs == 0) return w;
  double cost = RobustCost(r, huber);
  const Eigen::MatrixXd B = basis.leftCols(free_dirs);
  for (int it = 0; it < 30; ++it) {
    ++iterations;
    Eigen::Matrix3d H;
    Eigen::Vector3d g;
    NormalEquations(p, w, r, behind, huber, H, g);
    const Eigen::MatrixXd Hs = B.transpose() * H * B;
    const Eigen::VectorXd step = -(B * Hs.ldlt().solve(B.transpose() * g));
    double taken = 0;
    for (double scale = 1; scale > 1e-3 && taken == 0; scale *= 0.5) {
      const Eigen::Vector3d wn = w + scale * step;
      const Eigen::VectorXd rn = Residuals(p, RotationOf(wn), behind);
      const double cn = RobustCost(rn, huber);
      if (cn < cost) {
        w = wn;
        r = rn;
        cost = cn;
        taken = scale;
      }
    }
    if (taken == 0 || taken * step.norm() < 1e-10) break;
  }
  return w;
}

void Require(const BoresightFit& fit, const BoresightOptions& o) {
  if (fit.points < 10 || fit.images < 2)
    throw Error("boresight: " + std::to_string(fit.points) + " points seen under " +
                std::to_string(o.min_angle_deg) + " degrees of parallax or more by " +
                std::to_string(fit.images) +
                " fitted images: too few to fit a rotation (10 points and 2 images at least)");
}

}  // namespace

BoresightFit FitBoresight(const Reconstruction& rec, const BoresightOptions& o) {
  BoresightFit fit;
  const double behind = 4 * o.max_error_px;  // a point turned behind a camera: a large residual
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // First pass: outliers judged at the recorded attitude; the free directions from the normal
  // matrix there.
  const Problem p0 = Gather(rec, o, I, fit);
  fit.points = p0.Points();
  Require(fit, o);
  Eigen::Matrix3d H;
  Eigen::Vector3d g;
  Eigen::VectorXd r = Residuals(p0, I, behind);
  NormalEquations(p0, Eigen::Vector3d::Zero(), r, behind, o.huber_px, H, g);
  Eigen::Matrix3d basis = I;  // columns: free directions first
  const int free_dirs = FreeDirections(H, o.conditioning, basis, fit);
  const Eigen::Vector3d w1 =
      Solve(p0, Eigen::Vector3d::Zero(), r, basis, free_dirs, behind, o.huber_px, fit.iterations);
  // Second pass: outliers judged again at the fitted attitude (the mount error itself can put
  // good observations over max_error_px at the recorded one), solved from there.
  const Problem p = Gather(rec, o, RotationOf(w1), fit);
  fit.points = p.Points();
  fit.observations = p.obs.size();
  Require(fit, o);
  r = Residuals(p, RotationOf(w1), behind);
  const Eigen::Vector3d w = Solve(p, w1, r, basis, free_dirs, behind, o.huber_px, fit.iterations);
  fit.rotation = w;
  fit.R = RotationOf(w);
  const std::vector<double> n0 = Norms(Residuals(p, I, behind));
  fit.mean_before = MeanOf(n0);
  fit.median_before = Median(n0);
  const std::vector<double> n = Norms(r);
  fit.mean_after = MeanOf(n);
  fit.median_after = Median(n);
  NormalEquations(p, w, r, behind, o.huber_px, H, g);
  fit.sigma_deg = SigmaDegrees(n, o.huber_px, H, basis, free_dirs, fit.points);
  fit.applied = fit.median_before - fit.median_after >= o.min_gain * fit.median_before &&
                fit.rotation.norm() > 0;
  return fit;
}

namespace {

struct Seen {
  const Camera* cam;
  Eigen::Matrix3d R;      // world-to-camera rotation (turned)
  Eigen::Vector3d c_rel;  // centre relative to the point's origin
  Eigen::Vector2d uv;
};

// Huber (1 px) reprojection cost of a point over its observations; points behind count 1e6.
double PointCost(const std::vector<Seen>& seen, const Eigen::Vector3d& x_rel) {
  double c = 0;
  for (const Seen& s : seen) {
    const Eigen::Vector3d xc = s.R * (x_rel - s.c_rel);
    if (!(xc.z() > 0)) return 1e6 * seen.size();
    const double e = (s.cam->Project(xc) - s.uv).norm();
    c += HuberCost(e, 1);
  }
  return c;
}

// Gauss-Newton on the point's Huber-weighted reprojection error; a step is kept only when it
// lowers the cost.
void RefinePoint(const std::vector<Seen>& seen, Eigen::Vector3d& x_rel) {
  double cost = PointCost(seen, x_rel);
  for (int it = 0; it < 8; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const Seen& s : seen) {
      const Eigen::Vector3d xc = s.R * (x_rel - s.c_rel);
      if (!(xc.z() > 0)) return;
      const Eigen::Vector2d res = s.cam->Project(xc) - s.uv;
      const double wt = HuberWeight(res.norm(), 1);
      Eigen::Matrix<double, 2, 3> dp;
      dp << s.cam->fx() / xc.z(), 0, -s.cam->fx() * xc.x() / (xc.z() * xc.z()), 0,
          s.cam->fy() / xc.z(), -s.cam->fy() * xc.y() / (xc.z() * xc.z());
      const Eigen::Matrix<double, 2, 3> Jx = dp * s.R;
      H += wt * Jx.transpose() * Jx;
      g += wt * Jx.transpose() * res;
    }
    Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
    if (!lu.isInvertible()) return;
    const Eigen::Vector3d step = -lu.solve(g);
    if (!step.allFinite()) return;
    const double c = PointCost(seen, x_rel + step);
    if (!(c < cost)) return;
    x_rel += step;
    cost = c;
    if (step.norm() < 1e-12 * (1 + x_rel.norm())) return;
  }
}

}  // namespace

void ApplyBoresight(Reconstruction& rec, const Eigen::Matrix3d& R, double min_angle_deg) {
  std::map<uint32_t, Eigen::Matrix3d> before;
  for (auto& [id, im] : rec.images) {
    const Eigen::Matrix3d Ri = im.world_to_camera.R();
    const Eigen::Vector3d C = im.world_to_camera.Centre();
    before[id] = Ri;
    const Eigen::Matrix3d Rn = R * Ri;
    im.world_to_camera = Rigid3d(NormalizedQuaternion(Eigen::Quaterniond(Rn)), -Rn * C);
  }
  std::vector<Eigen::Vector3d> d;
  std::vector<Seen> seen;
  for (auto& [pid, pt] : rec.points3D) {
    // Its origin: the first camera of its track that the model has.
    const ImageRecord* first = nullptr;
    for (const TrackElement& t : pt.track) {
      const auto it = rec.images.find(t.image_id);
      if (it != rec.images.end()) {
        first = &it->second;
        break;
      }
    }
    if (!first) continue;
    const Eigen::Vector3d origin = first->world_to_camera.Centre();
    // Fixed to that camera: the same ray and depth there.
    Eigen::Vector3d x_rel =
        first->world_to_camera.R().transpose() * (before[first->id] * (pt.xyz - origin));
    d.clear();
    seen.clear();
    for (const TrackElement& t : pt.track) {
      const auto it = rec.images.find(t.image_id);
      if (it == rec.images.end() || t.point2D_idx >= it->second.points2D.size()) continue;
      const ImageRecord& im = it->second;
      const Camera& cam = rec.cameras.at(im.camera_id);
      if (!cam.IsUndistorted()) continue;
      const Eigen::Vector2d uv = im.points2D[t.point2D_idx].xy;
      const Eigen::Matrix3d Rj = im.world_to_camera.R();
      d.push_back((Rj.transpose() * cam.Unproject(uv, 1.0)).normalized());
      seen.push_back({&cam, Rj, im.world_to_camera.Centre() - origin, uv});
    }
    // Refined over its track where its rays meet at an angle.
    if (seen.size() >= 2 && MaxRayAngle(d) >= min_angle_deg * kPi / 180) RefinePoint(seen, x_rel);
    pt.xyz = origin + x_rel;
    double sum = 0;
    size_t cnt = 0;
    for (const Seen& s : seen) {
      const Eigen::Vector3d xc = s.R * (x_rel - s.c_rel);
      if (!(xc.z() > 0)) continue;
      sum += (s.cam->Project(xc) - s.uv).norm();
      ++cnt;
    }
    if (cnt > 0) pt.error = sum / cnt;
  }
}

}  // namespace mvtm
