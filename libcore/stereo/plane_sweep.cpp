#include "stereo/plane_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "base/error.h"

namespace mvtm {

namespace {

constexpr float kNoScore = -2.f;  // below every ZNCC: "this neighbour / plane says nothing"

// The neighbour's pose relative to the reference: x_nb = R x_ref + t.
void RelativePose(const StereoView& ref, const StereoView& nb, Eigen::Matrix3d& R,
                  Eigen::Vector3d& t) {
  R = nb.world_to_camera.R() * ref.world_to_camera.R().transpose();
  t = nb.world_to_camera.t - R * ref.world_to_camera.t;
}

// Window mean and standard deviation of an image (box filter, reflected borders).
void WindowStats(const cv::Mat& I, int win, cv::Mat& mean, cv::Mat& sd) {
  cv::Mat sq;
  cv::boxFilter(I, mean, CV_32F, {win, win}, {-1, -1}, true, cv::BORDER_REFLECT);
  cv::boxFilter(I.mul(I), sq, CV_32F, {win, win}, {-1, -1}, true, cv::BORDER_REFLECT);
  cv::Mat var = sq - mean.mul(mean);
  cv::max(var, 0.0, var);
  cv::sqrt(var, sd);
}

// n·r for the ray r = K⁻¹(u, v, 1) through the centre of each pixel (COLMAP pixel coordinates).
cv::Mat RayDot(const Camera& cam, const Eigen::Vector3d& n, int w, int h) {
  cv::Mat out(h, w, CV_32F);
  const double ax = n.x() / cam.fx(), ay = n.y() / cam.fy();
  const double c0 = n.z() - ax * cam.cx() - ay * cam.cy();
  for (int y = 0; y < h; ++y) {
    float* row = out.ptr<float>(y);
    for (int x = 0; x < w; ++x) row[x] = static_cast<float>(c0 + ax * (x + 0.5) + ay * (y + 0.5));
  }
  return out;
}

struct RefWindows {
  cv::Mat mean, sd;
  int win = 7;
};

// ZNCC of the reference with the warped neighbour J; kNoScore where the window is not wholly
// seen by the neighbour (`seen` < 1) or J is flat there.
cv::Mat Zncc(const cv::Mat& I, const RefWindows& r, const cv::Mat& J, const cv::Mat& seen) {
  const cv::Size k(r.win, r.win);
  cv::Mat mJ, mJJ, mIJ, cover;
  cv::boxFilter(J, mJ, CV_32F, k, {-1, -1}, true, cv::BORDER_REFLECT);
  cv::boxFilter(J.mul(J), mJJ, CV_32F, k, {-1, -1}, true, cv::BORDER_REFLECT);
  cv::boxFilter(I.mul(J), mIJ, CV_32F, k, {-1, -1}, true, cv::BORDER_REFLECT);
  cv::boxFilter(seen, cover, CV_32F, k, {-1, -1}, true, cv::BORDER_CONSTANT);
  cv::Mat out(I.size(), CV_32F);
  for (int y = 0; y < I.rows; ++y) {
    const float *a = r.mean.ptr<float>(y), *sa = r.sd.ptr<float>(y), *b = mJ.ptr<float>(y);
    const float *bb = mJJ.ptr<float>(y), *ab = mIJ.ptr<float>(y), *c = cover.ptr<float>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < I.cols; ++x) {
      const float var_b = bb[x] - b[x] * b[x];
      if (c[x] < 0.999f || var_b <= 1e-6f || sa[x] <= 1e-3f) {
        o[x] = kNoScore;
        continue;
      }
      const float v = (ab[x] - a[x] * b[x]) / (sa[x] * std::sqrt(var_b));
      o[x] = std::max(-1.f, std::min(1.f, v));
    }
  }
  return out;
}

// OpenCV pixel coordinates have the top-left pixel centre at (0, 0), COLMAP's at (0.5, 0.5).
cv::Matx33d ToOpenCv(const Eigen::Matrix3d& H) {
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity(), Si = Eigen::Matrix3d::Identity();
  S(0, 2) = S(1, 2) = -0.5;
  Si(0, 2) = Si(1, 2) = 0.5;
  const Eigen::Matrix3d G = S * H * Si;
  return cv::Matx33d(G(0, 0), G(0, 1), G(0, 2), G(1, 0), G(1, 1), G(1, 2), G(2, 0), G(2, 1),
                     G(2, 2));
}

// The neighbour's ZNCC with the reference on one plane; kNoScore where the neighbour does not
// see the plane point in front of it, or the homography is singular (the plane passes through
// the neighbour's centre).
cv::Mat NeighbourScore(const StereoView& ref, const RefWindows& rw, const StereoView& nb,
                       const Eigen::Vector3d& n, double d) {
  const Eigen::Matrix3d H = PlaneHomography(ref, nb, n, d);
  const double scale = H.norm();
  if (!std::isfinite(scale) || scale == 0 ||
      std::abs(H.determinant()) < 1e-12 * scale * scale * scale)
    return cv::Mat(ref.grey.size(), CV_32F, cv::Scalar(kNoScore));
  const cv::Matx33d G = ToOpenCv(H);
  const cv::Mat ones(nb.grey.size(), CV_32F, cv::Scalar(1));
  cv::Mat J, seen;
  cv::warpPerspective(nb.grey, J, G, ref.grey.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, 0);
  cv::warpPerspective(ones, seen, G, ref.grey.size(), cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, 0);
  // The point must lie in front of the neighbour: its depth there is z_ref · w, w the third
  // homogeneous coordinate (K's last row is 0 0 1), and z_ref > 0 is checked by the caller.
  for (int y = 0; y < seen.rows; ++y) {
    float* s = seen.ptr<float>(y);
    for (int x = 0; x < seen.cols; ++x)
      if (G(2, 0) * x + G(2, 1) * y + G(2, 2) <= 0) s[x] = 0;
  }
  return Zncc(ref.grey, rw, J, seen);
}

// Mean of the best k of the scores in `v` (reordered), or kNoScore when fewer than k say
// something.
float MeanOfBestK(std::vector<float>& v, int k) {
  if (int(v.size()) < k) return kNoScore;
  std::partial_sort(v.begin(), v.begin() + k, v.end(), std::greater<float>());
  if (!(v[size_t(k) - 1] > kNoScore)) return kNoScore;
  float sum = 0;
  for (int j = 0; j < k; ++j) sum += v[size_t(j)];
  return sum / float(k);
}

// Mean of the best k scores per pixel (kNoScore when fewer than k neighbours say something).
cv::Mat BestK(const std::vector<cv::Mat>& scores, int k) {
  const cv::Size sz = scores.front().size();
  cv::Mat out(sz, CV_32F);
  std::vector<float> v(scores.size());
  for (int y = 0; y < sz.height; ++y)
    for (int x = 0; x < sz.width; ++x) {
      for (size_t j = 0; j < scores.size(); ++j) v[j] = scores[j].at<float>(y, x);
      out.at<float>(y, x) = MeanOfBestK(v, k);
    }
  return out;
}

// The aggregated score of every plane of a family (planes in parallel).
std::vector<cv::Mat> FamilyScores(const StereoView& ref, const RefWindows& rw,
                                  const std::vector<StereoView>& nbs, const SweepFamily& f,
                                  const cv::Mat& ray_dot, int k) {
  std::vector<cv::Mat> out(f.offsets.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(f.offsets.size())), [&](const cv::Range& range) {
    for (int p = range.start; p < range.end; ++p) {
      const double d = f.offsets[size_t(p)];
      std::vector<cv::Mat> per;
      if (d != 0)
        for (const StereoView& nb : nbs) per.push_back(NeighbourScore(ref, rw, nb, f.normal, d));
      cv::Mat s =
          per.empty() ? cv::Mat(ref.grey.size(), CV_32F, cv::Scalar(kNoScore)) : BestK(per, k);
      // Only planes in front of the reference camera: z = d / (n·r) > 0.
      for (int y = 0; y < s.rows; ++y)
        for (int x = 0; x < s.cols; ++x)
          if (!(d / ray_dot.at<float>(y, x) > 0)) s.at<float>(y, x) = kNoScore;
      out[size_t(p)] = s;
    }
  });
  return out;
}

// Per pixel, the family's best plane refined by a parabola through its neighbours' scores; keeps
// it where it beats `best` (depth and score of the best family so far).
// The peak of the parabola through scores a, b, c at steps -1, 0, +1 (b the best), in steps,
// within ±0.5; 0 when a side has no score or the three do not make a maximum.
double ParabolaPeak(double a, double b, double c) {
  const double den = a - 2.0 * b + c;
  if (!(a > kNoScore && c > kNoScore && den < 0)) return 0;
  return std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
}

struct Winners {
  cv::Mat z, score, margin;  // CV_32F: depth (+inf: none), aggregated ZNCC, margin
  cv::Mat family;            // CV_32S: index of the winning family (-1: none)
  cv::Mat param;             // CV_64F: its plane parameter (offset, or 1/offset for fronto)
};

// The parameter that spaces a family's planes evenly (inverse depth for fronto planes).
double FamilyParam(const SweepFamily& f, size_t p) {
  return f.inverse_spacing ? 1.0 / f.offsets[p] : f.offsets[p];
}

void TakeBest(const SweepFamily& f, int fi, const std::vector<cv::Mat>& scores,
              const cv::Mat& ray_dot, Winners& w) {
  cv::Mat &best_z = w.z, &best_s = w.score, &best_margin = w.margin;
  const int P = static_cast<int>(scores.size());
  auto param = [&](int p) { return FamilyParam(f, size_t(p)); };
  for (int y = 0; y < best_z.rows; ++y)
    for (int x = 0; x < best_z.cols; ++x) {
      int bp = -1, n = 0;
      float bs = kNoScore;
      double sum = 0;
      for (int p = 0; p < P; ++p) {
        const float v = scores[size_t(p)].at<float>(y, x);
        if (v > kNoScore) sum += v, ++n;
        if (v > bs) bs = v, bp = p;
      }
      if (bp < 0 || bs <= best_s.at<float>(y, x)) continue;
      double s = param(bp);
      if (bp > 0 && bp + 1 < P) {
        const double delta = ParabolaPeak(scores[size_t(bp - 1)].at<float>(y, x), bs,
                                          scores[size_t(bp + 1)].at<float>(y, x));
        s += delta * (delta > 0 ? param(bp + 1) - s : s - param(bp - 1));
      }
      const double d = f.inverse_spacing ? 1.0 / s : s;
      const double z = d / ray_dot.at<float>(y, x);
      if (!(z > 0) || !std::isfinite(z)) continue;
      best_z.at<float>(y, x) = static_cast<float>(z);
      best_s.at<float>(y, x) = bs;
      w.family.at<int>(y, x) = fi;
      w.param.at<double>(y, x) = s;
      // How much the best plane stands out from the family's mean: near the epipole of a
      // forward-moving camera every plane warps alike and the match says nothing.
      best_margin.at<float>(y, x) = static_cast<float>(bs - sum / n);
    }
}

// The aggregated ZNCC of one pixel's window on one plane, each neighbour's window warped through
// that plane's homography H = A + b cᵀ / d (A = Kn R Kr⁻¹, b = Kn t, cᵀx = n·ray(x)); the best-k
// mean, or kNoScore when fewer than k neighbours see the whole window in front of them. The
// reference window (reflected at the borders, as the box filters of the sweep) is given.
struct PixelMatcher {
  struct Nb {
    Eigen::Matrix3d A;
    Eigen::Vector3d b;
    const cv::Mat* grey;
  };
  std::vector<Nb> nbs;
  int win = 7, k = 2;

  float Score(const float* ref_win, double ref_mean, double ref_sd, int x0, int y0,
              const Eigen::Vector3d& c, double d, std::vector<float>& scores) const {
    const int r = win / 2, n = win * win;
    scores.clear();
    for (const Nb& nb : nbs) {
      const Eigen::Matrix3d H = nb.A + nb.b * c.transpose() / d;
      const cv::Mat& J = *nb.grey;
      const float wmax = float(J.cols - 1), hmax = float(J.rows - 1);
      double sj = 0, sjj = 0, sij = 0;
      bool ok = true;
      for (int dy = -r, i = 0; dy <= r && ok; ++dy)
        for (int dx = -r; dx <= r; ++dx, ++i) {
          const Eigen::Vector3d q = H * Eigen::Vector3d(x0 + dx + 0.5, y0 + dy + 0.5, 1.0);
          if (!(q.z() > 0)) {
            ok = false;
            break;
          }
          const float u = float(q.x() / q.z() - 0.5), v = float(q.y() / q.z() - 0.5);
          if (!(u >= 0 && v >= 0 && u <= wmax && v <= hmax)) {
            ok = false;
            break;
          }
          const int iu = std::min(int(u), J.cols - 2 < 0 ? 0 : J.cols - 2),
                    iv = std::min(int(v), J.rows - 2 < 0 ? 0 : J.rows - 2);
          const float fu = u - float(iu), fv = v - float(iv);
          const float* row0 = J.ptr<float>(iv);
          const float* row1 = J.ptr<float>(std::min(iv + 1, J.rows - 1));
          const int iu1 = std::min(iu + 1, J.cols - 1);
          const float val = (1 - fv) * ((1 - fu) * row0[iu] + fu * row0[iu1]) +
                            fv * ((1 - fu) * row1[iu] + fu * row1[iu1]);
          sj += val;
          sjj += double(val) * val;
          sij += double(val) * ref_win[i];
        }
      if (!ok) continue;
      const double mj = sj / n, var_j = sjj / n - mj * mj;
      if (var_j <= 1e-6) continue;
      scores.push_back(
          float(std::clamp((sij / n - ref_mean * mj) / (ref_sd * std::sqrt(var_j)), -1.0, 1.0)));
    }
    return MeanOfBestK(scores, k);
  }
};

// Refines every pixel's winning plane on its own: the aggregated score at `steps` sub-steps per
// plane spacing on both sides of the winner, then a parabola through the best and its sides.
void RefineWinners(const StereoView& ref, const std::vector<StereoView>& nbs,
                   const std::vector<SweepFamily>& fams, const PlaneSweepOptions& o, int k,
                   const RefWindows& rw, Winners& w) {
  PixelMatcher m;
  m.win = o.window;
  m.k = k;
  const Eigen::Matrix3d Kri = ref.camera.K().inverse();
  for (const StereoView& nb : nbs) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    RelativePose(ref, nb, R, t);
    m.nbs.push_back({nb.camera.K() * R * Kri, nb.camera.K() * t, &nb.grey});
  }
  std::vector<Eigen::Vector3d> cs;
  std::vector<double> spacing;
  for (const SweepFamily& f : fams) {
    cs.push_back(Kri.transpose() * f.normal);
    const size_t P = f.offsets.size();  // a family of fewer than 2 planes has no spacing
    spacing.push_back(P < 2 ? 0.0
                            : std::abs(FamilyParam(f, P - 1) - FamilyParam(f, 0)) / double(P - 1));
  }
  const int steps = o.refine, r = o.window / 2, W = ref.grey.cols, Hh = ref.grey.rows;
  cv::parallel_for_(cv::Range(0, Hh), [&](const cv::Range& rows) {
    std::vector<float> win(size_t(o.window * o.window)), scratch;
    std::vector<float> sc(size_t(2 * steps + 1));
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < W; ++x) {
        const int fi = w.family.at<int>(y, x);
        const float sd = rw.sd.at<float>(y, x);
        // Pixels the thresholds will drop anyway (ambiguous or textureless) are not refined.
        if (fi < 0 || !(sd > 1e-3f) || sd < o.min_texture ||
            w.margin.at<float>(y, x) < o.min_margin)
          continue;
        // The reference window, reflected at the borders as the box filters of the sweep do.
        for (int dy = -r, i = 0; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx, ++i)
            win[size_t(i)] =
                ref.grey.at<float>(cv::borderInterpolate(y + dy, Hh, cv::BORDER_REFLECT),
                                   cv::borderInterpolate(x + dx, W, cv::BORDER_REFLECT));
        const double mean = rw.mean.at<float>(y, x), sdev = sd;
        const SweepFamily& f = fams[size_t(fi)];
        const double p0 = w.param.at<double>(y, x), h = spacing[size_t(fi)] / steps;
        if (!(h > 0)) continue;
        const double ray = cs[size_t(fi)].dot(Eigen::Vector3d(x + 0.5, y + 0.5, 1.0));
        int bj = -1;
        for (int j = 0; j <= 2 * steps; ++j) {
          const double p = p0 + (j - steps) * h, d = f.inverse_spacing ? 1.0 / p : p;
          sc[size_t(j)] = kNoScore;
          if (!(p != 0 && std::isfinite(d) && d / ray > 0)) continue;
          sc[size_t(j)] = m.Score(win.data(), mean, sdev, x, y, cs[size_t(fi)], d, scratch);
          if (sc[size_t(j)] > kNoScore && (bj < 0 || sc[size_t(j)] > sc[size_t(bj)])) bj = j;
        }
        if (bj < 0) continue;
        double p = p0 + (bj - steps) * h;
        if (bj > 0 && bj < 2 * steps)
          p += ParabolaPeak(sc[size_t(bj - 1)], sc[size_t(bj)], sc[size_t(bj + 1)]) * h;
        const double d = f.inverse_spacing ? 1.0 / p : p, z = d / ray;
        if (!(z > 0) || !std::isfinite(z)) continue;
        w.z.at<float>(y, x) = static_cast<float>(z);
        w.score.at<float>(y, x) = sc[size_t(bj)];
      }
  });
}

}  // namespace

void PlaneSweepOptions::Check() const {
  if (window < 3 || window > 31 || window % 2 == 0)
    throw FieldError("window", "must be odd, 3..31");
  if (best_k < 1) throw FieldError("best_k", "must be >= 1");
  if (!(min_score >= -1 && min_score <= 1)) throw FieldError("min_score", "must be in [-1, 1]");
  if (!(min_texture >= 0 && std::isfinite(min_texture)))
    throw FieldError("min_texture", "must be >= 0");
  if (!(min_margin >= 0 && min_margin <= 2)) throw FieldError("min_margin", "must be in [0, 2]");
  if (refine < 0 || refine > 64) throw FieldError("refine", "must be 0..64");
}

SweepFamily MakeFrontoSweep(double near_z, double far_z, int planes) {
  if (!(near_z > 0 && far_z > near_z && planes >= 2))
    throw Error("fronto sweep: need 0 < near < far and >= 2 planes");
  SweepFamily f;
  f.name = "fronto";
  f.inverse_spacing = true;
  for (int i = 0; i < planes; ++i) {
    const double s = 1.0 / far_z + (1.0 / near_z - 1.0 / far_z) * i / (planes - 1);
    f.offsets.push_back(1.0 / s);
  }
  std::sort(f.offsets.begin(), f.offsets.end());
  return f;
}

SweepFamily MakeOffsetSweep(const std::string& name, const Eigen::Vector3d& normal, double lo,
                            double hi, int planes) {
  if (!(hi > lo && planes >= 2 && std::abs(normal.norm() - 1) < 1e-9))
    throw Error(name + " sweep: need lo < hi, a unit normal and >= 2 planes");
  SweepFamily f;
  f.name = name;
  f.normal = normal;
  for (int i = 0; i < planes; ++i) f.offsets.push_back(lo + (hi - lo) * i / (planes - 1));
  return f;
}

Eigen::Matrix3d PlaneHomography(const StereoView& ref, const StereoView& nb,
                                const Eigen::Vector3d& n, double d) {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  RelativePose(ref, nb, R, t);
  const Eigen::Matrix3d M = R + t * n.transpose() / d;
  return nb.camera.K() * M * ref.camera.K().inverse();
}

DepthMap SweepDepth(const StereoView& ref, const std::vector<StereoView>& nbs,
                    const std::vector<SweepFamily>& families, const PlaneSweepOptions& o) {
  o.Check();
  const int w = ref.grey.cols, h = ref.grey.rows;
  if (w != int(ref.camera.width) || h != int(ref.camera.height))
    throw Error("reference image and camera differ in size");
  for (const auto& nb : nbs)
    if (nb.grey.cols != int(nb.camera.width) || nb.grey.rows != int(nb.camera.height))
      throw Error("neighbour image and camera differ in size");
  DepthMap out{Image(w, h, 1, 32, std::numeric_limits<float>::infinity()), Image(w, h, 1, 32, 0.f)};
  const int k = std::min<int>(o.best_k, static_cast<int>(nbs.size()));
  if (k < 1) return out;
  RefWindows rw;
  rw.win = o.window;
  WindowStats(ref.grey, o.window, rw.mean, rw.sd);
  Winners win{cv::Mat(h, w, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity())),
              cv::Mat(h, w, CV_32F, cv::Scalar(kNoScore)), cv::Mat(h, w, CV_32F, cv::Scalar(0)),
              cv::Mat(h, w, CV_32S, cv::Scalar(-1)), cv::Mat(h, w, CV_64F, cv::Scalar(0))};
  for (size_t fi = 0; fi < families.size(); ++fi) {
    const cv::Mat ray_dot = RayDot(ref.camera, families[fi].normal, w, h);
    TakeBest(families[fi], int(fi), FamilyScores(ref, rw, nbs, families[fi], ray_dot, k), ray_dot,
             win);
  }
  if (o.refine > 0) RefineWinners(ref, nbs, families, o, k, rw, win);
  const cv::Mat &best_z = win.z, &best_s = win.score, &best_margin = win.margin;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float s = best_s.at<float>(y, x), margin = best_margin.at<float>(y, x);
      if (s < o.min_score || margin < o.min_margin || rw.sd.at<float>(y, x) < o.min_texture)
        continue;
      out.depth.at(x, y) = best_z.at<float>(y, x);
      out.confidence.at(x, y) = std::clamp(std::min(s, margin), 0.f, 1.f);
    }
  return out;
}

}  // namespace mvtm
