#include "mesh/merge.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>
#include <vector>

#include "base/error.h"
#include "base/stats.h"
#include "raycast/mesh_raycaster.h"

namespace mvtm {

namespace {

Eigen::Vector3d FaceNormal(const Mesh& m, const std::array<uint32_t, 3>& f) {
  return (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]);
}

Eigen::Vector3d Centroid(const Mesh& m, const std::array<uint32_t, 3>& f) {
  return (m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) / 3.0;
}

// A grid cell's key from its two integer coordinates (unsigned: no shift of a negative value).
uint64_t CellKey(int64_t ia, int64_t ib) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(static_cast<int32_t>(ia))) << 32) |
         static_cast<uint32_t>(static_cast<int32_t>(ib));
}

// Each proxy face once: 0 degenerate, 1 wall, 2 ground (normal within 45° of unit `u`).
std::vector<uint8_t> ProxyFaceKinds(const Mesh& proxy, const Eigen::Vector3d& u) {
  std::vector<uint8_t> kind(proxy.faces.size(), 0);
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    const Eigen::Vector3d n = FaceNormal(proxy, proxy.faces[i]);
    if (n.norm() > 0) kind[i] = n.normalized().dot(u) >= std::cos(M_PI / 4) ? 2 : 1;
  }
  return kind;
}

// Coordinates across and along unit `u`, relative to `o` (UTM-sized coordinates keep their
// precision), and square grid cells of side `cell` across it.
struct UpFrame {
  UpFrame(const Eigen::Vector3d& up, const Eigen::Vector3d& origin, double cell_side)
      : u(up), e1(up.unitOrthogonal()), e2(up.cross(e1)), o(origin), cell(cell_side) {}
  Eigen::Vector2d Direction(const Eigen::Vector3d& d) const { return {d.dot(e1), d.dot(e2)}; }
  Eigen::Vector2d Across(const Eigen::Vector3d& p) const { return Direction(p - o); }
  double Height(const Eigen::Vector3d& p) const { return (p - o).dot(u); }
  int64_t Index(double a) const { return static_cast<int64_t>(std::floor(a / cell)); }
  uint64_t Cell(const Eigen::Vector2d& a) const { return CellKey(Index(a.x()), Index(a.y())); }
  // The cell of `a` and its 8 neighbours (rows of the first coordinate, then the second).
  std::array<uint64_t, 9> CellsAround(const Eigen::Vector2d& a) const {
    std::array<uint64_t, 9> keys{};
    for (int64_t i = -1, k = 0; i <= 1; ++i)
      for (int64_t j = -1; j <= 1; ++j)
        keys[size_t(k++)] = CellKey(Index(a.x()) + i, Index(a.y()) + j);
    return keys;
  }
  Eigen::Vector3d u, e1, e2, o;
  double cell;
};

// The frame of a proxy: its first vertex as the origin.
UpFrame ProxyFrame(const Mesh& proxy, const Eigen::Vector3d& u, double cell) {
  return {u, proxy.vertices.empty() ? Eigen::Vector3d::Zero() : proxy.vertices[0], cell};
}

}  // namespace

double ProxyGroundAbove(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                        double reach, double bound) {
  if (!(up.norm() > 0) || !(reach > 0) || !(bound > 0))
    throw Error("merge: the up direction, reach and bound must be non-zero");
  const Eigen::Vector3d u = up.normalized();
  // The proxy's ground face centroids in cells of `reach` across `up`.
  const UpFrame frame = ProxyFrame(proxy, u, reach);
  const std::vector<uint8_t> kind = ProxyFaceKinds(proxy, u);
  std::unordered_map<uint64_t, std::vector<Eigen::Vector3d>> grid;  // (a, b, height)
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    if (kind[i] != 2) continue;
    const Eigen::Vector3d c = Centroid(proxy, proxy.faces[i]);
    const Eigen::Vector2d a = frame.Across(c);
    grid[frame.Cell(a)].push_back({a.x(), a.y(), frame.Height(c)});
  }
  std::vector<double> h;
  for (const auto& f : dense.faces) {
    const Eigen::Vector3d n = FaceNormal(dense, f);
    if (!(n.norm() > 0) || std::abs(n.normalized().dot(u)) < std::cos(M_PI / 6)) continue;
    const Eigen::Vector3d c = Centroid(dense, f);
    const Eigen::Vector2d ab = frame.Across(c);
    const double a = ab.x(), b = ab.y();
    double best = reach * reach, height = 0;
    bool found = false;
    for (uint64_t key : frame.CellsAround(ab)) {
      auto it = grid.find(key);
      if (it == grid.end()) continue;
      for (const Eigen::Vector3d& p : it->second) {
        const double d2 = (p.x() - a) * (p.x() - a) + (p.y() - b) * (p.y() - b);
        if (d2 <= best) best = d2, height = p.z(), found = true;
      }
    }
    const double above = height - frame.Height(c);
    if (found && std::abs(above) <= bound) h.push_back(above);
  }
  return h.size() < 50 ? 0.0 : Median(std::move(h));
}

namespace {

// The dense surface's near-vertical faces (normal within 60° of horizontal) in the frame's cells
// across up: position and unit normal across up, height along it.
class FacadeGrid {
 public:
  FacadeGrid(const Mesh& dense, const UpFrame& frame) : frame_(frame) {
    for (const auto& f : dense.faces) {
      const Eigen::Vector3d n = FaceNormal(dense, f);
      const Eigen::Vector2d nh = frame_.Direction(n);
      if (!(n.norm() > 0) || nh.norm() < std::cos(M_PI / 3) * n.norm()) continue;
      const Eigen::Vector3d c = Centroid(dense, f);
      const Eigen::Vector2d at = frame_.Across(c);
      grid_[frame_.Cell(at)].push_back({at, nh.normalized(), frame_.Height(c)});
    }
  }

  // (distance behind, height) of the faces facing a wall at `at` with unit normal `wn` (towards
  // the path): within 45° of it, within search.reach along it, from search.front in front to
  // search.back behind; found in the cells along the line across the wall and one either side.
  std::vector<Eigen::Vector2d> Column(const Eigen::Vector2d& at, const Eigen::Vector2d& wn,
                                      const FacadeSearch& search) const {
    std::set<uint64_t> cells;
    for (double t = -search.front;; t += frame_.cell / 4) {  // no face within reach falls between
      for (uint64_t key : frame_.CellsAround(at - std::min(t, search.back) * wn)) cells.insert(key);
      if (t >= search.back) break;
    }
    const Eigen::Vector2d along(-wn.y(), wn.x());
    std::vector<Eigen::Vector2d> found;
    for (uint64_t k : cells) {
      auto it = grid_.find(k);
      if (it == grid_.end()) continue;
      for (const Face& fc : it->second) {
        if (std::abs(fc.normal.dot(wn)) < std::cos(M_PI / 4)) continue;
        const Eigen::Vector2d d = fc.at - at;
        const double b = -d.dot(wn);
        if (std::abs(d.dot(along)) <= search.reach && b >= -search.front && b <= search.back)
          found.emplace_back(b, fc.height);
      }
    }
    return found;
  }

 private:
  struct Face {
    Eigen::Vector2d at, normal;
    double height;
  };
  const UpFrame frame_;
  std::unordered_map<uint64_t, std::vector<Face>> grid_;
};

}  // namespace

std::vector<double> DenseFacadeBehindWalls(const Mesh& dense, const Mesh& proxy,
                                           const Eigen::Vector3d& up, const FacadeSearch& search) {
  if (!(up.norm() > 0) || !(search.reach > 0) || !(search.rise > 0) || !(search.front >= 0) ||
      !(search.back >= 0) || !std::isfinite(search.front + search.back) || !(search.spread >= 0) ||
      !(search.quantile >= 0) || !(search.quantile <= 1))
    throw Error(
        "merge: the facade search needs up, reach and rise > 0, finite front and back >= 0, "
        "spread >= 0, quantile in [0, 1]");
  if (!proxy.has_normals()) throw Error("merge: the proxy has no vertex normals");
  const Eigen::Vector3d u = up.normalized();
  const UpFrame frame = ProxyFrame(proxy, u, search.reach);
  const FacadeGrid grid(dense, frame);
  std::vector<double> out(proxy.vertices.size(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<uint8_t> kind = ProxyFaceKinds(proxy, u);
  std::vector<bool> wall(proxy.vertices.size(), false);
  for (size_t i = 0; i < proxy.faces.size(); ++i)
    if (kind[i] == 1)
      for (uint32_t v : proxy.faces[i]) wall[v] = true;
  // A wall's column (its vertices at one place across up, one normal) gathers its faces once;
  // each vertex keeps those within `rise` of its height.
  std::map<std::array<int64_t, 4>, std::vector<Eigen::Vector2d>> columns;
  const double q = search.reach * 1e-6;
  std::vector<double> behind;
  for (size_t v = 0; v < proxy.vertices.size(); ++v) {
    Eigen::Vector2d wn = frame.Direction(proxy.normals[v].cast<double>());
    if (!wall[v] || !(wn.norm() > 0)) continue;
    wn.normalize();
    const Eigen::Vector2d at = frame.Across(proxy.vertices[v]);
    const std::array<int64_t, 4> place{std::llround(at.x() / q), std::llround(at.y() / q),
                                       std::llround(wn.x() * 1e6), std::llround(wn.y() * 1e6)};
    auto column = columns.find(place);
    if (column == columns.end()) column = columns.emplace(place, grid.Column(at, wn, search)).first;
    const double height = frame.Height(proxy.vertices[v]);
    behind.clear();
    for (const Eigen::Vector2d& f : column->second)
      if (std::abs(f.y() - height) <= search.rise) behind.push_back(f.x());
    if (behind.size() >= std::max<size_t>(search.min_faces, 1) &&
        Percentile(behind, 0.75) - Percentile(behind, 0.25) <= search.spread)
      out[v] = Percentile(behind, search.quantile);
  }
  return out;
}

Mesh MergeProxyBehind(const Mesh& dense, const Mesh& proxy, const Eigen::Vector3d& up,
                      double ground_below, double walls_behind, MergeReport* report,
                      const std::vector<double>& wall_offsets) {
  if (!(ground_below >= 0) || !std::isfinite(ground_below) || !std::isfinite(walls_behind))
    throw Error("merge: the offsets must be finite lengths, ground_below >= 0");
  if (!(up.norm() > 0)) throw Error("merge: the up direction is zero");
  if (walls_behind >= 0 && (walls_behind > 0 || !wall_offsets.empty()) && !proxy.has_normals())
    throw Error("merge: the proxy has no vertex normals");
  if (!wall_offsets.empty() && wall_offsets.size() != proxy.vertices.size())
    throw Error("merge: one wall offset per proxy vertex");
  const Eigen::Vector3d u = up.normalized();
  // A wall moved back leaves a gap above the ground's edge through which a ray would see
  // nothing; the wall's foot (its vertices where the ground's edge is) goes down by as much as
  // the wall goes back, which closes the gap for every camera farther from the wall than it is
  // high above the ground (the gap's far side is then at most walls_behind below the ground).
  std::set<std::array<float, 3>> ground_points;
  auto key = [&](uint32_t v) {
    const Eigen::Vector3f p = proxy.vertices[v].cast<float>();
    return std::array<float, 3>{p.x(), p.y(), p.z()};
  };
  // Degenerate faces are dropped.
  const std::vector<uint8_t> kind = ProxyFaceKinds(proxy, u);
  if (walls_behind >= 0 && (walls_behind > 0 || ground_below > 0 || !wall_offsets.empty()))
    for (size_t i = 0; i < proxy.faces.size(); ++i)
      if (kind[i] == 2)
        for (uint32_t v : proxy.faces[i]) ground_points.insert(key(v));
  Mesh out;
  out.vertices = dense.vertices;
  out.faces = dense.faces;
  out.face_kinds = dense.has_face_kinds() ? dense.face_kinds
                                          : std::vector<uint8_t>(dense.faces.size(), kFaceObserved);
  std::map<uint32_t, uint32_t> index;  // proxy vertex → output vertex (shared within a part)
  auto vertex = [&](uint32_t v, bool ground) {
    auto it = index.find(v);
    if (it != index.end()) return it->second;
    const double back =
        !wall_offsets.empty() && std::isfinite(wall_offsets[v]) ? wall_offsets[v] : walls_behind;
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();  // a wall not moved needs no normals
    if (ground)
      shift = -ground_below * u;
    else if (back != 0)
      shift = -back * proxy.normals[v].cast<double>();
    if (!ground && ground_points.count(key(v)))  // the wall's foot: as far down as either went
      shift -= std::max({back, ground_below, 0.0}) * u;
    out.vertices.push_back(proxy.vertices[v] + shift);
    return index[v] = static_cast<uint32_t>(out.vertices.size() - 1);
  };
  MergeReport r;
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    const auto& f = proxy.faces[i];
    if (kind[i] == 0) continue;
    const bool ground = kind[i] == 2;
    if (!ground && walls_behind < 0) continue;
    out.faces.push_back({vertex(f[0], ground), vertex(f[1], ground), vertex(f[2], ground)});
    out.face_kinds.push_back(ground ? kFaceFillGround : kFaceFillWall);
    ++(ground ? r.ground_faces : r.wall_faces);
  }
  out.ComputeNormals();
  if (report) *report = r;
  return out;
}

namespace {

// The walls of a proxy: for each vertex, the wall it belongs to (wall faces connected through
// shared vertices), or -1 for a vertex of no wall face.
std::vector<int64_t> WallComponents(const Mesh& proxy, const std::vector<uint8_t>& kind) {
  std::vector<int64_t> parent(proxy.vertices.size(), -1);
  auto root = [&](int64_t v) {
    while (parent[size_t(v)] != v) v = parent[size_t(v)] = parent[size_t(parent[size_t(v)])];
    return v;
  };
  for (size_t i = 0; i < proxy.faces.size(); ++i) {
    if (kind[i] != 1) continue;
    for (uint32_t v : proxy.faces[i])
      if (parent[v] < 0) parent[v] = v;
    for (int k = 1; k < 3; ++k) parent[size_t(root(proxy.faces[i][k]))] = root(proxy.faces[i][0]);
  }
  for (size_t v = 0; v < parent.size(); ++v)
    if (parent[v] >= 0) parent[v] = root(int64_t(v));
  return parent;
}

// Gives each wall vertex without a value (NaN in `out`) the median of the values of its wall's
// vertices within `near` of it across up (its column above and below it, whatever the wall's
// lean, and its neighbours'), else of its wall; a wall with no value stays NaN.
void FillUnseenWalls(const Mesh& proxy, const UpFrame& frame, const std::vector<int64_t>& wall,
                     double near, std::vector<double>& out) {
  std::unordered_map<uint64_t, std::vector<size_t>> grid;  // valued vertices by cell
  std::map<int64_t, std::vector<double>> by_wall;
  for (size_t v = 0; v < out.size(); ++v)
    if (wall[v] >= 0 && std::isfinite(out[v])) {
      grid[frame.Cell(frame.Across(proxy.vertices[v]))].push_back(v);
      by_wall[wall[v]].push_back(out[v]);
    }
  std::map<int64_t, double> wall_median;
  for (auto& [k, values] : by_wall) wall_median[k] = Median(values);
  // Only the vertices valued before the fill are read (the grid holds no other), so filling in
  // place does not depend on the order.
  std::vector<double> column;
  for (size_t v = 0; v < out.size(); ++v) {
    if (wall[v] < 0 || std::isfinite(out[v])) continue;
    const Eigen::Vector2d at = frame.Across(proxy.vertices[v]);
    column.clear();
    for (uint64_t key : frame.CellsAround(at)) {
      auto it = grid.find(key);
      if (it == grid.end()) continue;
      for (size_t w : it->second)
        if (wall[w] == wall[v] && (frame.Across(proxy.vertices[w]) - at).norm() <= near)
          column.push_back(out[w]);
    }
    if (!column.empty())
      out[v] = Median(column);
    else if (auto w = wall_median.find(wall[v]); w != wall_median.end())
      out[v] = w->second;
  }
}

// A sight that met a wall before its point: where (across up, height), how far behind the wall
// its point lies, and whether the dense surface is there (covered) or not (a hole).
struct WallSample {
  Eigen::Vector2d at;
  double height = 0, behind = NAN;
  bool covered = false;
};

std::vector<WallSample> SampleWalls(const Mesh& proxy, const std::vector<uint8_t>& kind,
                                    const UpFrame& frame, const std::vector<Sight>& sights,
                                    const Mesh& dense, const SeenWallSearch& s) {
  const MeshRaycaster walls(proxy), fused(dense);
  std::vector<WallSample> out(sights.size());
  tbb::parallel_for(size_t{0}, sights.size(), [&](size_t i) {
    const Eigen::Vector3d d = sights[i].point - sights[i].origin;
    if (!(d.norm() > 0) || !d.allFinite()) return;
    const auto h = walls.Closest(sights[i].origin, d, 0, 1);
    if (!h || kind[h->triangle] != 1) return;
    // The dense surface in front of the wall hides it there: no sample. Between the wall and the
    // point (well before the point: this photo saw past it), it is what the wall must not hide.
    const auto f = fused.Closest(sights[i].origin, d, 0, 1 + s.tolerance);
    if (f && f->t <= h->t) return;
    const Eigen::Vector3d& end = f && f->t < 1 - s.tolerance ? f->point : sights[i].point;
    const Eigen::Vector3d n = h->normal.dot(d) < 0 ? h->normal : Eigen::Vector3d(-h->normal);
    out[i].at = frame.Across(h->point);
    out[i].height = frame.Height(h->point);
    out[i].behind = std::clamp((h->point - end).dot(n), 0.0, s.back);
    out[i].covered = f.has_value();
  });
  return out;
}

}  // namespace

std::vector<double> SeenWallDistances(const Mesh& proxy, const Eigen::Vector3d& up,
                                      const std::vector<Sight>& sights, const Mesh& dense,
                                      const SeenWallSearch& search) {
  const SeenWallSearch& s = search;
  if (!(up.norm() > 0) || !(s.reach > 0) || !(s.rise > 0) || !(s.back > 0) ||
      !std::isfinite(s.back) || !(s.quantile >= 0) || !(s.quantile <= 1) ||
      !(s.covered_quantile >= 0) || !(s.covered_quantile <= 1) || !(s.tolerance >= 0) ||
      !(s.tolerance < 1))
    throw Error(
        "merge: the seen-wall search needs up, reach, rise and a finite back > 0, quantiles in "
        "[0, 1], tolerance in [0, 1)");
  const Eigen::Vector3d u = up.normalized();
  const std::vector<uint8_t> kind = ProxyFaceKinds(proxy, u);
  const UpFrame frame = ProxyFrame(proxy, u, s.reach);
  const std::vector<WallSample> samples = SampleWalls(proxy, kind, frame, sights, dense, s);
  std::unordered_map<uint64_t, std::vector<const WallSample*>> grid;
  for (const WallSample& w : samples)
    if (std::isfinite(w.behind)) grid[frame.Cell(w.at)].push_back(&w);
  const std::vector<int64_t> wall = WallComponents(proxy, kind);
  std::vector<double> out(proxy.vertices.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<double> hole, covered;
  const size_t enough = std::max<size_t>(s.min_samples, 1);
  for (size_t v = 0; v < proxy.vertices.size(); ++v) {
    if (wall[v] < 0) continue;
    const Eigen::Vector2d at = frame.Across(proxy.vertices[v]);
    const double height = frame.Height(proxy.vertices[v]);
    hole.clear();
    covered.clear();
    for (uint64_t key : frame.CellsAround(at)) {
      auto it = grid.find(key);
      if (it == grid.end()) continue;
      for (const WallSample* w : it->second)
        if ((w->at - at).norm() <= s.reach && std::abs(w->height - height) <= s.rise)
          (w->covered ? covered : hole).push_back(w->behind);
    }
    if (hole.size() >= enough) out[v] = Percentile(hole, s.quantile);
    if (covered.size() >= enough) {
      const double c = Percentile(covered, s.covered_quantile);
      out[v] = std::isfinite(out[v]) ? std::max(out[v], c) : c;
    }
  }
  FillUnseenWalls(proxy, frame, wall, s.reach / 2, out);
  return out;
}

}  // namespace mvtm
