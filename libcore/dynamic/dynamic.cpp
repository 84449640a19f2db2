#include "dynamic/dynamic.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <opencv2/ximgproc/segmentation.hpp>
#include <string>
#include <utility>

#include "base/error.h"

namespace mvtm {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A depth map's convention: +inf, NaN and <= 0 are "no depth".
bool HasDepth(double z) { return z > 0 && std::isfinite(z); }

// Non-zero where `depth` (CV_32F) has a depth: above 0 and finite.
cv::Mat HasDepthMask(const cv::Mat& depth) {
  return (depth > 0) & (depth < std::numeric_limits<float>::infinity());
}

void CheckView(const DynamicView& v, const char* what) {
  v.camera.RequireUndistorted();
  const int w = static_cast<int>(v.camera.width), h = static_cast<int>(v.camera.height);
  const auto ok = [&](const cv::Mat& m) {
    return m.type() == CV_32F && m.cols == w && m.rows == h;
  };
  if (!ok(v.grey) || !ok(v.depth))
    throw Error(std::string(what) + ": luma and depth must be float images of the camera's size " +
                std::to_string(w) + "x" + std::to_string(h));
  if (!v.colour.empty() && (v.colour.type() != CV_8UC3 || v.colour.size() != v.grey.size()))
    throw Error(std::string(what) + ": the colour image must be 8-bit RGB of the luma's size");
  if (!v.dynamic.empty() && !ok(v.dynamic))
    throw Error(std::string(what) +
                ": the first-pass probability must be float of the luma's size");
  if (!v.seen.empty() && !ok(v.seen))
    throw Error(std::string(what) + ": the seen depth must be float of the luma's size");
  if (!v.guessed.empty() && (v.guessed.type() != CV_8U || v.guessed.size() != v.grey.size()))
    throw Error(std::string(what) + ": the guessed-depth mask must be 8-bit of the luma's size");
}

// Where each target pixel lands in `nb` (map_x, map_y; NaN when not valid there).
void WarpMaps(const DynamicView& t, const DynamicView& nb, double tol, cv::Mat& mx, cv::Mat& my,
              cv::Mat& coarser, cv::Mat& motion) {
  const Rigid3d t2n = nb.world_to_camera * t.world_to_camera.Inverse();
  const Eigen::Matrix3d R = t2n.R();
  const Eigen::Vector3d tr = t2n.t;
  const double fx = t.camera.fx(), fy = t.camera.fy(), cx = t.camera.cx(), cy = t.camera.cy();
  const double gx = nb.camera.fx(), gy = nb.camera.fy(), hx = nb.camera.cx(), hy = nb.camera.cy();
  const int nw = nb.depth.cols, nh = nb.depth.rows;
  mx.create(t.depth.size(), CV_32F);
  my.create(t.depth.size(), CV_32F);
  coarser = cv::Mat::ones(t.depth.size(), CV_32F);
  motion = cv::Mat::zeros(t.depth.size(), CV_32F);
  cv::parallel_for_(cv::Range(0, t.depth.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float* z = t.depth.ptr<float>(y);
      float* ox = mx.ptr<float>(y);
      float* oy = my.ptr<float>(y);
      for (int x = 0; x < t.depth.cols; ++x) {
        ox[x] = oy[x] = kNaN;
        const double d = z[x];
        if (!HasDepth(d) || d < nb.beyond) continue;
        const Eigen::Vector3d pc((x + 0.5 - cx) / fx * d, (y + 0.5 - cy) / fy * d, d);
        const Eigen::Vector3d q = R * pc + tr;
        if (!(q.z() > 0)) continue;
        const double u = gx * q.x() / q.z() + hx, v = gy * q.y() / q.z() + hy;
        if (!(u >= 0.5 && v >= 0.5 && u <= nw - 0.5 && v <= nh - 0.5)) continue;
        const int iu = std::min(nw - 1, static_cast<int>(u)),
                  iv = std::min(nh - 1, static_cast<int>(v));
        // Hidden in nb behind a surface of this depth map (empty: none).
        const auto nearer = [&](const cv::Mat& map) {
          if (map.empty()) return false;
          const float dn = map.at<float>(iv, iu);
          return HasDepth(dn) && dn < q.z() * (1 - tol);
        };
        // Behind the static surface, or behind what nb saw there (a parked vehicle).
        if (nearer(nb.depth) || nearer(nb.seen)) continue;
        if (!nb.dynamic.empty() && nb.dynamic.at<float>(iv, iu) >= 0.5f)
          continue;  // hidden in nb by something that moves
        // How much coarser the neighbour sees the point (its pixel footprint over the target's).
        coarser.at<float>(y, x) = static_cast<float>((q.z() / gx) / (d / fx));
        motion.at<float>(y, x) = static_cast<float>(std::hypot(u - x - 0.5, v - y - 0.5));
        ox[x] = static_cast<float>(u - 0.5);  // remap's pixel centres are integers
        oy[x] = static_cast<float>(v - 0.5);
      }
    }
  });
}

// The gain that brings `warp` to the target's exposure: exp(median log ratio) over valid pixels
// that are neither black nor saturated in both.
double ExposureGain(const cv::Mat& target, const cv::Mat& warp) {
  std::vector<float> r;
  r.reserve(target.total() / 4);
  for (int y = 0; y < target.rows; y += 2) {
    const float* a = target.ptr<float>(y);
    const float* b = warp.ptr<float>(y);
    for (int x = 0; x < target.cols; x += 2)
      if (a[x] > 0.02f && b[x] > 0.02f && a[x] < 0.98f && b[x] < 0.98f)
        r.push_back(std::log(a[x] / b[x]));
  }
  if (r.size() < 16) return 1;
  std::nth_element(r.begin(), r.begin() + static_cast<long>(r.size() / 2), r.end());
  return std::exp(static_cast<double>(r[r.size() / 2]));
}

// Photometric residual of one neighbour (NaN where not valid), see the header.
cv::Mat Photometric(const cv::Mat& target, const cv::Mat& warp, const cv::Mat& valid,
                    const cv::Mat& coarser, const DynamicOptions& o) {
  const cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, {2 * o.slack + 1, 2 * o.slack + 1});
  cv::Mat lo_in = warp.clone(), hi_in = warp.clone();
  lo_in.setTo(2.0, ~valid);  // invalid pixels never set a bound
  hi_in.setTo(-1.0, ~valid);
  cv::Mat lo, hi;
  cv::erode(lo_in, lo, k);
  cv::dilate(hi_in, hi, k);
  // Where the neighbour saw the surface r times coarser than the target (from farther), its warp
  // is a blurred copy: the target blurred alike (Gaussian sigma 0.5·sqrt(r² − 1), in steps) is
  // compared, so detail the neighbour could not resolve is not a difference.
  cv::Mat tb = target.clone();
  for (double sigma : {0.5, 1.0, 1.5, 2.0, 3.0}) {
    const double r = std::sqrt(1 + 4 * sigma * sigma);  // the ratio that asks for sigma
    cv::Mat blurred;
    cv::GaussianBlur(target, blurred, {0, 0}, sigma);
    blurred.copyTo(tb, coarser >= r * 0.85);
  }
  const cv::Mat above = tb - hi, below = lo - tb;
  cv::Mat d;
  cv::max(above, below, d);
  d = cv::max(d, 0.0);
  d.setTo(0, ~valid);
  cv::Mat vf, sum, cnt;
  valid.convertTo(vf, CV_32F, 1.0 / 255);
  const cv::Size box(o.window, o.window);
  cv::boxFilter(d, sum, CV_32F, box, {-1, -1}, false);
  cv::boxFilter(vf, cnt, CV_32F, box, {-1, -1}, false);
  cv::Mat out(target.size(), CV_32F, kNaN);
  const float need = 0.5f * static_cast<float>(o.window * o.window);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x)
      if (valid.at<uint8_t>(y, x) && cnt.at<float>(y, x) >= need)
        out.at<float>(y, x) = sum.at<float>(y, x) / cnt.at<float>(y, x);
  return out;
}

// Length of the DIS flow from the target to the warp (invalid pixels: the target's own).
cv::Mat FlowResidual(const cv::Mat& target, const cv::Mat& warp, const cv::Mat& valid,
                     const cv::Mat& motion, const DynamicOptions& o) {
  cv::Mat filled = warp.clone();
  target.copyTo(filled, ~valid);
  cv::Mat a8, b8, flow;
  target.convertTo(a8, CV_8U, 255);
  filled.convertTo(b8, CV_8U, 255);
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST);
  // DIS's coarsest pyramid level holds 4 patches across; its finest level must not be coarser
  // (OpenCV 4.6 crashes on small images otherwise), and an image too small for one level has no
  // flow evidence.
  const int coarsest = static_cast<int>(std::floor(
      std::log2(std::max(target.cols, target.rows) / (4.0 * dis->getPatchSize())) + 0.5));
  if (coarsest < 0) return cv::Mat(target.size(), CV_32F, kNaN);
  dis->setFinestScale(std::min(dis->getFinestScale(), coarsest));
  dis->calc(a8, b8, flow);
  cv::Mat parts[2], mag;
  cv::split(flow, parts);
  cv::magnitude(parts[0], parts[1], mag);
  // A large rigid motion warps the neighbour more (foreshortening, resampling): the residual is
  // taken relative to max(threshold, flow_relative × the rigid motion), in threshold units.
  cv::Mat allowed = cv::max(motion * o.flow_relative, o.flow_threshold);
  mag = mag.mul(o.flow_threshold / allowed);
  mag.setTo(kNaN, ~valid);
  return mag;
}

// Per pixel, the `quantile` of the finite values across `maps` (NaN when none).
cv::Mat Reduce(const std::vector<cv::Mat>& maps, double quantile, cv::Size size) {
  cv::Mat out(size, CV_32F, kNaN);
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<float> v;
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < size.width; ++x) {
        v.clear();
        for (const cv::Mat& m : maps) {
          const float f = m.at<float>(y, x);
          if (std::isfinite(f)) v.push_back(f);
        }
        if (v.empty()) continue;
        std::sort(v.begin(), v.end());
        const double pos = quantile * static_cast<double>(v.size() - 1);
        const size_t i = static_cast<size_t>(pos);
        const double f = pos - static_cast<double>(i);
        out.at<float>(y, x) =
            static_cast<float>(i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i]);
      }
  });
  return out;
}

// Logistic in r / threshold: 0.5 at 1, 0.05 at 0.4, 0.95 at 1.6; 0 for NaN.
float Logistic(float r, double threshold) {
  if (!std::isfinite(r)) return 0;
  const double s = (r / threshold - 1.0) / (0.6 / std::log(19.0));
  return static_cast<float>(1.0 / (1.0 + std::exp(-s)));
}

// Per pixel, the texture weight: local mean gradient magnitude of the luma / `scale`, at most 1.
cv::Mat TextureWeight(const cv::Mat& grey, int window, double scale) {
  cv::Mat gx, gy, mag;
  cv::Sobel(grey, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(grey, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  cv::magnitude(gx, gy, mag);
  cv::boxFilter(mag, mag, CV_32F, {window, window});
  cv::Mat w = mag / scale;
  return cv::min(w, 1.0);
}

// Spreads the pixel probabilities over the target's regions (see the header).
void SpreadOverRegions(const DynamicView& t, const cv::Mat& has_depth, const DynamicOptions& o,
                       cv::Mat& p) {
  cv::Mat src;
  if (!t.colour.empty())
    src = t.colour;
  else
    t.grey.convertTo(src, CV_8U, 255);
  const int min_size = std::max(16, static_cast<int>(t.grey.total() / 2000));
  auto gs = cv::ximgproc::segmentation::createGraphSegmentation(0.5, float(o.segments), min_size);
  cv::Mat seg;
  gs->processImage(src, seg);
  double max_label = 0;
  cv::minMaxLoc(seg, nullptr, &max_label);
  const size_t n = static_cast<size_t>(max_label) + 1;
  const cv::Mat w = TextureWeight(t.grey, o.window, o.texture);
  std::vector<double> sw(n, 0), swp(n, 0), area(n, 0), nd(n, 0);
  for (int y = 0; y < p.rows; ++y)
    for (int x = 0; x < p.cols; ++x) {
      const size_t s = static_cast<size_t>(seg.at<int>(y, x));
      area[s] += 1;
      if (!has_depth.at<uint8_t>(y, x)) continue;
      nd[s] += 1;
      sw[s] += w.at<float>(y, x);
      swp[s] += w.at<float>(y, x) * p.at<float>(y, x);
    }
  for (int y = 0; y < p.rows; ++y)
    for (int x = 0; x < p.cols; ++x) {
      const size_t s = static_cast<size_t>(seg.at<int>(y, x));
      if (sw[s] < 0.05 * area[s]) continue;
      if (!has_depth.at<uint8_t>(y, x)) {  // the region's, when mostly with depth
        if (nd[s] > o.region_depth * area[s]) p.at<float>(y, x) = float(swp[s] / sw[s]);
        continue;
      }
      const float wp = w.at<float>(y, x);
      p.at<float>(y, x) = wp * p.at<float>(y, x) + (1 - wp) * static_cast<float>(swp[s] / sw[s]);
    }
}

}  // namespace

void DynamicOptions::Check() const {
  if (!(threshold > 0) || !std::isfinite(threshold))
    throw UsageError("--threshold must be above 0, got " + std::to_string(threshold));
  if (!(colour_threshold > 0) || !std::isfinite(colour_threshold))
    throw UsageError("--colour-threshold must be above 0, got " + std::to_string(colour_threshold));
  if (!(flow_relative >= 0 && flow_relative < 10))
    throw UsageError("--flow-relative must be in [0, 10), got " + std::to_string(flow_relative));
  if (!(flow_threshold > 0) || !std::isfinite(flow_threshold))
    throw UsageError("--flow-threshold must be above 0, got " + std::to_string(flow_threshold));
  if (!(quantile >= 0 && quantile <= 1))
    throw UsageError("--quantile must be in [0, 1], got " + std::to_string(quantile));
  if (!(partners_veto >= 0 && partners_veto <= 10))
    throw UsageError("--partners-veto must be in [0, 10], got " + std::to_string(partners_veto));
  if (!(ahead_veto >= 0 && ahead_veto <= 10))
    throw UsageError("--ahead-veto must be in [0, 10], got " + std::to_string(ahead_veto));
  if (!(depth_tolerance > 0 && depth_tolerance < 1))
    throw UsageError("--depth-tolerance must be in (0, 1), got " + std::to_string(depth_tolerance));
  if (slack < 0 || slack > 5)
    throw UsageError("--slack must be 0..5, got " + std::to_string(slack));
  if (window < 1 || window > 31 || window % 2 == 0)
    throw UsageError("--window must be odd, 1..31, got " + std::to_string(window));
  if (!(segments >= 0) || !std::isfinite(segments))
    throw UsageError("--segments must be at least 0, got " + std::to_string(segments));
  if (!(texture > 0) || !std::isfinite(texture))
    throw UsageError("--texture must be above 0, got " + std::to_string(texture));
  if (!(region_depth >= 0 && region_depth <= 1))
    throw UsageError("--region-depth must be in [0, 1], got " + std::to_string(region_depth));
}

void MaskOptions::Check() const {
  if (!(probability > 0 && probability < 1))
    throw UsageError("--probability must be in (0, 1), got " + std::to_string(probability));
  if (open < 0 || open > 50) throw UsageError("--open must be 0..50, got " + std::to_string(open));
  if (!(close >= 0 && close <= 0.2))
    throw UsageError("--close must be in [0, 0.2], got " + std::to_string(close));
  if (!(min_area >= 0 && min_area < 1))
    throw UsageError("--min-area must be in [0, 1), got " + std::to_string(min_area));
}

namespace {

// The three colour channels of view `v` (which has a colour image), float 0..1.
std::vector<cv::Mat> ColourPlanes(const DynamicView& v) {
  std::vector<cv::Mat> c;
  cv::split(v.colour, c);
  for (cv::Mat& m : c) m.convertTo(m, CV_32F, 1.0 / 255);
  return c;
}

// View `v`'s planes of the kind of `n` target planes: its colour channels for 3, else its luma.
std::vector<cv::Mat> PlanesLike(const DynamicView& v, size_t n) {
  return n == 3 ? ColourPlanes(v) : std::vector{v.grey};
}

// `m` times the gain that brings it to `target`'s exposure (ExposureGain), as a new image: never
// `m`'s own pixels in place (a view's luma is shared with the caller's cache).
cv::Mat Gained(const cv::Mat& m, const cv::Mat& target) {
  const cv::Mat out = m * ExposureGain(target, m);
  return out;
}

// Whether view `v` has a colour image that is not grey (its three channels not all equal: a
// grey camera's photo is loaded as three copies of its one channel).
bool InColour(const DynamicView& v) {
  if (v.colour.empty()) return false;
  std::vector<cv::Mat> c;
  cv::split(v.colour, c);
  return cv::countNonZero(c[0] != c[1]) + cv::countNonZero(c[0] != c[2]) > 0;
}

// The target's planes for the photometric residual, made once per target: its luma, and with
// `colour` its three colour channels when it is in colour (InColour).
class TargetPlanes {
 public:
  TargetPlanes(const DynamicView& t, bool colour) : luma_{t.grey} {
    if (colour && InColour(t)) colour_ = ColourPlanes(t);
  }
  // Those compared against view `nb`: the colour channels when both are in colour, else the luma.
  const std::vector<cv::Mat>& Against(const DynamicView& nb) const {
    return !colour_.empty() && InColour(nb) ? colour_ : luma_;
  }

 private:
  std::vector<cv::Mat> luma_, colour_;
};

// A view resampled into the target through the static depth.
struct Warped {
  cv::Mat grey;  // its luma, gained to the target's exposure (0 where not valid); flow only
  std::vector<cv::Mat> planes;     // its planes matching the target's, each gained to it apart
  cv::Mat valid, coarser, motion;  // where it sees the target's point; WarpMaps' maps
};

// `nb` warped into the target: `own`, nb's PlanesLike the target's `planes` (luma or colour);
// false when it sees none of the target's pixels.
bool WarpView(const DynamicView& t, const std::vector<cv::Mat>& planes, const DynamicView& nb,
              const std::vector<cv::Mat>& own, const DynamicOptions& o, Warped& w) {
  cv::Mat mx, my;
  WarpMaps(t, nb, o.depth_tolerance, mx, my, w.coarser, w.motion);
  w.valid = mx == mx;  // not NaN
  if (cv::countNonZero(w.valid) == 0) return false;
  const auto resample = [&](const cv::Mat& src, const cv::Mat& target) {
    cv::Mat out;
    cv::remap(src, out, mx, my, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    out.setTo(0, ~w.valid);
    return Gained(out, target);
  };
  w.planes.clear();
  for (size_t k = 0; k < own.size(); ++k) w.planes.push_back(resample(own[k], planes[k]));
  // Only the flow reads the luma; on the luma's planes it is the one plane warped already.
  if (o.flow) w.grey = planes.size() == 1 ? w.planes[0] : resample(nb.grey, t.grey);
  return true;
}

// The photometric residual of `warped` planes against the target's `planes` (Photometric per
// plane, where `valid`): their largest, colour planes' in units of the luma's threshold (times
// threshold / colour_threshold).
cv::Mat PlanesResidual(const std::vector<cv::Mat>& planes, const std::vector<cv::Mat>& warped,
                       const cv::Mat& valid, const cv::Mat& coarser, const DynamicOptions& o) {
  if (planes.size() == 1) return Photometric(planes[0], warped[0], valid, coarser, o);
  cv::Mat out;
  for (size_t k = 0; k < planes.size(); ++k) {
    const cv::Mat r = Photometric(planes[k], warped[k], valid, coarser, o);
    out = out.empty() ? r : cv::Mat(cv::max(out, r));  // NaN where not valid, in every plane
  }
  return out * (o.threshold / o.colour_threshold);
}

// The target's residuals against `views`, reduced over them (photometric, and flow when on);
// returns how many views saw any of the target's pixels.
int ReducedResiduals(const DynamicView& t, const std::vector<const DynamicView*>& views,
                     const DynamicOptions& o, const char* what, cv::Mat& photometric,
                     cv::Mat& flow) {
  std::vector<cv::Mat> photo, flows;
  int seen_by = 0;
  const TargetPlanes target(t, o.colour);
  for (const DynamicView* nb : views) {
    CheckView(*nb, what);
    const std::vector<cv::Mat>& planes = target.Against(*nb);
    Warped w;
    if (!WarpView(t, planes, *nb, PlanesLike(*nb, planes.size()), o, w)) continue;
    ++seen_by;
    photo.push_back(PlanesResidual(planes, w.planes, w.valid, w.coarser, o));
    if (o.flow) flows.push_back(FlowResidual(t.grey, w.grey, w.valid, w.motion, o));
  }
  photometric = Reduce(photo, o.quantile, t.grey.size());
  if (o.flow) flow = Reduce(flows, o.quantile, t.grey.size());
  return seen_by;
}

// Non-zero where one of the target's photos farther along (`ahead`) witnesses its static point:
// its warp through the static depth agrees with the target (photometric residual under
// ahead_veto × threshold) and its own pixel at the same place does not (at least that). A vehicle
// keeping the camera's pace ahead keeps its place in the drive's photos: a photo where the
// pixel's own place shows what the target shows as well as the warp does cannot tell the static
// point from such a vehicle (a car's uniform panels, seen a pixel or two off). A view of another
// size than the target's is a witness wherever its warp agrees. `seen_by`: how many of them saw
// any of the target's pixels.
cv::Mat AheadWitnesses(const DynamicView& t, const std::vector<const DynamicView*>& ahead,
                       const DynamicOptions& o, int& seen_by) {
  const double agree = o.ahead_veto * o.threshold;
  cv::Mat out(t.grey.size(), CV_8U, cv::Scalar(0));
  seen_by = 0;
  const TargetPlanes target(t, o.colour);
  for (const DynamicView* nb : ahead) {
    CheckView(*nb, "ahead view");
    const std::vector<cv::Mat>& planes = target.Against(*nb);
    const std::vector<cv::Mat> own = PlanesLike(*nb, planes.size());
    Warped w;
    if (!WarpView(t, planes, *nb, own, o, w)) continue;
    ++seen_by;
    cv::Mat witness = PlanesResidual(planes, w.planes, w.valid, w.coarser, o) < agree;
    // A photo behind the target (its centre at z <= 0 in the target's camera) cannot have
    // passed a vehicle ahead: its own pixel is compared too, gained alike.
    const bool behind = (t.world_to_camera * nb->world_to_camera.Centre()).z() <= 0;
    if (behind && nb->grey.size() == t.grey.size()) {
      const cv::Mat all(t.grey.size(), CV_8U, cv::Scalar(255));
      std::vector<cv::Mat> same;
      for (size_t k = 0; k < own.size(); ++k) same.push_back(Gained(own[k], planes[k]));
      const cv::Mat ones = cv::Mat::ones(t.grey.size(), CV_32F);
      witness &= ~(PlanesResidual(planes, same, all, ones, o) < agree);
    }
    out |= witness;
  }
  return out;
}

// max over the cues of their logistic (a cue's map may be empty: no such cue).
float CueProbability(int y, int x, std::initializer_list<std::pair<const cv::Mat*, double>> cues) {
  float p = 0;
  for (const auto& [m, threshold] : cues)
    if (!m->empty()) p = std::max(p, Logistic(m->at<float>(y, x), threshold));
  return p;
}

}  // namespace

DynamicEvidence EstimateDynamic(const DynamicView& t,
                                const std::vector<const DynamicView*>& neighbours,
                                const DynamicOptions& o,
                                const std::vector<const DynamicView*>& partners,
                                const std::vector<const DynamicView*>& ahead) {
  o.Check();
  CheckView(t, "target view");
  DynamicEvidence ev;
  ev.neighbours = ReducedResiduals(t, neighbours, o, "neighbour view", ev.photometric, ev.flow);
  // Partners and photos farther along give photometric evidence only: another drive has other
  // light and another lane; a photo metres ahead warps the near road too distorted.
  DynamicOptions photometric_only = o;
  photometric_only.flow = false;
  cv::Mat no_flow;
  if (!partners.empty())
    ev.partners =
        ReducedResiduals(t, partners, photometric_only, "partner view", ev.across, no_flow);
  if (o.partners_veto > 0 && !ev.across.empty() && !ev.flow.empty()) {
    // Another drive saw the static point as this photo does: the motion this drive's own
    // neighbours show there is view-dependent light (NaN, seen by no partner, compares false).
    ev.flow.setTo(kNaN, ev.across < o.partners_veto * o.threshold);
  }
  cv::Mat ahead_cue;
  if (o.ahead_veto > 0 && !ev.across.empty() && !ahead.empty()) {
    // The photo's own drive, farther along, saw these pixels as they are: what another drive's
    // photos disagree with there is that drive's own traffic.
    ev.across.setTo(kNaN, AheadWitnesses(t, ahead, photometric_only, ev.ahead));
  } else if (!ahead.empty()) {
    ev.ahead = ReducedResiduals(t, ahead, photometric_only, "ahead view", ev.ahead_photo, no_flow);
    ahead_cue = ev.ahead_photo;
  }
  ev.probability.create(t.grey.size(), CV_32F);
  for (int y = 0; y < t.grey.rows; ++y)
    for (int x = 0; x < t.grey.cols; ++x)
      ev.probability.at<float>(y, x) = CueProbability(y, x,
                                                      {
                                                          {&ev.photometric, o.threshold},
                                                          {&ev.flow, o.flow_threshold},
                                                          {&ev.across, o.threshold},
                                                          {&ahead_cue, o.threshold},
                                                      });
  if (o.segments > 0 && ev.neighbours + ev.partners + ev.ahead > 0) {
    SpreadOverRegions(t, HasDepthMask(t.depth), o, ev.probability);
  }
  return ev;
}

namespace {

// Pixel (x, y)'s point at depth map `z`'s depth, camera coordinates (any depth: check it first).
Eigen::Vector3d PointAt(const Camera& c, const cv::Mat& z, int x, int y) {
  const double d = z.at<float>(y, x);
  return {(x + 0.5 - c.cx()) / c.fx() * d, (y + 0.5 - c.cy()) / c.fy() * d, d};
}

// The static point of pixel (x, y) in camera coordinates; NaN when it has no depth.
Eigen::Vector3d StaticPoint(const DynamicView& t, int x, int y) {
  if (!HasDepth(t.depth.at<float>(y, x))) return Eigen::Vector3d::Constant(std::nan(""));
  return PointAt(t.camera, t.depth, x, y);
}

// The static point of pixel (x, y) of `t` along `up` relative to the camera centre; NaN when the
// pixel has no depth.
double HeightOf(const DynamicView& t, const Eigen::Vector3d& up_cam, int x, int y) {
  return StaticPoint(t, x, y).dot(up_cam);
}

// The ground's height under the camera along `up_cam`, relative to its centre (negative): the
// median height of the static points of the image's lower middle (its lowest fifth, middle
// half: the road ahead); NaN without 16 such points or when it is not below the camera.
double GroundBelow(const DynamicView& t, const Eigen::Vector3d& up_cam) {
  std::vector<double> road;
  for (int y = t.depth.rows * 4 / 5; y < t.depth.rows; ++y)
    for (int x = t.depth.cols / 4; x < t.depth.cols * 3 / 4; ++x) {
      const double h = HeightOf(t, up_cam, x, y);
      if (std::isfinite(h)) road.push_back(h);
    }
  if (road.size() < 16) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(road.begin(), road.begin() + long(road.size() / 2), road.end());
  const double ground = road[road.size() / 2];
  return ground < 0 ? ground : std::numeric_limits<double>::quiet_NaN();
}

// How high a blob column rises above the ground at its foot, along `up_cam`, in the units of the
// static depth: the top pixel's ray taken to the foot's distance across `up_cam`; NaN when the
// foot has no static point (at the lowest pixel or the one below it).
double ColumnRise(const DynamicView& t, const Eigen::Vector3d& up_cam, int x, int top, int low) {
  Eigen::Vector3d f = StaticPoint(t, x, low);
  if (!f.allFinite() && low + 1 < t.depth.rows) f = StaticPoint(t, x, low + 1);
  if (!f.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d r((x + 0.5 - t.camera.cx()) / t.camera.fx(),
                          (top + 0.5 - t.camera.cy()) / t.camera.fy(), 1);
  const double across = (r - r.dot(up_cam) * up_cam).norm();
  const double reach = (f - f.dot(up_cam) * up_cam).norm();
  if (!(across > 1e-9)) return std::numeric_limits<double>::quiet_NaN();
  return r.dot(up_cam) * reach / across - f.dot(up_cam);
}

// Calls visit(x, b, top, low) for every column x of every blob b of `labels` (n labels, 0 =
// background) that has pixels in it: its highest and lowest row there.
template <class Visit>
void ForEachBlobColumn(const cv::Mat& labels, int n, Visit visit) {
  std::vector<int> top(static_cast<size_t>(n)), low(static_cast<size_t>(n));
  for (int x = 0; x < labels.cols; ++x) {
    std::fill(top.begin(), top.end(), -1);
    for (int y = 0; y < labels.rows; ++y) {
      const size_t b = size_t(labels.at<int>(y, x));
      if (b == 0) continue;
      if (top[b] < 0) top[b] = y;
      low[b] = y;
    }
    for (size_t b = 1; b < size_t(n); ++b)
      if (top[b] >= 0) visit(x, b, top[b], low[b]);
  }
}

// Per blob of `labels` (n labels, 0 = background): the highest rise of its columns relative to
// `height` (NaN: no column judged).
std::vector<double> BlobRises(const DynamicView& t, const Eigen::Vector3d& up_cam,
                              const cv::Mat& labels, int n, double height) {
  std::vector<double> rise(size_t(n), std::numeric_limits<double>::quiet_NaN());
  ForEachBlobColumn(labels, n, [&](int x, size_t b, int top, int low) {
    const double r = ColumnRise(t, up_cam, x, top, low) / height;
    if (std::isfinite(r) && !(r <= rise[b])) rise[b] = r;
  });
  return rise;
}

// Per blob of `labels` (n labels, 0 = background): the share of its upper pixels (in each column,
// those above the middle between its top and lowest pixel) whose static depth is more than
// (1 + gap) times its foot's (the column's lowest pixel's, or the one below it), or none (sky):
// what the blob hides behind it. NaN when no column has a foot.
std::vector<double> BlobOcclusions(const DynamicView& t, const cv::Mat& labels, int n, double gap) {
  std::vector<double> behind(size_t(n), 0), judged(size_t(n), 0);
  ForEachBlobColumn(labels, n, [&](int x, size_t b, int top, int low) {
    float foot = t.depth.at<float>(low, x);
    if (!HasDepth(foot) && low + 1 < t.depth.rows) foot = t.depth.at<float>(low + 1, x);
    if (!HasDepth(foot)) return;
    for (int y = top; 2 * y < top + low; ++y) {
      if (size_t(labels.at<int>(y, x)) != b) continue;
      const float z = t.depth.at<float>(y, x);
      judged[b] += 1;
      behind[b] += !HasDepth(z) || z > (1 + gap) * foot;
    }
  });
  for (size_t b = 1; b < size_t(n); ++b)
    behind[b] = judged[b] > 0 ? behind[b] / judged[b] : std::numeric_limits<double>::quiet_NaN();
  return behind;
}

// Non-zero where the photo's own depth (`t.seen`) is the static depth within `tolerance`
// (relative): the photo saw the static surface there.
cv::Mat ExplainedPixels(const DynamicView& t, double tolerance) {
  cv::Mat out(t.depth.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const float z = t.depth.at<float>(y, x), s = t.seen.at<float>(y, x);
      out.at<uint8_t>(y, x) = HasDepth(z) && HasDepth(s) && std::abs(s - z) <= tolerance * z;
    }
  return out;
}

// Sets to 0 the probability of every pixel where the photo's own depth is the static depth
// within `tolerance` (relative); the number of pixels so cleared that were at or above `at`.
size_t ClearExplained(const DynamicView& t, double tolerance, double at, cv::Mat& probability) {
  const cv::Mat explained = ExplainedPixels(t, tolerance);
  size_t cleared = 0;
  for (int y = 0; y < probability.rows; ++y)
    for (int x = 0; x < probability.cols; ++x) {
      if (!explained.at<uint8_t>(y, x)) continue;
      float& p = probability.at<float>(y, x);
      cleared += p >= at;
      p = 0;
    }
  return cleared;
}

// 255 where `mask`'s 8-connected component holds a pixel of `seeds` (both CV_8U, one size).
cv::Mat ComponentsTouching(const cv::Mat& mask, const cv::Mat& seeds) {
  cv::Mat labels;
  const int n = cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<uint8_t> touches(size_t(n), 0);
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if (seeds.at<uint8_t>(y, x)) touches[size_t(labels.at<int>(y, x))] = 1;
  touches[0] = 0;
  cv::Mat out(mask.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if (touches[size_t(labels.at<int>(y, x))]) out.at<uint8_t>(y, x) = 255;
  return out;
}

// Sets to 0 the probability of every pixel whose blob (`labels`, 0 = background) `drop` marks.
void ZeroBlobs(const cv::Mat& labels, const std::vector<uint8_t>& drop, cv::Mat& probability) {
  for (int y = 0; y < probability.rows; ++y)
    for (int x = 0; x < probability.cols; ++x)
      if (drop[size_t(labels.at<int>(y, x))]) probability.at<float>(y, x) = 0;
}

}  // namespace

int KeepGrounded(const DynamicView& t, const Eigen::Vector3d& up, double at, double tolerance,
                 cv::Mat& probability) {
  const Eigen::Vector3d up_cam = t.world_to_camera.R() * up;  // world direction in the camera
  const double ground = GroundBelow(t, up_cam);               // negative: below the camera
  if (!std::isfinite(ground)) return 0;
  cv::Mat labels;
  const int n = cv::connectedComponents(probability >= at, labels, 8, CV_32S);
  // Per blob, column by column: whether the static point below its lowest pixel is near the
  // ground (once one is, the blob is grounded).
  std::vector<int> state(size_t(n), 0);  // 0 unknown (kept), 1 grounded, 2 floating
  ForEachBlobColumn(labels, n, [&](int x, size_t b, int, int low) {
    if (state[b] == 1 || low + 1 >= probability.rows) return;
    const double hf = HeightOf(t, up_cam, x, low + 1);
    if (!std::isfinite(hf)) return;
    state[b] = std::abs(hf - ground) <= tolerance * std::abs(ground) ? 1 : 2;
  });
  std::vector<uint8_t> drop(size_t(n), 0);
  for (int b = 1; b < n; ++b) drop[size_t(b)] = state[size_t(b)] == 2;
  ZeroBlobs(labels, drop, probability);
  return int(std::count(drop.begin(), drop.end(), 1));
}

namespace {

cv::Mat Disk(int r) { return cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}); }

// Opens the binary mask `m` by a disk of radius r (> 0; 0: nothing): specks go.
void OpenMask(cv::Mat& m, int r) {
  if (r > 0) cv::morphologyEx(m, m, cv::MORPH_OPEN, Disk(r));
}

// Clears the blobs (8-connected) of `m` under `min_area` of the image.
void DropSmallBlobs(cv::Mat& m, double min_area) {
  cv::Mat labels, stats, cents;
  const int k = cv::connectedComponentsWithStats(m, labels, stats, cents, 8, CV_32S);
  const double min_px = min_area * static_cast<double>(m.total());
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x) {
      const int l = labels.at<int>(y, x);
      if (l > 0 && l < k && stats.at<int>(l, cv::CC_STAT_AREA) < min_px) m.at<uint8_t>(y, x) = 0;
    }
}

}  // namespace

cv::Mat MaskFromProbability(const cv::Mat& probability, const MaskOptions& o) {
  o.Check();
  cv::Mat m = probability >= o.probability;
  OpenMask(m, o.open);
  const int close = static_cast<int>(std::lround(o.close * m.cols));
  if (close > 0) cv::morphologyEx(m, m, cv::MORPH_CLOSE, Disk(close));
  // Holes: background components that do not touch the border.
  cv::Mat bg = ~m, labels;
  const int n = cv::connectedComponents(bg, labels, 4, CV_32S);
  std::vector<uint8_t> border(static_cast<size_t>(n), 0);
  for (int x = 0; x < labels.cols; ++x)
    border[static_cast<size_t>(labels.at<int>(0, x))] =
        border[static_cast<size_t>(labels.at<int>(labels.rows - 1, x))] = 1;
  for (int y = 0; y < labels.rows; ++y)
    border[static_cast<size_t>(labels.at<int>(y, 0))] =
        border[static_cast<size_t>(labels.at<int>(y, labels.cols - 1))] = 1;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      if (!m.at<uint8_t>(y, x) && !border[static_cast<size_t>(labels.at<int>(y, x))])
        m.at<uint8_t>(y, x) = 255;
  DropSmallBlobs(m, o.min_area);
  return m;
}

namespace {

// For each label 1..n-1 of `labels` (CV_32S), the share of its pixels where `flags` (CV_8U) is
// non-zero; 0 for a label with no pixel.
std::vector<double> BlobShares(const cv::Mat& labels, int n, const cv::Mat& flags) {
  std::vector<double> on(size_t(n), 0), all(size_t(n), 0);
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int b = labels.at<int>(y, x);
      if (b <= 0) continue;
      all[size_t(b)] += 1;
      on[size_t(b)] += flags.at<uint8_t>(y, x) != 0;
    }
  for (size_t b = 0; b < size_t(n); ++b) on[b] = all[b] > 0 ? on[b] / all[b] : 0;
  return on;
}

// The blobs (`labels`, 1..n-1, of the mask made of `probability`) more than `max_share` of whose
// pixels are on `guessed`: probability 0 at those pixels. The count of such blobs.
int ClearGuessed(const cv::Mat& guessed, const cv::Mat& labels, int n, double max_share,
                 cv::Mat& probability) {
  const std::vector<double> share = BlobShares(labels, n, guessed);
  int cleared = 0;
  for (int b = 1; b < n; ++b) cleared += share[size_t(b)] > max_share;
  if (cleared == 0) return 0;
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int b = labels.at<int>(y, x);
      if (b > 0 && share[size_t(b)] > max_share && guessed.at<uint8_t>(y, x) != 0)
        probability.at<float>(y, x) = 0;
    }
  return cleared;
}

}  // namespace

BlobTestCounts KeepStandingUnexplained(const DynamicView& t, const Eigen::Vector3d& up,
                                       const MaskOptions& mask, const BlobTestOptions& o,
                                       cv::Mat& probability) {
  if (!(o.min_height >= 0) || !(o.seen_tolerance >= 0 && o.seen_tolerance < 1) ||
      !(o.occludes >= 0 && o.occludes <= 1) || !(o.occlusion_gap > 0) ||
      !(o.max_guessed >= 0 && o.max_guessed <= 1))
    throw Error("KeepStandingUnexplained: options out of range");
  CheckView(t, "target view");
  if (probability.type() != CV_32F || probability.size() != t.depth.size())
    throw Error("target view: the probability must be float of the depth's size");
  BlobTestCounts counts;
  if (o.seen_tolerance > 0 && !t.seen.empty())
    counts.explained = ClearExplained(t, o.seen_tolerance, mask.probability, probability);
  const Eigen::Vector3d up_cam = t.world_to_camera.R() * up.normalized();
  const double ground = GroundBelow(t, up_cam);
  // The blobs of the mask the probability makes; made again only when it changed.
  cv::Mat labels;
  int n = 0;
  const auto label = [&] {
    n = cv::connectedComponents(MaskFromProbability(probability, mask), labels, 8, CV_32S);
  };
  if (o.max_guessed < 1 && !t.guessed.empty()) {
    label();
    counts.guessed = ClearGuessed(t.guessed, labels, n, o.max_guessed, probability);
    if (counts.guessed > 0) n = 0;
  }
  const bool rise_test = o.min_height > 0 && std::isfinite(ground);
  if (!rise_test && !(o.occludes > 0)) return counts;
  if (n == 0) label();
  std::vector<double> rise(size_t(n), std::numeric_limits<double>::quiet_NaN()), behind = rise;
  if (rise_test) rise = BlobRises(t, up_cam, labels, n, -ground);
  if (o.occludes > 0) behind = BlobOcclusions(t, labels, n, o.occlusion_gap);
  std::vector<uint8_t> drop(size_t(n), 0);
  for (size_t b = 1; b < size_t(n); ++b) {
    if (rise[b] < o.min_height)
      drop[b] = 1, ++counts.lying;
    else if (behind[b] < o.occludes)
      drop[b] = 1, ++counts.surface;
  }
  ZeroBlobs(labels, drop, probability);
  return counts;
}

int CompleteBlobs(const DynamicView& t, const MaskOptions& mask, const BlobCompletion& o,
                  cv::Mat& probability) {
  if (!(o.max_grow >= 0) || !(o.tolerance > 0 && o.tolerance < 1) || o.iterations < 1)
    throw Error("CompleteBlobs: options out of range");
  CheckView(t, "target view");
  if (probability.type() != CV_32F || probability.size() != t.depth.size())
    throw Error("target view: the probability must be float of the depth's size");
  if (t.colour.empty() || t.seen.empty() || o.max_grow <= 0) return 0;
  // Sure background: where the photo's own depth is the static depth (it saw the static surface).
  const cv::Mat fixed = ExplainedPixels(t, o.tolerance);
  cv::Mat labels, stats, centres;
  const int n = cv::connectedComponentsWithStats(MaskFromProbability(probability, mask), labels,
                                                 stats, centres, 8, CV_32S);
  int completed = 0;
  cv::Mat add(probability.size(), CV_8U, cv::Scalar(0));
  for (int b = 1; b < n; ++b) {
    const cv::Rect box(stats.at<int>(b, cv::CC_STAT_LEFT), stats.at<int>(b, cv::CC_STAT_TOP),
                       stats.at<int>(b, cv::CC_STAT_WIDTH), stats.at<int>(b, cv::CC_STAT_HEIGHT));
    // The box widened by half its width on each side and by its height upwards.
    const cv::Rect roi = cv::Rect(box.x - box.width / 2, box.y - box.height,
                                  box.width + box.width / 2 * 2, 2 * box.height) &
                         cv::Rect(0, 0, probability.cols, probability.rows);
    const cv::Mat blob = labels(roi) == b;
    cv::Mat core;  // pixels beyond the box count as outside the blob
    cv::erode(blob, core, cv::Mat(), cv::Point(-1, -1), 2, cv::BORDER_CONSTANT, cv::Scalar(0));
    if (cv::countNonZero(core) < 5) continue;  // too small to model its colours
    cv::Mat gc(roi.size(), CV_8U, cv::Scalar(cv::GC_PR_BGD));
    cv::rectangle(gc, cv::Rect(0, 0, gc.cols, gc.rows), cv::Scalar(cv::GC_BGD), 1);
    gc.setTo(cv::GC_BGD, fixed(roi));
    gc.setTo(cv::GC_PR_FGD, blob);  // the blob's own pixels, explained or on the border, too
    gc.setTo(cv::GC_FGD, core);
    // A blob filling its box (a full mask): no background to model its colours against.
    // (GrabCut's colour models are k-means of 5 clusters: fewer samples than that throw.)
    if (cv::countNonZero((gc == cv::GC_BGD) | (gc == cv::GC_PR_BGD)) < 5) continue;
    cv::Mat bg, fg;
    // GrabCut starts its colour models with k-means from OpenCV's thread's generator: seeded per
    // blob (and put back after), a blob's completion does not depend on what ran before it.
    const cv::RNG kept = cv::theRNG();
    cv::theRNG() = cv::RNG(0x9e3779b97f4a7c15ULL);
    cv::grabCut(t.colour(roi), gc, cv::Rect(), bg, fg, o.iterations, cv::GC_INIT_WITH_MASK);
    cv::theRNG() = kept;
    const cv::Mat f = (gc == cv::GC_FGD) | (gc == cv::GC_PR_FGD);
    // The parts of the foreground that touch the blob, less the blob.
    const cv::Mat grown = ComponentsTouching(f, blob) & ~blob;
    const int area = stats.at<int>(b, cv::CC_STAT_AREA), more = cv::countNonZero(grown);
    if (more == 0 || more > o.max_grow * area) continue;
    cv::Mat at = add(roi);
    cv::bitwise_or(at, grown, at);
    ++completed;
  }
  cv::Mat raised;
  cv::max(probability, mask.probability, raised);
  raised.copyTo(probability, add);
  return completed;
}

namespace {

// A stretch of a path in the target's camera coordinates: its ends across up (a, b), the road's
// height along up under them (road_a, road_b), the drive's camera height; `first`/`last`: the
// path begins or ends there (nothing beyond it is beside it).
struct DrivenSegment {
  Eigen::Vector3d a, b;
  double road_a = 0, road_b = 0, height = 0;
  bool first = false, last = false;
};

// The paths' stretches within far + half_width × their camera's height (across up) of the
// target's camera centre, in its camera coordinates. Centres repeated (within 1e-6 of the camera's
// height) are taken once: a car that stood still has no way there.
std::vector<DrivenSegment> DrivenSegments(const Rigid3d& w2c, const Eigen::Vector3d& up_cam,
                                          const std::vector<DrivenPath>& paths, double far,
                                          double half_width) {
  const auto across = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(p - p.dot(up_cam) * up_cam);
  };
  std::vector<DrivenSegment> out;
  for (const DrivenPath& path : paths) {
    if (!(path.height > 0)) continue;
    std::vector<Eigen::Vector3d> c;
    for (const Eigen::Vector3d& w : path.centres) {
      const Eigen::Vector3d x = w2c * w;
      if (c.empty() || (x - c.back()).norm() > 1e-6 * path.height) c.push_back(x);
    }
    for (size_t k = 0; k + 1 < c.size(); ++k) {
      DrivenSegment s{across(c[k]),
                      across(c[k + 1]),
                      c[k].dot(up_cam) - path.height,
                      c[k + 1].dot(up_cam) - path.height,
                      path.height,
                      k == 0,
                      k + 2 == c.size()};
      // Distance of the camera centre (the origin) to the stretch, across up.
      const Eigen::Vector3d d = s.b - s.a;
      const double t = std::clamp(-s.a.dot(d) / d.squaredNorm(), 0.0, 1.0);
      if ((s.a + t * d).norm() <= far + half_width * s.height) out.push_back(s);
    }
  }
  return out;
}

// The pixels (255) of `agree` (non-zero where the seen point is the static one) whose seen
// point lies in the driven space of some stretch: within half_width × its camera's height of it
// across up (beside it: not beyond a path's first or last centre), between above and below × that
// height over the road there.
cv::Mat DrivenPixels(const DynamicView& t, const cv::Mat& agree, const Eigen::Vector3d& up_cam,
                     const std::vector<DrivenSegment>& segs, const DrivenSpace& o) {
  cv::Mat marked(t.seen.size(), CV_8U, cv::Scalar(0));
  // The heights along up where a stretch's space can be: a pixel outside them (the road, the
  // facades' upper floors, the sky) needs no search.
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const DrivenSegment& s : segs) {
    low = std::min({low, s.road_a + o.above * s.height, s.road_b + o.above * s.height});
    high = std::max({high, s.road_a + o.below * s.height, s.road_b + o.below * s.height});
  }
  cv::parallel_for_(cv::Range(0, t.seen.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < t.seen.cols; ++x) {
        if (!agree.at<uint8_t>(y, x)) continue;
        const Eigen::Vector3d p = PointAt(t.camera, t.seen, x, y);
        const double hp = p.dot(up_cam);
        if (hp <= low || hp >= high) continue;
        const Eigen::Vector3d ph = p - hp * up_cam;
        for (const DrivenSegment& s : segs) {
          const Eigen::Vector3d d = s.b - s.a;
          const double u = (ph - s.a).dot(d) / d.squaredNorm();
          if ((s.first && u < 0) || (s.last && u > 1)) continue;
          const double uc = std::clamp(u, 0.0, 1.0);
          if ((ph - s.a - uc * d).norm() > o.half_width * s.height) continue;
          const double rise = (hp - (s.road_a + uc * (s.road_b - s.road_a))) / s.height;
          if (rise > o.above && rise < o.below) {
            marked.at<uint8_t>(y, x) = 255;
            break;
          }
        }
      }
  });
  return marked;
}

}  // namespace

size_t MarkDriven(const DynamicView& t, const std::vector<DrivenPath>& paths,
                  const Eigen::Vector3d& up, const DrivenSpace& o, cv::Mat& probability) {
  if (!(o.half_width > 0) || !(o.above >= 0) || !(o.below > o.above) ||
      !(o.agree > 0 && o.agree < 1) || o.open < 0 || !(o.min_area >= 0 && o.min_area < 1))
    throw Error("MarkDriven: options out of range");
  CheckView(t, "target view");
  if (probability.type() != CV_32F || probability.size() != t.depth.size())
    throw Error("target view: the probability must be float of the depth's size");
  if (t.seen.empty()) return 0;
  const Eigen::Vector3d up_cam = t.world_to_camera.R() * up.normalized();
  const cv::Mat agree = ExplainedPixels(t, o.agree);
  if (cv::countNonZero(agree) == 0) return 0;
  // The mesh's own surface, where it has one and it is not a guess (a corridor wall behind a
  // hole): what the marked blobs grow over.
  DynamicView mesh = t;
  mesh.seen = t.depth;
  cv::Mat surface(t.depth.size(), CV_8U, cv::Scalar(0));
  if (o.grow) surface.setTo(1, HasDepthMask(t.depth));
  if (!t.guessed.empty()) surface.setTo(0, t.guessed);
  // The stretches that can hold a point counted: within its distance (plus the space's width,
  // added per stretch) of the camera.
  double far = 0;
  for (int y = 0; y < agree.rows; ++y)
    for (int x = 0; x < agree.cols; ++x) {
      if (agree.at<uint8_t>(y, x)) far = std::max(far, PointAt(t.camera, t.seen, x, y).norm());
      if (surface.at<uint8_t>(y, x)) far = std::max(far, PointAt(t.camera, t.depth, x, y).norm());
    }
  const std::vector<DrivenSegment> segs =
      DrivenSegments(t.world_to_camera, up_cam, paths, far, o.half_width);
  if (segs.empty()) return 0;
  cv::Mat marked = DrivenPixels(t, agree, up_cam, segs, o);
  // A stray depth is a speck; a vehicle a surface: specks go as the masks' do.
  OpenMask(marked, o.open);
  DropSmallBlobs(marked, o.min_area);
  // Where the photo's depth has none or another (a dark body, a window: stereo finds nothing
  // there), the mesh's surface in the space, joined to a marked blob, is the same vehicle.
  if (o.grow && cv::countNonZero(marked) > 0)
    marked = ComponentsTouching(DrivenPixels(mesh, surface, up_cam, segs, o) | marked, marked);
  size_t raised = 0;
  for (int y = 0; y < marked.rows; ++y)
    for (int x = 0; x < marked.cols; ++x) {
      float& v = probability.at<float>(y, x);
      if (marked.at<uint8_t>(y, x) && v < 1) v = 1, ++raised;
    }
  return raised;
}

}  // namespace mvtm
