// drive on the mkroad fixture, against what the fixture knows without drive: its CPU ray tracer
// (the camera's height above the true ground), its road layout (lane keeping on the curve, the
// lane change's lateral offset from the recorded path) and its UTM-shifted copy.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "base/text.h"
#include "drive.h"
#include "drive/lane_change.h"
#include "io/trajectory.h"
#include "mkroad/mkroad.h"
#include "mkroad/road_scene.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;

const Eigen::Vector3d kUtm(451000, 5410000, 120);

fs::path Root() {
  static fs::path r = fs::temp_directory_path() / ("mvtm-drive-" + std::to_string(getpid()));
  return r;
}

// The fixture (12 frames a pass, no vehicles, small images), made once per origin.
fs::path Fixture(bool utm) {
  const fs::path dir = Root() / (utm ? "ws-utm" : "ws");
  if (!fs::exists(dir / "sparse")) {
    fixture::MkroadOptions m;
    m.frames = 12;
    m.width = 96;
    m.height = 32;
    m.vehicles = 0;
    m.supersample = 1;
    m.points = 300;
    m.out_dir = dir.string();
    m.fullsize_frames = 0;
    m.offpath_every = 0;
    m.quiet = true;
    if (utm) m.origin = kUtm;
    fixture::RunMkroad(m);
  }
  return dir;
}

// Straight 40 m, the 1 rad arc of the centreline in lane A (radius 60 + 1.75 m: a steering-wheel
// angle of 15·atan(2.7/61.75)), straight again, at 10 m/s.
fs::path CurveControls() {
  const fs::path p = Root() / "curve.tsv";
  const double steer = 15 * std::atan(2.7 / 61.75) * 180 / M_PI;
  const double arc_end = 4 + 61.75 / 10;
  std::ofstream f(p);
  f << "time\tsteer\tspeed\tthrottle\n0\t0\t10\t0\n4\t" << FormatDouble(steer) << "\t10\t0\n"
    << FormatDouble(arc_end) << "\t0\t10\t0\n12\t0\t10\t0\n";
  return p;
}

DriveOptions Options(bool utm, const std::string& out) {
  DriveOptions o;
  o.workspace = Fixture(utm).string();
  o.controls = CurveControls().string();
  o.out = (Root() / out).string();
  o.metric = true;
  o.start = "A_0000.png";
  o.camera_offset = "0,0,1.65";
  o.force = true;
  return o;
}

std::vector<StampedPose> Drive(const DriveOptions& o) {
  RunDrive(o);
  return ReadTum(o.out).poses;
}

TEST(DriveTool, CameraStaysAtItsHeightAboveTheTrueGroundAndInLane) {
  const auto poses = Drive(Options(false, "curve.txt"));
  ASSERT_EQ(poses.size(), 121u);
  const fixture::RoadScene scene = fixture::BuildRoadScene(1, 0.75);
  double worst_h = 0, worst_d = 0;
  for (const StampedPose& p : poses) {
    fixture::Hit hit;
    ASSERT_TRUE(scene.bvh.Intersect({p.pose.t, Eigen::Vector3d(0, 0, -1)}, hit)) << p.time;
    worst_h = std::max(worst_h, std::abs(hit.t - 1.65));
    const Eigen::Vector2d sd = fixture::RoadCoordinates(p.pose.t.head<2>());
    worst_d = std::max(worst_d, std::abs(sd.y() - fixture::kLaneA));
  }
  std::printf(
      "mkroad curve, 121 poses: max |camera height - 1.65| = %.3g m (ray-traced truth); "
      "max distance from lane A's centre %.3f m\n",
      worst_h, worst_d);
  EXPECT_LE(worst_h, 0.01);
  // The start pose's wobble (±8 cm, ±0.5°) alone drifts ~0.4 m over 40 m; off the curve's
  // steering the car would be metres out.
  EXPECT_LE(worst_d, 0.6);
  // The end of the log, 18.25 m past the arc, heads along the road (1 rad) to the wobble's 0.5°.
  const Eigen::Vector3d fwd = poses.back().pose.R().col(2);
  EXPECT_NEAR(std::atan2(fwd.y(), fwd.x()), 1.0, 0.01);
}

TEST(DriveTool, DefaultHeightIsTheRecordedOne) {
  DriveOptions o = Options(false, "default.txt");
  o.camera_offset.clear();
  const DriveReport r = RunDrive(o);
  EXPECT_TRUE(r.height_from_workspace);
  EXPECT_EQ(r.height_cameras, 24u);
  EXPECT_NEAR(r.camera_height, fixture::kCameraHeight, 0.015);  // the ±1.5 cm wobble
}

TEST(DriveTool, EndPoseDoesNotDependOnTheRate) {
  std::vector<StampedPose> ends;
  for (double rate : {7.0, 10.0, 30.0}) {
    DriveOptions o = Options(false, "rate.txt");
    o.rate = rate;
    ends.push_back(Drive(o).back());
  }
  // The planar state at the end is the same bits at every rate (drive_test); the placement on
  // the mesh starts each ray from the previous ground height, so it agrees to rounding.
  double worst_t = 0, worst_q = 0;
  for (const auto& e : ends) {
    EXPECT_EQ(e.time, 12);
    worst_t = std::max(worst_t, (e.pose.t - ends[0].pose.t).norm());
    worst_q = std::max(worst_q, (e.pose.q.coeffs() - ends[0].pose.q.coeffs()).norm());
  }
  std::printf("end pose at 7, 10, 30 Hz: position within %.3g m, quaternion within %.3g\n", worst_t,
              worst_q);
  EXPECT_LE(worst_t, 1e-12);
  EXPECT_LE(worst_q, 1e-14);
}

TEST(DriveTool, UtmCopyDrivesTheSamePath) {
  const auto a = Drive(Options(false, "a.txt"));
  const auto b = Drive(Options(true, "b.txt"));
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i)
    worst = std::max(worst, (b[i].pose.t - kUtm - a[i].pose.t).norm());
  std::printf("UTM copy: max position difference %.3g m\n", worst);
  EXPECT_LE(worst, 1e-6);
}

TEST(DriveTool, LaneChangeMovesSidewaysFromTheRecordedPath) {
  DriveOptions o = Options(false, "lane.txt");
  o.controls.clear();
  o.lane_change = "2:4:3.5";
  o.pass = "A_";
  o.frame_rate = 1;  // 7.3 m between the 12 frames: 7.3 m/s
  o.rate = 20;
  const auto poses = Drive(o);
  // The recorded camera path of pass A (truth), linear between frames at 1 s.
  const auto rec = ReadTum((Fixture(false) / "truth" / "trajectory_A.txt").string()).poses;
  ASSERT_EQ(rec.size(), 12u);
  const LaneChange lc{2, 4, 3.5};
  double worst = 0;
  for (const StampedPose& p : poses) {
    const size_t i = std::min<size_t>(static_cast<size_t>(p.time), 10);
    const double w = p.time - i;
    const Eigen::Vector3d c = (1 - w) * rec[i].pose.t + w * rec[i + 1].pose.t;
    const double d_rec = fixture::RoadCoordinates(c.head<2>()).y();
    const double d_out = fixture::RoadCoordinates(p.pose.t.head<2>()).y();
    worst = std::max(worst, std::abs(d_out - d_rec - lc.At(p.time).d));
  }
  std::printf("lane change on mkroad: |lateral offset - profile| <= %.3g m over %zu poses\n", worst,
              poses.size());
  // The offset is taken across the recorded camera's heading (±0.5° wobble): 3.5·tan 0.5° = 3 cm.
  EXPECT_LE(worst, 0.04);
}

TEST(DriveTool, ErrorsSayWhatIsWrong) {
  DriveOptions o = Options(false, "err.txt");
  o.metric = false;
  try {
    RunDrive(o);
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("is not known to be metric: give --scale"),
              std::string::npos);
  }
  o = Options(false, "err.txt");
  o.start = "B_0011.png";  // the car drives off the end of the road
  try {
    RunDrive(o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("leaves the mesh at t = "), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mvtm
