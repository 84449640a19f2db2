#include "geo/gps_align.h"

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <random>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

namespace {

using C = std::complex<double>;

// q ≈ a·p + b by least squares over `idx` (a complex: scale and rotation); with `scale` > 0 the
// scale is held at it and only the rotation and translation are fitted.
void FitSimilarity(const std::vector<C>& p, const std::vector<C>& q, const std::vector<size_t>& idx,
                   C& a, C& b, double scale = 0) {
  C pm = 0, qm = 0;
  for (size_t i : idx) {
    pm += p[i];
    qm += q[i];
  }
  pm /= static_cast<double>(idx.size());
  qm /= static_cast<double>(idx.size());
  C num = 0;
  double den = 0;
  for (size_t i : idx) {
    num += std::conj(p[i] - pm) * (q[i] - qm);
    den += std::norm(p[i] - pm);
  }
  if (scale > 0)
    a = std::abs(num) > 0 ? scale * num / std::abs(num) : C(scale);
  else
    a = den > 0 ? num / den : C(0);
  b = qm - a * pm;
}

// Each fix within the frames' span paired with the camera centre interpolated between the two
// frames around its time (`t`: each frame's GPS time). Fixes are the independent measurements (a
// 10 Hz video between 1 Hz fixes would otherwise count each fix's error ten times over).
struct Pairs {
  std::vector<Eigen::Vector3d> cam, fix;  // camera centre; easting, northing, altitude
  bool alt_all = true;
};

Pairs PairFixes(const std::vector<Eigen::Vector3d>& centres, const std::vector<double>& t,
                const GpsLog& log, const UtmZone& zone, double max_gap) {
  std::vector<std::pair<double, size_t>> order;
  for (size_t i = 0; i < centres.size(); ++i) order.emplace_back(t[i], i);
  std::sort(order.begin(), order.end());
  Pairs out;
  for (const GpsFix& f : log.fixes) {
    auto hi =
        std::lower_bound(order.begin(), order.end(), f.time,
                         [](const std::pair<double, size_t>& e, double v) { return e.first < v; });
    if (hi == order.end()) continue;
    auto lo = hi;
    if (hi->first > f.time) {
      if (hi == order.begin()) continue;
      lo = hi - 1;
    }
    if (hi->first - lo->first > max_gap) continue;
    const double w = hi->first > lo->first ? (f.time - lo->first) / (hi->first - lo->first) : 0;
    out.cam.push_back((1 - w) * centres[lo->second] + w * centres[hi->second]);
    const Eigen::Vector2d e = ToUtm(zone, f.lat, f.lon);
    out.fix.emplace_back(e.x(), e.y(), f.alt);
    out.alt_all = out.alt_all && f.has_alt;
  }
  return out;
}

std::vector<C> Plane(const std::vector<Eigen::Vector3d>& v, const Eigen::Vector3d& origin) {
  std::vector<C> out;
  for (const auto& x : v) out.emplace_back(x.x() - origin.x(), x.y() - origin.y());
  return out;
}

// q ≈ a·p + b by least median of squares over two-point samples (every pair up to 2000, else a
// seeded sample); `med` = the median squared residual (infinite when no pair spans any extent).
struct Lmeds {
  double med = std::numeric_limits<double>::infinity();
  C a = 0, b = 0;
};

Lmeds LeastMedian(const std::vector<C>& p, const std::vector<C>& q) {
  const size_t n = p.size();
  std::vector<std::pair<size_t, size_t>> pairs;
  if (n * (n - 1) / 2 <= 2000) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) pairs.emplace_back(i, j);
  } else {
    std::mt19937 rng(1);
    std::uniform_int_distribution<size_t> pick(0, n - 1);
    while (pairs.size() < 2000) {
      const size_t i = pick(rng), j = pick(rng);
      if (i != j) pairs.emplace_back(i, j);
    }
  }
  Lmeds best;
  std::vector<double> r2(n);
  for (const auto& [i, j] : pairs) {
    if (std::abs(p[j] - p[i]) <= 0) continue;
    const C a = (q[j] - q[i]) / (p[j] - p[i]);
    const C b = q[i] - a * p[i];
    for (size_t k = 0; k < n; ++k) r2[k] = std::norm(a * p[k] + b - q[k]);
    const double med = Median(r2);
    if (med < best.med) best = {med, a, b};
  }
  return best;
}

std::string Span(double a, double b) { return FormatIsoTime(a) + " to " + FormatIsoTime(b); }

// The frames' GPS times at `offset` (see the header: relative or absolute frame times).
std::vector<double> GpsTimes(const std::vector<double>& times, double log_start, double offset) {
  std::vector<double> t(times.size());
  for (size_t i = 0; i < times.size(); ++i)
    t[i] = times[i] > 1e8 ? times[i] + offset : log_start + offset + times[i];
  return t;
}

// The offset in [o.offset − o.search, o.offset + o.search] whose pairs fit best (least median of
// squares, metres²): a coarse pass (0.1 s), then around its best (0.01 s). Only offsets that pair
// nearly as many fixes as the best-covered one compete: at the edge of the overlap a handful of
// pairs fits anything (three pairs give a zero median).
double SearchOffset(const std::vector<Eigen::Vector3d>& centres, const std::vector<double>& times,
                    const GpsLog& log, const UtmZone& zone, const GpsAlignOptions& o) {
  auto score = [&](double off, size_t& count) {
    const Pairs pr =
        PairFixes(centres, GpsTimes(times, log.fixes.front().time, off), log, zone, o.max_gap);
    count = pr.cam.size();
    if (count < 3) return std::numeric_limits<double>::infinity();
    return LeastMedian(Plane(pr.cam, Eigen::Vector3d::Zero()), Plane(pr.fix, pr.fix[0])).med;
  };
  double offset = o.offset;
  for (double step : {0.1, 0.01}) {
    const double from = step == 0.1 ? o.offset - o.search : offset - 0.1,
                 to = step == 0.1 ? o.offset + o.search : offset + 0.1;
    std::vector<std::pair<double, std::pair<double, size_t>>> cand;  // offset, (median, pairs)
    size_t most = 0;
    for (double off = from; off <= to + 1e-9; off += step) {
      size_t count = 0;
      const double med = score(off, count);
      cand.push_back({off, {med, count}});
      most = std::max(most, count);
    }
    double best_score = std::numeric_limits<double>::infinity();
    for (const auto& [off, sc] : cand)
      if (sc.second >= std::max<size_t>(5, (most * 9 + 9) / 10) && sc.first < best_score) {
        best_score = sc.first;
        offset = off;
      }
    if (!std::isfinite(best_score)) break;
  }
  return offset;
}

// The pairs within 2.5 robust sigmas (Rousseeuw's, from the least median of squares) of `lm`;
// every pair when fewer than 3 are.
std::vector<size_t> Inliers(const std::vector<C>& p, const std::vector<C>& q, const Lmeds& lm) {
  const size_t n = p.size();
  const double sigma =
      1.4826 * (1 + 5.0 / std::max<double>(1, static_cast<double>(n) - 2)) * std::sqrt(lm.med);
  std::vector<size_t> in;
  for (size_t k = 0; k < n; ++k)
    if (std::abs(lm.a * p[k] + lm.b - q[k]) <= std::max(2.5 * sigma, 1e-9)) in.push_back(k);
  if (in.size() < 3) {
    in.clear();
    for (size_t k = 0; k < n; ++k) in.push_back(k);
  }
  return in;
}

}  // namespace

int UtmZone::Epsg() const {
  if (zone == 0) return north ? 32661 : 32761;  // UPS North / South
  return (north ? 32600 : 32700) + zone;
}

std::string UtmZone::Name() const {
  return zone == 0 ? std::string(north ? "UPS N" : "UPS S")
                   : std::to_string(zone) + (north ? "N" : "S");
}

UtmZone ZoneOf(double lat, double lon) {
  UtmZone z;
  z.zone = GeographicLib::UTMUPS::StandardZone(lat, lon);
  z.north = lat >= 0;
  return z;
}

Eigen::Vector2d ToUtm(const UtmZone& zone, double lat, double lon) {
  int zn;
  bool north;
  double x, y;
  GeographicLib::UTMUPS::Forward(lat, lon, zn, north, x, y, zone.zone);
  if (north != zone.north)  // carried on across the equator in the first fix's hemisphere
    GeographicLib::UTMUPS::Transfer(zn, north, x, y, zone.zone, zone.north, x, y, zn);
  return {x, y};
}

GpsAlignment AlignToGps(const std::vector<Eigen::Vector3d>& centres,
                        const std::vector<double>& times, const GpsLog& log,
                        const std::string& log_name, const GpsAlignOptions& o) {
  if (log.fixes.empty()) throw Error(log_name, 0, "the GPS log has no fix");
  GpsAlignment out;
  out.frames = centres.size();
  out.log_start = log.fixes.front().time;
  out.log_end = log.fixes.back().time;
  out.zone = ZoneOf(log.fixes.front().lat, log.fixes.front().lon);
  const double offset = o.search > 0 ? SearchOffset(centres, times, log, out.zone, o) : o.offset;
  out.offset = offset;
  const std::vector<double> t = GpsTimes(times, out.log_start, offset);
  const double tmin = *std::min_element(t.begin(), t.end()),
               tmax = *std::max_element(t.begin(), t.end());
  for (double v : t) out.matched += v >= out.log_start && v <= out.log_end;
  const Pairs pr = PairFixes(centres, t, log, out.zone, o.max_gap);
  const std::vector<Eigen::Vector3d>& cam = pr.cam;
  const std::vector<Eigen::Vector3d>& fix = pr.fix;
  out.pairs = fix.size();
  if (fix.size() < 3)
    throw Error(log_name, 0,
                "the GPS log does not overlap the frames: its fixes span " +
                    Span(out.log_start, out.log_end) + ", the frames " + Span(tmin, tmax) +
                    " in GPS time (" + std::to_string(fix.size()) +
                    " fixes among the frames; need 3; see --gps-offset)");
  out.has_altitude = pr.alt_all;
  out.origin = Eigen::Vector3d(std::round(fix[0].x()), std::round(fix[0].y()), 0);
  const std::vector<C> p = Plane(cam, Eigen::Vector3d::Zero()), q = Plane(fix, out.origin);
  const Lmeds lm = LeastMedian(p, q);
  if (!std::isfinite(lm.med))
    throw Error(log_name, 0, "the frames within the GPS log do not move: no horizontal extent");
  const std::vector<size_t> in = Inliers(p, q, lm);
  C a, b;
  FitSimilarity(p, q, in, a, b);
  double ss = 0, spread = 0;
  C pm = 0;
  for (size_t k : in) pm += p[k];
  pm /= static_cast<double>(in.size());
  for (size_t k : in) {
    ss += std::norm(a * p[k] + b - q[k]);
    spread += std::norm(p[k] - pm);
  }
  const double dof = std::max<double>(1, 2.0 * static_cast<double>(in.size()) - 4);
  out.scale_gps = std::abs(a);
  out.scale_gps_sigma = spread > 0 ? std::sqrt(ss / dof) / std::sqrt(spread) : 0;
  double s = out.scale_gps;
  out.scale_source = "gps";
  if (o.height_scale > 0) {
    const double vh = std::pow(o.height_sigma * o.height_scale, 2),
                 vg = std::pow(out.scale_gps_sigma, 2);
    s = vg > 0 ? (out.scale_gps / vg + o.height_scale / vh) / (1 / vg + 1 / vh) : out.scale_gps;
    out.scale_source = "gps+camera-height";
    FitSimilarity(p, q, in, a, b, s);
  }
  double rss = 0;
  for (size_t k : in) rss += std::norm(a * p[k] + b - q[k]);
  out.rms = std::sqrt(rss / static_cast<double>(in.size()));
  out.inliers = in.size();
  const double th = std::arg(a);
  out.T.scale = s;
  out.T.R << std::cos(th), -std::sin(th), 0, std::sin(th), std::cos(th), 0, 0, 0, 1;
  double tz = 0;
  if (out.has_altitude) {
    std::vector<double> dz;
    for (size_t k : in) dz.push_back(fix[k].z() - s * cam[k].z());
    out.origin.z() = std::round(Median(dz));
    tz = Median(dz) - out.origin.z();
  }
  out.T.t = Eigen::Vector3d(b.real(), b.imag(), tz);
  return out;
}

}  // namespace mvtm
