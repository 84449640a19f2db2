#include "mesh/corridor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "base/error.h"
#include "base/stats.h"
#include "geometry/rigid.h"

namespace mvtm {

namespace {

// Lengths in metre-equivalents (times the unit in model units).
constexpr double kDefaultCameraHeight = 1.65;  // KITTI; used when too few points lie below
constexpr double kDefaultWall = 8.0;           // wall distance where no side has enough points
constexpr double kMaxWall = 30.0;
constexpr double kExtend = 30.0;     // corridor continues this far past both ends
constexpr double kWallWindow = 5.0;  // half-length of the along-path wall window
constexpr double kFarAway = 60.0;    // points farther from the path are ignored
constexpr double kPathStep = 0.5;    // spacing of the fine path in the ordering parameter
constexpr double kMinSigma = 2.0;    // smallest path smoothing sigma
constexpr size_t kMinGroundPoints = 10, kMinWallPoints = 5, kMinCellPoints = 3;

// The options in model units; `u` converts any other metre-equivalent.
struct Lengths {
  double u, width, wall_height, res;
  explicit Lengths(const CorridorOptions& o)
      : u(o.unit),
        width(o.width * o.unit),
        wall_height(o.wall_height * o.unit),
        res(o.resolution * o.unit) {}
};

// Counts from ratios of lengths: a 1e-9 tolerance, so a scaled model (whose ratios differ in the
// last bits) gets the same grid.
size_t CeilCount(double ratio) { return static_cast<size_t>(std::ceil(ratio - 1e-9)); }
size_t FloorCount(double ratio) { return static_cast<size_t>(std::floor(ratio + 1e-9)); }

// One cross-section of the corridor: centre on the smoothed camera path, and a right-handed
// frame forward × left = up.
struct Station {
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::UnitX(),
                  l = Eigen::Vector3d::UnitY(), u = Eigen::Vector3d::UnitZ();
  double s = 0;  // arc length from the first station
};

// A polyline with an up vector at each point.
struct Polyline {
  std::vector<Eigen::Vector3d> p, up;
};

// (distance along the road, image index), sorted. The distance is measured from one end of the
// set (valid while the road turns by less than about 180°); forward is the way the cameras look,
// so it starts from the other end when they look back.
std::vector<std::pair<double, size_t>> OrderAlongRoad(const std::vector<Eigen::Vector3d>& centres,
                                                      const std::vector<Eigen::Vector3d>& views) {
  const size_t n = centres.size();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : centres) mean += c;
  mean /= double(n);
  size_t end = 0;
  for (size_t i = 0; i < n; ++i)
    if ((centres[i] - mean).norm() > (centres[end] - mean).norm()) end = i;
  std::vector<std::pair<double, size_t>> order;
  for (size_t i = 0; i < n; ++i) order.emplace_back((centres[i] - centres[end]).norm(), i);
  std::sort(order.begin(), order.end());
  double ahead = 0;
  for (size_t i = 1; i < n; ++i) {
    const Eigen::Vector3d move = centres[order[i].second] - centres[order[i - 1].second];
    ahead += move.dot(views[order[i].second] + views[order[i - 1].second]);
  }
  if (ahead < 0) {
    size_t far = order.back().second;
    for (auto& [u, i] : order) u = (centres[i] - centres[far]).norm();
    std::sort(order.begin(), order.end());
  }
  return order;
}

// A fine polyline every kPathStep of the ordering parameter: weighted local linear fits of the
// centres. `unit`: model units per metre-equivalent.
Polyline SmoothPath(const std::vector<std::pair<double, size_t>>& order,
                    const std::vector<Eigen::Vector3d>& centres,
                    const std::vector<Eigen::Vector3d>& ups, double unit) {
  const size_t n = order.size();
  const double u0 = order.front().first, u1 = order.back().first;
  if (u1 - u0 < 1e-6 * unit) throw Error("the cameras do not move: no path to follow");
  std::vector<double> gaps;
  for (size_t i = 1; i < n; ++i) gaps.push_back(order[i].first - order[i - 1].first);
  const double sigma = std::max(kMinSigma * unit, 3.0 * Median(gaps));

  Polyline fine;
  const int steps = std::max(2, static_cast<int>(CeilCount((u1 - u0) / (kPathStep * unit))));
  for (int k = 0; k <= steps; ++k) {
    const double u = u0 + (u1 - u0) * k / steps;
    double sw = 0, swx = 0, swxx = 0;
    Eigen::Vector3d swy = Eigen::Vector3d::Zero(), swxy = Eigen::Vector3d::Zero(),
                    up = Eigen::Vector3d::Zero();
    for (const auto& [ui, i] : order) {
      const double x = ui - u, w = std::exp(-0.5 * x * x / (sigma * sigma));
      sw += w, swx += w * x, swxx += w * x * x;
      swy += w * centres[i], swxy += w * x * centres[i];
      up += w * ups[i];
    }
    const double det = sw * swxx - swx * swx;
    // Intercept of the weighted line fit (unbiased at the ends, unlike a weighted mean).
    Eigen::Vector3d p = det > 1e-12 * sw * sw * unit * unit
                            ? Eigen::Vector3d((swxx * swy - swx * swxy) / det)
                            : Eigen::Vector3d(swy / sw);
    fine.p.push_back(p);
    fine.up.push_back(up.normalized());
  }
  return fine;
}

// Extends the path by kExtend along its end tangents (cameras look past the last one).
Polyline Extend(const Polyline& fine, double unit) {
  auto tangent = [&](size_t a, size_t b) {
    Eigen::Vector3d t = fine.p[b] - fine.p[a];
    return t.norm() > 1e-9 * unit ? Eigen::Vector3d(t.normalized()) : Eigen::Vector3d::UnitX();
  };
  const size_t last = fine.p.size() - 1, tail = std::min<size_t>(last, 4);
  const Eigen::Vector3d t_begin = tangent(0, tail), t_end = tangent(last - tail, last);
  const double extend = kExtend * unit;
  Polyline poly{{fine.p.front() - extend * t_begin}, {fine.up.front()}};
  poly.p.insert(poly.p.end(), fine.p.begin(), fine.p.end());
  poly.up.insert(poly.up.end(), fine.up.begin(), fine.up.end());
  poly.p.push_back(fine.p.back() + extend * t_end);
  poly.up.push_back(fine.up.back());
  return poly;
}

// Stations every `step` of arc length along `poly`, with their frames; `unit` as in SmoothPath.
std::vector<Station> Resample(const Polyline& poly, double step, double unit) {
  std::vector<double> acc = {0};
  for (size_t i = 1; i < poly.p.size(); ++i)
    acc.push_back(acc.back() + (poly.p[i] - poly.p[i - 1]).norm());
  std::vector<Station> st;
  const int count = static_cast<int>(FloorCount(acc.back() / step)) + 1;
  size_t seg = 0;
  for (int k = 0; k < count; ++k) {
    const double s = k * step;
    while (seg + 2 < poly.p.size() && acc[seg + 1] < s) ++seg;
    const double len = acc[seg + 1] - acc[seg];
    const double a = len > 0 ? std::clamp((s - acc[seg]) / len, 0.0, 1.0) : 0.0;
    Station x;
    x.s = s;
    x.c = (1 - a) * poly.p[seg] + a * poly.p[seg + 1];
    x.u = ((1 - a) * poly.up[seg] + a * poly.up[seg + 1]).normalized();
    st.push_back(x);
  }
  for (size_t k = 0; k < st.size(); ++k) {
    const size_t a = k == 0 ? 0 : k - 1, b = std::min(st.size() - 1, k + 1);
    Eigen::Vector3d f = st[b].c - st[a].c;
    f -= f.dot(st[k].u) * st[k].u;  // forward lies in the plane normal to up
    if (f.norm() < 1e-9 * unit) throw Error("the camera path runs along the cameras' up axis");
    st[k].f = f.normalized();
    st[k].l = st[k].u.cross(st[k].f);
  }
  return st;
}

// The camera path ordered along the road, smoothed, extended past both ends and resampled every
// `len.res` of arc length; `path_length` is the smoothed length without the extensions.
std::vector<Station> BuildPath(const std::vector<Eigen::Vector3d>& centres,
                               const std::vector<Eigen::Vector3d>& ups,
                               const std::vector<Eigen::Vector3d>& views, const Lengths& len,
                               double& path_length) {
  const Polyline fine = SmoothPath(OrderAlongRoad(centres, views), centres, ups, len.u);
  path_length = 0;
  for (size_t i = 1; i < fine.p.size(); ++i) path_length += (fine.p[i] - fine.p[i - 1]).norm();
  return Resample(Extend(fine, len.u), len.res, len.u);
}

// A sparse point in the corridor's coordinates: station index, arc length, lateral offset (left
// positive) and height above the camera path.
struct Local {
  size_t k;
  double s, d, h;
};

std::vector<Local> ToLocal(const Reconstruction& rec, const std::vector<Station>& st, double unit) {
  const double far = kFarAway * unit;
  std::vector<Local> out;
  out.reserve(rec.points3D.size());
  for (const auto& [id, p] : rec.points3D) {
    size_t best = 0;
    double bd = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < st.size(); ++k) {
      const double dd = (p.xyz - st[k].c).squaredNorm();
      if (dd < bd) bd = dd, best = k;
    }
    const Eigen::Vector3d a = p.xyz - st[best].c;
    const double along = a.dot(st[best].f);
    if (bd > far * far) continue;  // far from the corridor
    out.push_back({best, st[best].s + along, a.dot(st[best].l), a.dot(st[best].u)});
  }
  return out;
}

// Fills NaN entries by linear interpolation between valid neighbours (constant past the ends),
// or with `fallback` when nothing is valid.
void FillGaps(std::vector<double>& v, double fallback) {
  std::vector<size_t> valid;
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isnan(v[i])) valid.push_back(i);
  if (valid.empty()) {
    std::fill(v.begin(), v.end(), fallback);
    return;
  }
  for (size_t i = 0; i < v.size(); ++i) {
    if (!std::isnan(v[i])) continue;
    auto it = std::lower_bound(valid.begin(), valid.end(), i);
    if (it == valid.begin())
      v[i] = v[*it];
    else if (it == valid.end())
      v[i] = v[valid.back()];
    else {
      const size_t b = *it, a = *(it - 1);
      v[i] = v[a] + (v[b] - v[a]) * double(i - a) / double(b - a);
    }
  }
}

std::vector<double> SmoothAlong(const std::vector<double>& v, int radius) {
  std::vector<double> out(v.size());
  for (long i = 0; i < long(v.size()); ++i) {
    double s = 0;
    int c = 0;
    for (long j = std::max(0L, i - radius); j <= std::min(long(v.size()) - 1, i + radius); ++j)
      s += v[size_t(j)], ++c;
    out[size_t(i)] = s / c;
  }
  return out;
}

// Camera height: points below the cameras, close to the path (the lane the car drives in:
// cambered roads are higher towards their crown), else anywhere within the road. Sets
// camera_height and ground_points.
void FitCameraHeight(const std::vector<Local>& pts, const Lengths& len, Corridor& out) {
  std::vector<double> below;
  const double top = -0.5 * len.u, bottom = -4.0 * len.u;
  for (double band : {len.width / 4, len.width / 2}) {
    below.clear();
    for (const Local& p : pts)
      if (std::abs(p.d) < band && p.h < top && p.h > bottom) below.push_back(-p.h);
    if (below.size() >= kMinGroundPoints) break;
  }
  out.ground_points = below.size() >= kMinGroundPoints ? below.size() : 0;
  out.camera_height = out.ground_points ? Median(below) : kDefaultCameraHeight * len.u;
}

// The ground below the path: wall distances per station and a height field between the walls.
struct Ground {
  std::vector<double> left, right;  // wall distances per station
  size_t cols = 0;                  // grid columns from the right wall to the left
  std::vector<double> height;       // stations × (cols + 1) heights above the path
  std::vector<char> measured;       // the same grid: height from the points

  double Lateral(size_t k, size_t j) const {
    return -right[k] + (left[k] + right[k]) * double(j) / double(cols);
  }
};

// Walls: median lateral distance of points above the ground, per window along the path.
// `options` only for the window in stations (a ratio of lengths).
void FitWalls(const std::vector<Station>& st, const std::vector<Local>& pts, double cam_h,
              const CorridorOptions& o, Ground& g) {
  const Lengths len(o);
  const double wall_min = (o.width / 2 + 1) * len.u, wall_max = kMaxWall * len.u;
  const double beyond = (kMaxWall + 10) * len.u, low = -cam_h + 0.5 * len.u,
               high = -cam_h + len.wall_height + 5 * len.u;
  std::vector<std::vector<size_t>> by_station(st.size());
  for (size_t i = 0; i < pts.size(); ++i) by_station[pts[i].k].push_back(i);
  const int win = std::max(1, static_cast<int>(std::lround(kWallWindow / o.resolution)));
  std::vector<double> left(st.size()), right(st.size());
  for (long k = 0; k < long(st.size()); ++k) {
    std::vector<double> l, r;
    for (long j = std::max(0L, k - win); j <= std::min(long(st.size()) - 1, k + win); ++j)
      for (size_t i : by_station[size_t(j)]) {
        const Local& p = pts[i];
        if (p.h < low || p.h > high) continue;
        if (p.d > len.width / 2 && p.d < beyond) l.push_back(p.d);
        if (-p.d > len.width / 2 && -p.d < beyond) r.push_back(-p.d);
      }
    left[size_t(k)] = l.size() >= kMinWallPoints ? std::clamp(Median(l), wall_min, wall_max) : NAN;
    right[size_t(k)] = r.size() >= kMinWallPoints ? std::clamp(Median(r), wall_min, wall_max) : NAN;
  }
  const double fallback = std::clamp(kDefaultWall * len.u, wall_min, wall_max);
  FillGaps(left, fallback);
  FillGaps(right, fallback);
  g.left = SmoothAlong(left, win);
  g.right = SmoothAlong(right, win);
}

// Ground height field: rows = stations, columns spread evenly from the right wall to the left;
// each vertex the median height of the ground points (within 1 of the ground plane) around it.
// The bin and search counts come from the options (ratios of lengths), the rest in model units.
void MeasureGround(const std::vector<Station>& st, const std::vector<Local>& pts, double cam_h,
                   const CorridorOptions& o, Ground& g) {
  const Lengths len(o);
  const double res = len.res;
  double span = 0;
  for (size_t k = 0; k < st.size(); ++k) span = std::max(span, g.left[k] + g.right[k]);
  const size_t cols = g.cols = std::max<size_t>(2, CeilCount(span / res));
  // Ground points binned by station and lateral bins of the search radius.
  const double radius_m = std::max(1.0, 2 * o.resolution), radius = radius_m * len.u;
  const double wall_max = kMaxWall * len.u, margin = 10 * len.u, band = 1.0 * len.u;
  const int dbins = static_cast<int>(std::ceil(2 * (kMaxWall + 10) / radius_m));
  auto dbin = [&](double d) {
    return std::clamp(static_cast<int>(std::floor((d + wall_max + margin) / radius)), 0, dbins - 1);
  };
  std::vector<std::vector<std::vector<size_t>>> gbins(
      st.size(), std::vector<std::vector<size_t>>(size_t(dbins)));
  for (size_t i = 0; i < pts.size(); ++i)
    if (std::abs(pts[i].h + cam_h) < band) gbins[pts[i].k][size_t(dbin(pts[i].d))].push_back(i);
  g.height.assign(st.size() * (cols + 1), -cam_h);
  g.measured.assign(g.height.size(), 0);
  const int srad = static_cast<int>(std::ceil(radius_m / o.resolution));
  for (long k = 0; k < long(st.size()); ++k)
    for (size_t j = 0; j <= cols; ++j) {
      const double d = g.Lateral(size_t(k), j);
      std::vector<double> hs;
      for (long kk = std::max(0L, k - srad); kk <= std::min(long(st.size()) - 1, k + srad); ++kk)
        for (int b = std::max(0, dbin(d) - 1); b <= std::min(dbins - 1, dbin(d) + 1); ++b)
          for (size_t i : gbins[size_t(kk)][size_t(b)]) {
            const Local& p = pts[i];
            const double ds = p.s - st[size_t(k)].s, dd = p.d - d;
            if (ds * ds + dd * dd <= radius * radius) hs.push_back(p.h);
          }
      if (hs.size() >= kMinCellPoints) {
        g.height[size_t(k) * (cols + 1) + j] = Median(hs);
        g.measured[size_t(k) * (cols + 1) + j] = 1;
      }
    }
}

// Smooths the field (two 3×3 box passes); unmeasured cells stay at the plane but blend in.
// Returns the number of ground vertices off the plane (by 1e-3 × unit) or measured.
size_t SmoothGround(size_t stations, double cam_h, double unit, Ground& g) {
  const size_t cols = g.cols;
  std::vector<double>& field = g.height;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<double> next(field.size());
    for (long k = 0; k < long(stations); ++k)
      for (long j = 0; j <= long(cols); ++j) {
        double s = 0;
        int c = 0;
        for (long a = std::max(0L, k - 1); a <= std::min(long(stations) - 1, k + 1); ++a)
          for (long b = std::max(0L, j - 1); b <= std::min(long(cols), j + 1); ++b)
            s += field[size_t(a) * (cols + 1) + size_t(b)], ++c;
        next[size_t(k) * (cols + 1) + size_t(j)] = s / c;
      }
    field.swap(next);
  }
  size_t refined = 0;
  for (size_t i = 0; i < field.size(); ++i)
    refined += std::abs(field[i] + cam_h) > 1e-3 * unit || g.measured[i];
  return refined;
}

// The mesh: ground grid, then the left and right walls (own vertices: a sharp crease).
Mesh CorridorMesh(const std::vector<Station>& st, const Ground& g, const CorridorOptions& o) {
  Mesh mesh;
  auto at = [&](size_t k, double d, double h) {
    return Eigen::Vector3d(st[k].c + d * st[k].l + h * st[k].u);
  };
  const size_t K = st.size(), cols = g.cols;
  for (size_t k = 0; k < K; ++k)
    for (size_t j = 0; j <= cols; ++j)
      mesh.vertices.push_back(at(k, g.Lateral(k, j), g.height[k * (cols + 1) + j]));
  auto quad = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t d, bool flip) {
    if (!flip) {
      mesh.faces.push_back({a, b, c});
      mesh.faces.push_back({a, c, d});
    } else {
      mesh.faces.push_back({a, c, b});
      mesh.faces.push_back({a, d, c});
    }
  };
  const uint32_t gw = static_cast<uint32_t>(cols + 1);
  for (uint32_t k = 0; k + 1 < K; ++k)
    for (uint32_t j = 0; j < cols; ++j)  // (s, d) counter-clockwise seen from above: normal up
      quad(k * gw + j, (k + 1) * gw + j, (k + 1) * gw + j + 1, k * gw + j + 1, false);
  const size_t rows =
      std::max<size_t>(1, static_cast<size_t>(std::ceil(o.wall_height / o.resolution)));
  const double wall_height = o.wall_height * o.unit;
  for (int side = 0; side < 2; ++side) {
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.size()),
                   ww = static_cast<uint32_t>(rows + 1);
    for (size_t k = 0; k < K; ++k) {
      const size_t j = side == 0 ? cols : 0;
      const double d = side == 0 ? g.left[k] : -g.right[k], h0 = g.height[k * (cols + 1) + j];
      for (size_t m = 0; m <= rows; ++m)
        mesh.vertices.push_back(at(k, d, h0 + wall_height * double(m) / double(rows)));
    }
    // (s, up) counter-clockwise has normal −left: the left wall faces the road as is.
    for (uint32_t k = 0; k + 1 < K; ++k)
      for (uint32_t m = 0; m < rows; ++m)
        quad(base + k * ww + m, base + (k + 1) * ww + m, base + (k + 1) * ww + m + 1,
             base + k * ww + m + 1, side == 1);
  }
  mesh.ComputeNormals();
  return mesh;
}

}  // namespace

Corridor BuildCorridor(const Reconstruction& rec, const CorridorOptions& o) {
  const auto images = rec.ImagesByName();
  if (images.size() < 2) throw Error("need at least two registered images to follow a path");
  std::vector<Eigen::Vector3d> centres, ups, views;
  for (const ImageRecord* im : images) {
    const Rigid3d p(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t);
    centres.push_back(p.Centre());
    ups.push_back(p.Up());
    views.push_back(p.ViewDirection());
  }
  Corridor c;
  const Lengths len(o);
  const std::vector<Station> st = BuildPath(centres, ups, views, len, c.path_length);
  c.stations = st.size();
  const std::vector<Local> pts = ToLocal(rec, st, len.u);
  FitCameraHeight(pts, len, c);
  Ground g;
  FitWalls(st, pts, c.camera_height, o, g);
  c.left_wall = Median(g.left);
  c.right_wall = Median(g.right);
  MeasureGround(st, pts, c.camera_height, o, g);
  c.refined_vertices = SmoothGround(st.size(), c.camera_height, len.u, g);
  c.mesh = CorridorMesh(st, g, o);
  return c;
}

}  // namespace mvtm
