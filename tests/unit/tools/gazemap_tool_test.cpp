// gazemap on the mkroad fixture, against what the fixture knows without gazemap: its road layout
// (known 3-D points on the road surface, z = 0), its exact poses, and its CPU ray tracer (which
// photo sees which point, and what hides it). Synthetic gaze is aimed at the known points through
// the known render poses; the mapping must give them back, and attribute each point to exactly
// the photos the tracer says see it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "base/text.h"
#include "gazemap.h"
#include "io/colmap_model.h"
#include "io/trajectory.h"
#include "mkroad/mkroad.h"
#include "mkroad/road_scene.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

constexpr double kScreenW = 1920, kScreenH = 1080;  // the 160×48 render stretched full screen

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-gazemap-" + std::to_string(getpid()));
  return r;
}

fs::path Fixture() {
  const fs::path dir = Root() / "ws";
  if (!fs::exists(dir / "sparse")) {
    fixture::MkroadOptions m;
    m.frames = 12;
    m.width = 160;
    m.height = 48;
    m.vehicles = 0;
    m.supersample = 1;
    m.points = 300;
    m.out_dir = dir.string();
    m.fullsize_frames = 0;
    m.offpath_every = 0;
    m.quiet = true;
    fixture::RunMkroad(m);
  }
  return dir;
}

struct Target {
  size_t frame;
  Eigen::Vector3d P;  // on the road surface, seen from the frame's pose (tracer-checked)
  double x, y;        // screen pixel
  double distance;    // from the render camera
};

struct GazeSetup {
  std::vector<Target> targets;
  std::string frames, gaze;
};

// Frames: pass A's exact poses shown one second each. Targets: road points 8 m ahead (5 m right,
// 2 m left of the centreline) and 20 m ahead on it, projected through the pose; the gaze holds
// each for 0.4 s at 250 Hz and jumps to the next.
GazeSetup MakeSetup(const fixture::RoadScene& scene, const Camera& cam) {
  GazeSetup s;
  const auto rec = ReadTum((Fixture() / "truth" / "trajectory_A.txt").string()).poses;
  std::vector<StampedPose> shown = rec;
  for (size_t i = 0; i < shown.size(); ++i) shown[i].time = static_cast<double>(i);
  s.frames = (Root() / "frames.txt").string();
  WriteTum(s.frames, shown);
  const Camera screen = cam.Scaled(kScreenW, kScreenH);
  for (size_t k = 0; k < shown.size(); ++k) {
    const Rigid3d w2c = shown[k].pose.Inverse();
    const Eigen::Vector3d C = shown[k].pose.t;
    const double sc = fixture::RoadCoordinates(C.head<2>()).x();
    for (const Eigen::Vector2d& sd :
         {Eigen::Vector2d(8, -5), Eigen::Vector2d(8, 2), Eigen::Vector2d(20, 0)}) {
      const Eigen::Vector3d P = fixture::RoadPoint(sc + sd.x(), sd.y(), 0);
      fixture::Hit hit;
      if (!scene.bvh.Intersect({C, P - C}, hit) || std::abs(hit.t - 1) > 1e-9) continue;
      const Eigen::Vector2d px = screen.Project(w2c * P);
      s.targets.push_back({k, P, px.x(), px.y(), (P - C).norm()});
    }
  }
  s.gaze = (Root() / "gaze.tsv").string();
  std::ofstream g(s.gaze);
  g << "time\tx\ty\tvalid\n";
  for (int i = 0; i < 250 * static_cast<int>(shown.size()); ++i) {
    const double t = i / 250.0;
    const size_t k = static_cast<size_t>(t);
    const double in = t - static_cast<double>(k);
    // Up to three targets per frame, each held for a third of the second.
    std::vector<const Target*> mine;
    for (const Target& tg : s.targets)
      if (tg.frame == k) mine.push_back(&tg);
    const size_t slot = std::min<size_t>(static_cast<size_t>(in * 3), mine.size());
    if (slot == mine.size()) {
      g << FormatDouble(t) << "\tnan\tnan\t0\n";
      continue;
    }
    g << FormatDouble(t) << '\t' << FormatDouble(mine[slot]->x) << '\t'
      << FormatDouble(mine[slot]->y) << "\t1\n";
  }
  return s;
}

GazemapOptions Options(const GazeSetup& s, const std::string& out) {
  GazemapOptions o;
  o.workspace = Fixture().string();
  o.frames = s.frames;
  o.gaze = s.gaze;
  o.out = (Root() / out).string();
  o.screen = "1920x1080";
  o.screen_mm = "531x299";
  o.distance = 650;
  o.force = true;
  o.no_pictures = true;
  o.quiet = true;
  return o;
}

struct Row {
  size_t frame;
  Eigen::Vector3d X;
  double distance;
};

std::vector<Row> ReadFixations(const fs::path& out) {
  std::ifstream f(out / "fixations.tsv");
  std::string line;
  std::getline(f, line);
  std::vector<Row> rows;
  while (std::getline(f, line)) {
    const auto c = SplitChar(line, '\t');
    rows.push_back(
        {std::stoul(std::string(c[6])),
         {std::stod(std::string(c[7])), std::stod(std::string(c[8])), std::stod(std::string(c[9]))},
         std::stod(std::string(c[10]))});
  }
  return rows;
}

std::set<std::pair<size_t, std::string>> ReadSources(const fs::path& out) {
  std::ifstream f(out / "sources.tsv");
  std::string line;
  std::getline(f, line);
  std::set<std::pair<size_t, std::string>> s;
  while (std::getline(f, line)) {
    const auto c = SplitChar(line, '\t');
    s.insert({std::stoul(std::string(c[0])) - 1, std::string(c[1])});
  }
  return s;
}

class GazemapTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new fixture::RoadScene(fixture::BuildRoadScene(1, 0.75));
    model_ = new Reconstruction(ReadColmapModel((Fixture() / "sparse").string()));
    setup_ = new GazeSetup(MakeSetup(*scene_, model_->cameras.begin()->second));
  }
  static fixture::RoadScene* scene_;
  static Reconstruction* model_;
  static GazeSetup* setup_;
};
fixture::RoadScene* GazemapTool::scene_ = nullptr;
Reconstruction* GazemapTool::model_ = nullptr;
GazeSetup* GazemapTool::setup_ = nullptr;

TEST_F(GazemapTool, GazeAtKnownRoadPointsComesBackOnThem) {
  const GazeSetup& s = *setup_;
  ASSERT_GE(s.targets.size(), 30u);
  const GazemapReport r = RunGazemap(Options(s, "out-ray"));
  ASSERT_EQ(r.fixations, s.targets.size());
  const auto rows = ReadFixations(Root() / "out-ray");
  double worst = 0, worst_d = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].frame, s.targets[i].frame);
    worst = std::max(worst, (rows[i].X - s.targets[i].P).norm() / s.targets[i].distance);
    worst_d = std::max(worst_d,
                       std::abs(rows[i].distance - s.targets[i].distance) / s.targets[i].distance);
  }
  std::printf(
      "mkroad: %zu fixations at known road points through known poses: max |X - P| / distance "
      "= %.3g, max distance error %.3g (relative)\n",
      rows.size(), worst, worst_d);
  EXPECT_LE(worst, 1e-3);
  EXPECT_LE(worst_d, 1e-3);
}

// For every fixation and every photo, the tracer's verdict: does the photo see the point (in its
// image, nothing in between), and if not, is a building in the way?
struct Verdicts {
  std::set<std::pair<size_t, std::string>> sees;
  std::set<std::pair<size_t, std::string>> hidden_by_building;
  size_t hidden = 0;
};

Verdicts Truth(const GazeSetup& s, const Reconstruction& model, const fixture::RoadScene& scene) {
  Verdicts v;
  for (size_t i = 0; i < s.targets.size(); ++i)
    for (const ImageRecord* im : model.ImagesByName()) {
      const Camera& cam = model.cameras.at(im->camera_id);
      const Eigen::Vector3d xc = im->world_to_camera * s.targets[i].P;
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d px = cam.Project(xc);
      if (px.x() < 0 || px.y() < 0 || px.x() >= cam.width || px.y() >= cam.height) continue;
      const Eigen::Vector3d C = im->world_to_camera.Centre();
      fixture::Hit hit;
      scene.bvh.Intersect({C, s.targets[i].P - C}, hit);
      if (hit.valid() && hit.t < 1 - 1e-6) {
        ++v.hidden;
        const int m = scene.bvh.triangles()[hit.tri].material;
        if (scene.appearance.materials[m].label == fixture::kLabelBuilding)
          v.hidden_by_building.insert({i, im->name});
      } else {
        v.sees.insert({i, im->name});
      }
    }
  return v;
}

TEST_F(GazemapTool, SourcesAreThePhotosThatSeeThePoint) {
  const GazeSetup& s = *setup_;
  const Verdicts truth = Truth(s, *model_, *scene_);
  GazemapOptions o = Options(s, "out-ray");
  o.visibility = GazeVisibility::kRay;
  RunGazemap(o);
  const auto got = ReadSources(Root() / "out-ray");
  size_t wrongly_hidden = 0, wrongly_seen = 0, building_attributed = 0;
  for (const auto& p : truth.sees) wrongly_hidden += !got.count(p);
  for (const auto& p : got) wrongly_seen += !truth.sees.count(p);
  for (const auto& p : truth.hidden_by_building) building_attributed += got.count(p);
  std::printf(
      "sources by ray: %zu (fixation, photo) pairs seen by the tracer, %zu hidden (%zu by a "
      "building); gazemap misses %zu, adds %zu, attributes %zu hidden by a building\n",
      truth.sees.size(), truth.hidden, truth.hidden_by_building.size(), wrongly_hidden,
      wrongly_seen, building_attributed);
  ASSERT_GE(truth.hidden_by_building.size(), 1u);  // the case exists in this fixture
  EXPECT_EQ(building_attributed, 0u);
  EXPECT_EQ(wrongly_seen, 0u);
  EXPECT_EQ(wrongly_hidden, 0u);
}

TEST_F(GazemapTool, BakedDepthNeverAttributesAHiddenPoint) {
  const GazeSetup& s = *setup_;
  // The truth depth maps stand in for bakedepth's (the same static mesh, ray-traced).
  const fs::path ws = Fixture();
  fs::create_directories(ws / "depth");
  for (const auto& e : fs::directory_iterator(ws / "truth" / "depth"))
    fs::copy_file(e.path(), ws / "depth" / e.path().filename(),
                  fs::copy_options::overwrite_existing);
  const Verdicts truth = Truth(s, *model_, *scene_);
  RunGazemap(Options(s, "out-depth"));
  fs::remove_all(ws / "depth");
  const auto got = ReadSources(Root() / "out-depth");
  size_t found = 0, wrongly_seen = 0, building_attributed = 0;
  for (const auto& p : truth.sees) found += got.count(p);
  for (const auto& p : got) wrongly_seen += !truth.sees.count(p);
  for (const auto& p : truth.hidden_by_building) building_attributed += got.count(p);
  std::printf(
      "sources by baked depth (1%% tolerance): finds %zu of %zu seen pairs, adds %zu, attributes "
      "%zu of %zu hidden by a building\n",
      found, truth.sees.size(), wrongly_seen, building_attributed, truth.hidden_by_building.size());
  EXPECT_EQ(building_attributed, 0u);
  EXPECT_EQ(wrongly_seen, 0u);
  EXPECT_GE(found, truth.sees.size() * 9 / 10);
}

TEST_F(GazemapTool, LabelsGiveTheRoadItsDwellTime) {
  const GazeSetup& s = *setup_;
  const GazemapReport r = RunGazemap(Options(s, "out-ray"));
  EXPECT_EQ(r.aoi_from, "labels");
  // Every target is on the carriageway; the label at its pixel in the nearest photo is road
  // (lane markings included), except near a label edge at this resolution.
  double road = 0;
  for (const DwellRow& d : r.aoi)
    if (d.aoi == "road") road = d.share;
  std::printf("AOI road: %.3f of the dwell time\n", road);
  EXPECT_GE(road, 0.9);
}

}  // namespace
}  // namespace mvtm
