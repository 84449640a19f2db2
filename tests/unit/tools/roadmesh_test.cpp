// roadmesh against truth that did not come from roadmesh: the mkroad fixture's ray-traced depth
// (road and facade pixels), and on real KITTI odometry 06 the KITTI camera height (1.65 m) and
// the real held-out photographs (SSIM of vertex colours vs PTM through ptmrender). Scale: the
// unit estimated from the scene against the fixture's camera height and KITTI's recorded Sim(3),
// and renders of a workspace and of its similarity-transformed copy, each meshed by roadmesh.
#include "roadmesh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "image/image.h"
#include "image/ssim.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "mkroad/mkroad.h"
#include "mkroad/road_scene.h"
#include "ptmrender.h"
#include "render/context.h"
#include "render/renderer.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-roadmesh-" + std::to_string(getpid()));
  return r;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  auto it = v.begin() + static_cast<long>(q * double(v.size() - 1));
  std::nth_element(v.begin(), it, v.end());
  return *it;
}

std::string DataDir() {
  const char* e = std::getenv("MVTM_DATA");
  std::string d = e ? e : MVTM_DATA_DIR;
  return fs::is_directory(d) ? d : "";
}

// A Sim(3) x → s·R·x + t of the world.
struct Similarity3 {
  double s = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

// The model under `sim`: points moved, poses re-expressed (w2c' = w2c ∘ sim⁻¹; the centre moves).
Reconstruction Transformed(Reconstruction rec, const Similarity3& sim) {
  const Eigen::Quaterniond qr(sim.R);
  for (auto& [id, im] : rec.images) {
    const Eigen::Vector3d c = sim.s * (sim.R * im.world_to_camera.Centre()) + sim.t;
    const Eigen::Quaterniond q =
        (NormalizedQuaternion(im.world_to_camera.q) * qr.conjugate()).normalized();
    im.world_to_camera = Rigid3d(q, -(q * c));
  }
  for (auto& [id, p] : rec.points3D) p.xyz = sim.s * (sim.R * p.xyz) + sim.t;
  return rec;
}

// The test similarity: scale 0.2, a rotation that tilts "up" away from any axis, UTM offset.
Similarity3 UtmSimilarity() {
  Similarity3 sim;
  sim.s = 0.2;
  sim.R = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, -2, 5).normalized()).toRotationMatrix();
  sim.t = Eigen::Vector3d(451000, 5410000, 120);
  return sim;
}

// The mkroad fixture of the scale tests (12 frames a pass), made once.
fs::path ScaleFixture() {
  const fs::path dir = Root() / "mkroad-scale";
  if (!fs::exists(dir / "sparse")) {
    fixture::MkroadOptions m;
    m.frames = 12;
    m.out_dir = dir.string();
    m.fullsize_frames = 0;
    m.offpath_every = 0;
    m.quiet = true;
    fixture::RunMkroad(m);
  }
  return dir;
}

// A workspace of `rec` (text model) with the fixture's images, and no mesh.
fs::path MakeWorkspace(const fs::path& dir, const Reconstruction& rec, const fs::path& images) {
  fs::remove_all(dir);
  fs::create_directories(dir / "sparse");
  WriteColmapText(rec, (dir / "sparse").string());
  fs::create_directory_symlink(fs::absolute(images), dir / "images");
  return dir;
}

class RoadMesh : public ::testing::Test {
 protected:
  static void TearDownTestSuite() {
    if (!std::getenv("MVTM_KEEP")) fs::remove_all(Root());
  }
};

TEST_F(RoadMesh, OptionsAreChecked) {
  RoadMeshOptions ok;
  ok.workspace = "ws";  // WS is required
  EXPECT_NO_THROW(ok.Check());
  RoadMeshOptions o = ok;
  o.width = 0;
  EXPECT_THROW(o.Check(), UsageError);
  o = ok;
  o.resolution = 10;
  EXPECT_THROW(o.Check(), UsageError);
  o = ok;
  o.wall_height = -1;
  EXPECT_THROW(o.Check(), UsageError);
  EXPECT_THROW(RoadMeshOptions().Check(), UsageError);
}

// The fixture: cameras 1.65 m above a flat road (pavements 0.15 m higher), facades at 10 m from
// the centreline, i.e. 11.75–12.75 m left and 7.25–8.25 m right of the two passes.
TEST_F(RoadMesh, MkroadDepthAgainstRayTracedTruth) {
  fixture::MkroadOptions m;
  m.frames = 12;
  m.out_dir = (Root() / "mkroad").string();
  m.fullsize_frames = 0;
  m.offpath_every = 0;
  m.quiet = true;
  fixture::RunMkroad(m);
  const fs::path ws = m.out_dir;
  fs::remove(ws / "mesh.ply");

  RoadMeshOptions o;
  o.workspace = ws.string();
  o.quiet = true;
  RoadMeshReport r = RunRoadMesh(o);
  std::printf(
      "[roadmesh mkroad] %zu vertices, %zu triangles, path %.1f m, camera height %.3f m from %zu "
      "points, "
      "walls %.2f m left / %.2f m right, %zu ground vertices refined, %zu coloured\n",
      r.vertices, r.faces, r.path_length, r.camera_height, r.ground_points, r.left_wall,
      r.right_wall, r.refined_vertices, r.coloured);
  EXPECT_NEAR(r.camera_height, 1.65, 0.05);  // the fixture's camera height; wobble ±1.5 cm
  // Facades at |d| = 10 m seen from passes at d = −1.75 and −2.75 m: 12.25 m left, 7.75 m right
  // of the merged path (±0.5 m: the passes' spread, poles and trees in front of the facades).
  EXPECT_NEAR(r.left_wall, 12.25, 0.75);
  EXPECT_NEAR(r.right_wall, 7.75, 0.75);
  // A second run finds the mesh up to date and leaves it alone.
  const auto stamp = fs::last_write_time(ws / "mesh.ply");
  EXPECT_TRUE(RunRoadMesh(o).up_to_date);
  EXPECT_EQ(fs::last_write_time(ws / "mesh.ply"), stamp);

  Mesh mesh = ReadMesh((ws / "mesh.ply").string());
  ASSERT_TRUE(mesh.has_normals());
  ASSERT_TRUE(mesh.has_colors());
  Reconstruction rec = ReadColmapModel((ws / "sparse").string());
  auto ctx = GlContext::Create();
  Renderer renderer(mesh);
  std::vector<double> road, facade;
  size_t road_px = 0, road_missing = 0;
  for (const ImageRecord* im : rec.ImagesByName()) {
    const Camera& cam = rec.cameras.at(im->camera_id);
    Image d = renderer.RenderDepth(View{cam, im->world_to_camera});
    const std::string stem = fs::path(im->name).stem().string();
    Image truth = ReadImage((ws / "truth/depth" / (stem + ".exr")).string());
    Image labels = ReadImage((ws / "labels" / (stem + ".png")).string());
    ASSERT_EQ(d.width, truth.width);
    for (int y = 0; y < d.height; ++y)
      for (int x = 0; x < d.width; ++x) {
        const int label = static_cast<int>(labels.at(x, y));
        const float t = truth.at(x, y), z = d.at(x, y);
        if (!std::isfinite(t) || (label != 3 && label != 1)) continue;
        if (label == 3) ++road_px;
        if (!std::isfinite(z)) {
          road_missing += label == 3;
          continue;
        }
        (label == 3 ? road : facade).push_back(std::abs(double(z) - t) / t);
      }
  }
  const double road_med = Quantile(road, 0.5), road_p90 = Quantile(road, 0.9);
  const double fac_med = Quantile(facade, 0.5), fac_p90 = Quantile(facade, 0.9);
  std::printf(
      "[roadmesh mkroad] road (label 3): %zu px, median |d - truth|/truth %.4f, p90 %.4f, %zu px "
      "without surface\n",
      road_px, road_med, road_p90, road_missing);
  std::printf("[roadmesh mkroad] facades (label 1): %zu px, median rel. error %.4f, p90 %.4f\n",
              facade.size(), fac_med, fac_p90);
  // The road is flat and the camera height is fitted to within a few cm: a height error δ gives
  // a relative depth error of about δ / 1.65 m on the road, so 1 % allows δ ≈ 1.6 cm, the
  // fixture's pose wobble in height.
  EXPECT_LT(road_med, 0.01);
  // Every road pixel lies inside the corridor (which runs 30 m past the last camera).
  EXPECT_LT(double(road_missing) / double(road_px), 0.05);
  // Facades: one plane per side at the median point distance, while the two passes sit 1 m apart
  // and alleys and shop fronts break the facade line: 5 % (0.4–0.6 m at 8–12 m) bounds the median.
  EXPECT_LT(fac_med, 0.05);
}

// KITTI odometry 06 frames 0–50 (MVTM_DATA), "" when absent.
fs::path KittiDir() {
  const std::string data = DataDir();
  if (data.empty()) return "";
  const fs::path src = fs::path(data) / "kitti_odom06_f000-050";
  if (!fs::exists(src / "colmap/sparse/0/images.txt") ||
      !fs::exists(src / "colmap/colmap_to_kitti_sim3.txt"))
    return "";
  return src;
}

// colmap_to_kitti_sim3.txt: X_kitti = s·R·X_colmap + t.
Similarity3 ReadKittiSim3(const fs::path& src) {
  Similarity3 sim;
  sim.s = 0;
  std::ifstream f(src / "colmap/colmap_to_kitti_sim3.txt");
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream in(line);
    std::string key;
    in >> key;
    if (key == "s")
      in >> sim.s;
    else if (key == "t")
      in >> sim.t[0] >> sim.t[1] >> sim.t[2];
    else if (key.size() == 2 && key[0] == 'R') {
      const int row = key[1] - '0';
      in >> sim.R(row, 0) >> sim.R(row, 1) >> sim.R(row, 2);
    }
  }
  return sim;
}

// KITTI odometry 06, frames 0–50, with its COLMAP model brought to KITTI metres by the recorded
// Sim(3) (the model itself has arbitrary scale, SOURCE.md).
TEST_F(RoadMesh, KittiGroundAndVertexColoursVersusPtm) {
  const fs::path src = KittiDir();
  if (src.empty()) GTEST_SKIP() << "MVTM_DATA or kitti_odom06_f000-050 not present";
  const Similarity3 sim = ReadKittiSim3(src);
  ASSERT_GT(sim.s, 0);
  Reconstruction rec = Transformed(ReadColmapModel((src / "colmap/sparse/0").string()), sim);
  const fs::path ws = Root() / "kitti";
  fs::create_directories(ws / "sparse");
  WriteColmapText(rec, (ws / "sparse").string());
  fs::create_directory_symlink(src / "image_0", ws / "images");

  RoadMeshOptions o;
  o.workspace = ws.string();
  o.quiet = true;
  RoadMeshReport r = RunRoadMesh(o);
  std::printf(
      "[roadmesh kitti] %zu vertices, %zu triangles, path %.1f m, camera height %.3f m from %zu "
      "points, "
      "walls %.2f m left / %.2f m right, %zu ground vertices refined, %zu of %zu coloured\n",
      r.vertices, r.faces, r.path_length, r.camera_height, r.ground_points, r.left_wall,
      r.right_wall, r.refined_vertices, r.coloured, r.vertices);
  Mesh mesh = ReadMesh((ws / "mesh.ply").string());
  ASSERT_GT(mesh.faces.size(), 0u);
  EXPECT_GT(r.coloured, r.vertices / 4);

  // The ground below each camera, from the mesh: the depth at the principal point of a virtual
  // camera at the same centre looking straight down its −up axis (camera axes x' = −x, y' = z,
  // z' = y, right-handed).
  std::vector<double> heights;
  {
    auto ctx = GlContext::Create();
    Renderer renderer(mesh);
    for (const ImageRecord* im : rec.ImagesByName()) {
      const Camera& cam = rec.cameras.at(im->camera_id);
      const Eigen::Matrix3d c2w = im->world_to_camera.R().transpose();
      Eigen::Matrix3d down;
      down << -c2w.col(0), c2w.col(2), c2w.col(1);
      const Eigen::Quaterniond q(Eigen::Matrix3d(down.transpose()));
      const Rigid3d pose(q, -(q * im->world_to_camera.Centre()));
      Image d = renderer.RenderDepth(View{cam, pose});
      const float z = d.at(static_cast<int>(cam.cx()), static_cast<int>(cam.cy()));
      if (std::isfinite(z)) heights.push_back(z);
    }
  }
  const double h_med = Quantile(heights, 0.5);
  std::printf(
      "[roadmesh kitti] ground below the cameras (mesh, looking straight down): median %.3f m over "
      "%zu frames "
      "(KITTI: 1.65 m)\n",
      h_med, heights.size());
  ASSERT_FALSE(heights.empty());
  EXPECT_NEAR(h_med, 1.65, 0.1);  // KITTI's camera height; the road's camber and slope vary it

  // Held-out frames (every 5th, never projected onto themselves): vertex colours vs PTM.
  std::map<std::string, std::map<std::string, double>> ssim;
  for (const char* mode : {"vertex", "ptm"}) {
    PtmRenderOptions p;
    p.workspace = ws.string();
    p.outdir = (Root() / "kitti-renders" / mode).string();
    p.at_images = true;
    p.exclude_self = true;
    p.shard = "0/5";
    p.mode = std::string(mode) == "ptm" ? PtmMode::kPtm : PtmMode::kVertex;
    p.quiet = true;
    p.force = true;
    if (std::string(mode) == "ptm") p.projectors = 2;
    std::ostringstream sink;
    RunPtmRender(p, sink);
    for (const auto& e : fs::directory_iterator(p.outdir)) {
      if (!e.is_regular_file()) continue;
      const std::string name = e.path().filename().string();
      Image a = ToGrey(ReadImage(e.path().string()));
      Image b = ToGrey(ReadImage((src / "image_0" / name).string()));
      ssim[name][mode] = Ssim(a, b, SsimOptions());
    }
  }
  double sv = 0, sp = 0;
  for (const auto& [name, m] : ssim) {
    std::printf("[roadmesh kitti] %s  SSIM vertex %.4f  ptm %.4f  (%+.4f)\n", name.c_str(),
                m.at("vertex"), m.at("ptm"), m.at("ptm") - m.at("vertex"));
    sv += m.at("vertex"), sp += m.at("ptm");
  }
  ASSERT_EQ(ssim.size(), 11u);  // frames 0, 5, …, 50
  sv /= double(ssim.size()), sp /= double(ssim.size());
  std::printf("[roadmesh kitti] mean SSIM vertex %.4f, ptm %.4f (%+.4f)\n", sv, sp, sp - sv);
  EXPECT_GT(sp, sv);
}

// The unit from the scene: on the metric fixture, its camera height over 1.65 m (= 1); on the
// fixture under a similarity, s times that — the estimate uses ratios only, so it scales exactly.
TEST_F(RoadMesh, UnitFromTheCameraHeightOfTheScene) {
  const Reconstruction rec = ReadColmapModel((ScaleFixture() / "sparse").string());
  const SceneUnit a = EstimateSceneUnit(rec);
  const double want = fixture::kCameraHeight / 1.65;  // the fixture's cameras are level
  std::printf("[roadmesh unit] mkroad: %.5f (%s; want %.5f)\n", a.unit,
              DescribeSceneUnit(a).c_str(), want);
  EXPECT_STREQ(a.source, "camera height");
  EXPECT_GT(a.images, rec.images.size() / 2);
  EXPECT_NEAR(a.unit, want, 0.03 * want);  // ±1.5 cm pose wobble, kerbs, vehicles: within 3 %

  const Similarity3 sim = UtmSimilarity();
  const SceneUnit b = EstimateSceneUnit(Transformed(rec, sim));
  std::printf("[roadmesh unit] mkroad x %.1f: %.5f (%s)\n", sim.s, b.unit,
              DescribeSceneUnit(b).c_str());
  EXPECT_NEAR(b.unit, sim.s * want, 0.03 * sim.s * want);
  EXPECT_NEAR(b.unit / a.unit, sim.s, 1e-9);  // the same points, the same medians
  EXPECT_EQ(a.points, b.points);

  // Without points: the camera spacing over a typical 1 m. The fixture's frames are 80 m / 11
  // apart along the road (chords of its curve, ±8 cm wobble): 7.27 m.
  Reconstruction bare = rec;
  bare.points3D.clear();
  for (auto& [id, im] : bare.images) im.points2D.clear();
  const SceneUnit c = EstimateSceneUnit(bare);
  EXPECT_STREQ(c.source, "camera spacing");
  const double spacing = (fixture::kPathEnd - fixture::kPathBegin) / 11;
  EXPECT_NEAR(c.spacing, spacing, 0.2);
  EXPECT_DOUBLE_EQ(c.unit, c.spacing / 1.0);
}

// --metric keeps the metre lengths: the unit is 1 whatever the scene shows.
TEST_F(RoadMesh, MetricUsesUnitOne) {
  const fs::path src = ScaleFixture();
  const Similarity3 sim = UtmSimilarity();
  const fs::path ws =
      MakeWorkspace(Root() / "metric-scaled",
                    Transformed(ReadColmapModel((src / "sparse").string()), sim), src / "images");
  RoadMeshOptions o;
  o.workspace = ws.string();
  o.metric = o.quiet = o.no_colours = true;
  const RoadMeshReport r = RunRoadMesh(o);
  EXPECT_EQ(r.unit.unit, 1.0);
  EXPECT_STREQ(r.unit.source, "--metric");
  // Metres on a model 0.2 of metres: the camera height (0.33) is outside 0.5–4, so the default.
  EXPECT_EQ(r.ground_points, 0u);
  EXPECT_EQ(r.camera_height, 1.65);
}

// Renders are invariant under similarity transforms of the world: the fixture and its copy under
// a similarity (scale 0.2, rotation, UTM offset), each meshed by roadmesh with the unit from the
// scene, rendered by ptmrender at the recorded poses (held out) give the same frames.
TEST_F(RoadMesh, RendersAreInvariantUnderSimilarity) {
  const fs::path src = ScaleFixture();
  const Reconstruction rec = ReadColmapModel((src / "sparse").string());
  const Similarity3 sim = UtmSimilarity();
  std::map<std::string, fs::path> frames;
  std::map<std::string, RoadMeshReport> reports;
  for (const char* name : {"plain", "similar"}) {
    const bool similar = std::string(name) == "similar";
    const fs::path ws = MakeWorkspace(Root() / ("invariance-" + std::string(name)),
                                      similar ? Transformed(rec, sim) : rec, src / "images");
    RoadMeshOptions o;
    o.workspace = ws.string();
    o.quiet = true;
    reports[name] = RunRoadMesh(o);
    PtmRenderOptions p;
    p.workspace = ws.string();
    p.outdir = (ws / "frames").string();
    p.at_images = p.exclude_self = true;
    p.quiet = true;
    std::ostringstream sink;
    RunPtmRender(p, sink);
    frames[name] = p.outdir;
  }
  const RoadMeshReport &a = reports["plain"], &b = reports["similar"];
  EXPECT_NEAR(b.unit.unit / a.unit.unit, sim.s, 1e-9);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_NEAR(b.camera_height / a.camera_height, sim.s, 1e-9);
  double sum = 0, worst = 1;
  size_t n = 0;
  for (const ImageRecord* im : rec.ImagesByName()) {
    const std::string file = fs::path(im->name).stem().string() + ".png";
    ASSERT_TRUE(fs::exists(frames["plain"] / file)) << file;
    const double v = Ssim(ReadImage((frames["plain"] / file).string()),
                          ReadImage((frames["similar"] / file).string()), SsimOptions());
    sum += v, worst = std::min(worst, v), ++n;
  }
  std::printf("[roadmesh invariance] %zu frames: mean SSIM %.6f, worst %.6f\n", n, sum / n, worst);
  EXPECT_GE(sum / double(n), 0.999);
}

// The real non-metric model: the unit from its camera height against the true scale of the
// recorded Sim(3) (KITTI metres = s × model units, so 1/s model units a metre).
TEST_F(RoadMesh, KittiUnitFromTheSceneMatchesTheRecordedScale) {
  const fs::path src = KittiDir();
  if (src.empty()) GTEST_SKIP() << "MVTM_DATA or kitti_odom06_f000-050 not present";
  const Similarity3 sim = ReadKittiSim3(src);
  ASSERT_GT(sim.s, 0);
  const fs::path ws = Root() / "kitti-raw";
  fs::create_directories(ws);
  fs::create_directory_symlink(src / "colmap/sparse/0", ws / "sparse");
  RoadMeshOptions o;
  o.workspace = ws.string();
  o.quiet = o.no_colours = true;
  const RoadMeshReport r = RunRoadMesh(o);
  const double want = 1 / sim.s;
  std::printf(
      "[roadmesh kitti raw] unit %.5f (%s), true %.5f (%+.2f %%); camera height %.4f = %.3f "
      "metre-equivalents, walls %.3f / %.3f\n",
      r.unit.unit, DescribeSceneUnit(r.unit).c_str(), want, 100 * (r.unit.unit / want - 1),
      r.camera_height, r.camera_height / r.unit.unit, r.left_wall, r.right_wall);
  EXPECT_STREQ(r.unit.source, "camera height");
  EXPECT_NEAR(r.unit.unit, want, 0.03 * want);
  // The corridor then finds the ground where the metric model has it (1.64 m, see above).
  EXPECT_NEAR(r.camera_height * sim.s, 1.65, 0.1);
}

}  // namespace
}  // namespace mvtm
