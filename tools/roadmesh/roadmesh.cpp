#include "roadmesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "cli/progress.h"
#include "base/error.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "render/context.h"
#include "render/renderer.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

constexpr double kDefaultCameraHeight = 1.65;  // KITTI; used when too few points lie below
constexpr double kDefaultWall = 8.0;           // wall distance where no side has enough points
constexpr double kMaxWall = 30.0;
constexpr double kExtend = 30.0;     // corridor continues this far past both ends
constexpr double kWallWindow = 5.0;  // half-length (m) of the along-path wall window
constexpr size_t kMinGroundPoints = 10, kMinWallPoints = 5, kMinCellPoints = 3;

double Median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// One cross-section of the corridor: centre on the smoothed camera path, and a right-handed
// frame forward × left = up.
struct Station {
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::UnitX(),
                  l = Eigen::Vector3d::UnitY(), u = Eigen::Vector3d::UnitZ();
  double s = 0;  // arc length from the first station
};

// The camera path ordered along the road (distance from one end of the set: valid while the
// road turns by less than about 180°), pointing the way the cameras look, smoothed by a local
// linear fit, extended past both ends and resampled every `step` metres of arc length.
std::vector<Station> BuildPath(const std::vector<Eigen::Vector3d>& centres,
                               const std::vector<Eigen::Vector3d>& ups,
                               const std::vector<Eigen::Vector3d>& views, double step,
                               double& path_length) {
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
  // Forward is the way the cameras look: start from the other end when they look back.
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
  const double u0 = order.front().first, u1 = order.back().first;
  if (u1 - u0 < 1e-6) throw Error("the cameras do not move: no path to follow");
  std::vector<double> gaps;
  for (size_t i = 1; i < n; ++i) gaps.push_back(order[i].first - order[i - 1].first);
  const double sigma = std::max(2.0, 3.0 * Median(gaps));

  // Fine polyline every 0.5 m of the ordering parameter (weighted local linear fits).
  std::vector<Eigen::Vector3d> fine, fine_up;
  const int steps = std::max(2, static_cast<int>(std::ceil((u1 - u0) / 0.5)));
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
    Eigen::Vector3d p = det > 1e-12 * sw * sw ? Eigen::Vector3d((swxx * swy - swx * swxy) / det)
                                              : Eigen::Vector3d(swy / sw);
    fine.push_back(p);
    fine_up.push_back(up.normalized());
  }
  path_length = 0;
  for (size_t i = 1; i < fine.size(); ++i) path_length += (fine[i] - fine[i - 1]).norm();
  // Extend along the end tangents (cameras look past the last one).
  auto tangent = [&](size_t a, size_t b) {
    Eigen::Vector3d t = fine[b] - fine[a];
    return t.norm() > 1e-9 ? Eigen::Vector3d(t.normalized()) : Eigen::Vector3d::UnitX();
  };
  const size_t tail = std::min<size_t>(fine.size() - 1, 4);
  const Eigen::Vector3d t_begin = tangent(0, tail),
                        t_end = tangent(fine.size() - 1 - tail, fine.size() - 1);
  std::vector<Eigen::Vector3d> poly = {fine.front() - kExtend * t_begin},
                               poly_up = {fine_up.front()};
  poly.insert(poly.end(), fine.begin(), fine.end());
  poly_up.insert(poly_up.end(), fine_up.begin(), fine_up.end());
  poly.push_back(fine.back() + kExtend * t_end);
  poly_up.push_back(fine_up.back());

  // Resample by arc length.
  std::vector<double> acc = {0};
  for (size_t i = 1; i < poly.size(); ++i)
    acc.push_back(acc.back() + (poly[i] - poly[i - 1]).norm());
  std::vector<Station> st;
  const int count = static_cast<int>(std::floor(acc.back() / step)) + 1;
  size_t seg = 0;
  for (int k = 0; k < count; ++k) {
    const double s = k * step;
    while (seg + 2 < poly.size() && acc[seg + 1] < s) ++seg;
    const double len = acc[seg + 1] - acc[seg];
    const double a = len > 0 ? std::clamp((s - acc[seg]) / len, 0.0, 1.0) : 0.0;
    Station x;
    x.s = s;
    x.c = (1 - a) * poly[seg] + a * poly[seg + 1];
    x.u = ((1 - a) * poly_up[seg] + a * poly_up[seg + 1]).normalized();
    st.push_back(x);
  }
  for (size_t k = 0; k < st.size(); ++k) {
    const size_t a = k == 0 ? 0 : k - 1, b = std::min(st.size() - 1, k + 1);
    Eigen::Vector3d f = st[b].c - st[a].c;
    f -= f.dot(st[k].u) * st[k].u;  // forward lies in the plane normal to up
    if (f.norm() < 1e-9) throw Error("the camera path runs along the cameras' up axis");
    st[k].f = f.normalized();
    st[k].l = st[k].u.cross(st[k].f);
  }
  return st;
}

// A sparse point in the corridor's coordinates: station index, arc length, lateral offset (left
// positive) and height above the camera path.
struct Local {
  size_t k;
  double s, d, h;
};

std::vector<Local> ToLocal(const Reconstruction& rec, const std::vector<Station>& st) {
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
    if (bd > 60.0 * 60.0) continue;  // far from the corridor
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

}  // namespace

void RoadMeshOptions::Check() const {
  if (!(width > 0 && width <= 50)) throw UsageError("--width: must be in (0, 50] metres");
  if (!(wall_height > 0 && wall_height <= 200))
    throw UsageError("--wall-height: must be in (0, 200] metres");
  if (!(resolution >= 0.05 && resolution <= 5))
    throw UsageError("--resolution: must be in [0.05, 5] metres");
  ParseGlBackend(gl);
}

RoadMeshReport RunRoadMesh(const RoadMeshOptions& o) {
  o.Check();
  Workspace ws(o.workspace);
  std::vector<WsItem> needs = {WsItem::kSparse};
  if (!o.no_colours) needs.push_back(WsItem::kImages);
  ws.Require("roadmesh", needs);
  const fs::path existing = ws.MeshPath();
  if (fs::exists(existing) && !o.force)
    throw Error(existing.string(), 0, "a mesh exists already (--force replaces it)");
  // mesh.ply is the first name Workspace::MeshPath() looks for, so the new mesh wins.
  const fs::path out_path = ws.NewMeshPath();

  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  const auto images = rec.ImagesByName();
  RoadMeshReport rep;
  rep.images = images.size();
  rep.points = rec.points3D.size();
  if (images.size() < 2)
    throw Error(ws.SparseDir().string(), 0, "need at least two registered images to follow a path");
  std::vector<Eigen::Vector3d> centres, ups, views;
  std::vector<Rigid3d> poses;
  for (const ImageRecord* im : images) {
    Rigid3d p(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t);
    poses.push_back(p);
    centres.push_back(p.Centre());
    ups.push_back(-p.R().row(1).transpose());  // −y camera axis in the world
    views.push_back(p.ViewDirection());
  }

  const double res = o.resolution;
  std::vector<Station> st = BuildPath(centres, ups, views, res, rep.path_length);
  rep.stations = st.size();
  const std::vector<Local> pts = ToLocal(rec, st);

  // Camera height: points below the cameras, close to the path (the lane the car drives in:
  // cambered roads are higher towards their crown), else anywhere within the road.
  std::vector<double> below;
  for (double band : {o.width / 4, o.width / 2}) {
    below.clear();
    for (const Local& p : pts)
      if (std::abs(p.d) < band && p.h < -0.5 && p.h > -4.0) below.push_back(-p.h);
    if (below.size() >= kMinGroundPoints) break;
  }
  rep.ground_points = below.size() >= kMinGroundPoints ? below.size() : 0;
  const double cam_h = rep.ground_points ? Median(below) : kDefaultCameraHeight;
  rep.camera_height = cam_h;

  // Walls: median lateral distance of points above the ground, per window along the path.
  const double wall_min = o.width / 2 + 1;
  std::vector<std::vector<size_t>> by_station(st.size());
  for (size_t i = 0; i < pts.size(); ++i) by_station[pts[i].k].push_back(i);
  const int win = std::max(1, static_cast<int>(std::lround(kWallWindow / res)));
  std::vector<double> left(st.size()), right(st.size());
  for (long k = 0; k < long(st.size()); ++k) {
    std::vector<double> l, r;
    for (long j = std::max(0L, k - win); j <= std::min(long(st.size()) - 1, k + win); ++j)
      for (size_t i : by_station[size_t(j)]) {
        const Local& p = pts[i];
        if (p.h < -cam_h + 0.5 || p.h > -cam_h + o.wall_height + 5) continue;
        if (p.d > o.width / 2 && p.d < kMaxWall + 10) l.push_back(p.d);
        if (-p.d > o.width / 2 && -p.d < kMaxWall + 10) r.push_back(-p.d);
      }
    left[size_t(k)] = l.size() >= kMinWallPoints ? std::clamp(Median(l), wall_min, kMaxWall) : NAN;
    right[size_t(k)] = r.size() >= kMinWallPoints ? std::clamp(Median(r), wall_min, kMaxWall) : NAN;
  }
  const double fallback = std::clamp(kDefaultWall, wall_min, kMaxWall);
  FillGaps(left, fallback);
  FillGaps(right, fallback);
  left = SmoothAlong(left, win);
  right = SmoothAlong(right, win);
  rep.left_wall = Median(left);
  rep.right_wall = Median(right);

  // Ground height field: rows = stations, columns spread evenly from the right wall to the left.
  double span = 0;
  for (size_t k = 0; k < st.size(); ++k) span = std::max(span, left[k] + right[k]);
  const size_t cols = std::max<size_t>(2, static_cast<size_t>(std::ceil(span / res)));
  auto lateral = [&](size_t k, size_t j) {
    return -right[k] + (left[k] + right[k]) * double(j) / double(cols);
  };
  // Ground points: within 1 m of the ground plane, binned by station and 1 m lateral bins.
  const double radius = std::max(1.0, 2 * res);
  const int dbins = static_cast<int>(std::ceil(2 * (kMaxWall + 10) / radius));
  auto dbin = [&](double d) {
    return std::clamp(static_cast<int>(std::floor((d + kMaxWall + 10) / radius)), 0, dbins - 1);
  };
  std::vector<std::vector<std::vector<size_t>>> gbins(
      st.size(), std::vector<std::vector<size_t>>(size_t(dbins)));
  for (size_t i = 0; i < pts.size(); ++i)
    if (std::abs(pts[i].h + cam_h) < 1.0) gbins[pts[i].k][size_t(dbin(pts[i].d))].push_back(i);
  std::vector<double> field(st.size() * (cols + 1), -cam_h);
  std::vector<char> measured(field.size(), 0);
  const int srad = static_cast<int>(std::ceil(radius / res));
  for (long k = 0; k < long(st.size()); ++k)
    for (size_t j = 0; j <= cols; ++j) {
      const double d = lateral(size_t(k), j);
      std::vector<double> hs;
      for (long kk = std::max(0L, k - srad); kk <= std::min(long(st.size()) - 1, k + srad); ++kk)
        for (int b = std::max(0, dbin(d) - 1); b <= std::min(dbins - 1, dbin(d) + 1); ++b)
          for (size_t i : gbins[size_t(kk)][size_t(b)]) {
            const Local& p = pts[i];
            const double ds = p.s - st[size_t(k)].s, dd = p.d - d;
            if (ds * ds + dd * dd <= radius * radius) hs.push_back(p.h);
          }
      if (hs.size() >= kMinCellPoints) {
        field[size_t(k) * (cols + 1) + j] = Median(hs);
        measured[size_t(k) * (cols + 1) + j] = 1;
      }
    }
  // Smooth the field (two 3×3 box passes); unmeasured cells stay at the plane but blend in.
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<double> next(field.size());
    for (long k = 0; k < long(st.size()); ++k)
      for (long j = 0; j <= long(cols); ++j) {
        double s = 0;
        int c = 0;
        for (long a = std::max(0L, k - 1); a <= std::min(long(st.size()) - 1, k + 1); ++a)
          for (long b = std::max(0L, j - 1); b <= std::min(long(cols), j + 1); ++b)
            s += field[size_t(a) * (cols + 1) + size_t(b)], ++c;
        next[size_t(k) * (cols + 1) + size_t(j)] = s / c;
      }
    field.swap(next);
  }
  for (size_t i = 0; i < field.size(); ++i)
    rep.refined_vertices += std::abs(field[i] + cam_h) > 1e-3 || measured[i];

  // The mesh: ground grid, then the left and right walls (own vertices: a sharp crease).
  Mesh mesh;
  auto at = [&](size_t k, double d, double h) {
    return Eigen::Vector3d(st[k].c + d * st[k].l + h * st[k].u);
  };
  const size_t K = st.size();
  for (size_t k = 0; k < K; ++k)
    for (size_t j = 0; j <= cols; ++j)
      mesh.vertices.push_back(at(k, lateral(k, j), field[k * (cols + 1) + j]));
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
  const size_t rows = std::max<size_t>(1, static_cast<size_t>(std::ceil(o.wall_height / res)));
  for (int side = 0; side < 2; ++side) {
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.size()),
                   ww = static_cast<uint32_t>(rows + 1);
    for (size_t k = 0; k < K; ++k) {
      const size_t j = side == 0 ? cols : 0;
      const double d = side == 0 ? left[k] : -right[k], h0 = field[k * (cols + 1) + j];
      for (size_t m = 0; m <= rows; ++m)
        mesh.vertices.push_back(at(k, d, h0 + o.wall_height * double(m) / double(rows)));
    }
    // (s, up) counter-clockwise has normal −left: the left wall faces the road as is.
    for (uint32_t k = 0; k + 1 < K; ++k)
      for (uint32_t m = 0; m < rows; ++m)
        quad(base + k * ww + m, base + (k + 1) * ww + m, base + (k + 1) * ww + m + 1,
             base + k * ww + m + 1, side == 1);
  }
  mesh.ComputeNormals();
  rep.vertices = mesh.vertices.size();
  rep.faces = mesh.faces.size();

  if (!o.no_colours) {
    auto ctx = GlContext::Create(ParseGlBackend(o.gl));
    rep.gl = ctx->Describe();
    Renderer renderer(mesh);
    std::vector<Eigen::Vector3d> sum(mesh.vertices.size(), Eigen::Vector3d::Zero());
    std::vector<double> wsum(mesh.vertices.size(), 0.0);
    Progress bar("roadmesh", images.size(), o.quiet);
    for (size_t i = 0; i < images.size(); ++i) {
      const ImageRecord* im = images[i];
      Camera cam = rec.cameras.at(im->camera_id);
      cam.RequireUndistorted();
      const Image img = ReadImage(ws.SourceImagePath(im->name).string());
      if (uint64_t(img.width) != cam.width || uint64_t(img.height) != cam.height)
        cam = cam.Scaled(uint64_t(img.width), uint64_t(img.height));
      const Image depth = renderer.RenderDepth(View{cam, im->world_to_camera});
      const double scale = 255.0 / img.MaxValue();
      const int nc = img.channels >= 3 ? 3 : 1;
      for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        const Eigen::Vector3d x = poses[i] * mesh.vertices[v];
        if (x.z() < 0.1) continue;
        const Eigen::Vector2d px = cam.Project(x);
        const int ix = static_cast<int>(std::floor(px.x())),
                  iy = static_cast<int>(std::floor(px.y()));
        if (ix < 0 || iy < 0 || ix >= img.width || iy >= img.height) continue;
        // Visible when no surface is nearer: the farthest depth around the pixel absorbs
        // silhouettes and grazing angles.
        float dmax = 0;
        for (int yy = std::max(0, iy - 1); yy <= std::min(img.height - 1, iy + 1); ++yy)
          for (int xx = std::max(0, ix - 1); xx <= std::min(img.width - 1, ix + 1); ++xx) {
            const float z = depth.at(xx, yy);
            if (std::isfinite(z)) dmax = std::max(dmax, z);
          }
        if (x.z() > dmax * 1.01 + 0.02) continue;
        const Eigen::Vector3d to_cam = centres[i] - mesh.vertices[v];
        const double dist = to_cam.norm();
        const double cosv = mesh.normals[v].cast<double>().dot(to_cam) / dist;
        if (cosv <= 0.02) continue;
        const double w = cosv / dist;
        // Bilinear sample; pixel centres are at +0.5.
        const double fx = std::clamp(px.x() - 0.5, 0.0, img.width - 1.0),
                     fy = std::clamp(px.y() - 0.5, 0.0, img.height - 1.0);
        const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
        const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
        const double ax = fx - x0, ay = fy - y0;
        Eigen::Vector3d c;
        for (int ch = 0; ch < 3; ++ch) {
          const int cc = nc == 3 ? ch : 0;
          c[ch] = (1 - ay) * ((1 - ax) * img.at(x0, y0, cc) + ax * img.at(x1, y0, cc)) +
                  ay * ((1 - ax) * img.at(x0, y1, cc) + ax * img.at(x1, y1, cc));
        }
        sum[v] += w * scale * c;
        wsum[v] += w;
      }
      bar.Step();
    }
    mesh.colors.resize(mesh.vertices.size());
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      if (wsum[v] > 0) ++rep.coloured;
      for (int ch = 0; ch < 3; ++ch) {
        const double c = wsum[v] > 0 ? sum[v][ch] / wsum[v] : 128.0;  // unseen: mid grey
        mesh.colors[v][size_t(ch)] = static_cast<uint8_t>(std::lround(std::clamp(c, 0.0, 255.0)));
      }
    }
  }

  WriteMesh(out_path.string(), mesh);
  rep.mesh_path = out_path.string();
  std::vector<fs::path> inputs;
  for (const char* f : {"images", "cameras", "points3D"})
    for (const char* ext : {".txt", ".bin"})
      if (fs::exists(ws.SparseDir() / (std::string(f) + ext)))
        inputs.push_back(ws.SparseDir() / (std::string(f) + ext));
  nlohmann::json opts = {{"width", o.width},
                         {"wall_height", o.wall_height},
                         {"resolution", o.resolution},
                         {"no_colours", o.no_colours},
                         {"gl", rep.gl},
                         {"camera_height", rep.camera_height},
                         {"ground_points", rep.ground_points},
                         {"left_wall", rep.left_wall},
                         {"right_wall", rep.right_wall}};
  ws.WriteProvenance("roadmesh", opts, inputs);
  return rep;
}

}  // namespace mvtm
