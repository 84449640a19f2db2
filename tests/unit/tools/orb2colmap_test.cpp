// orb2colmap against real trajectories with ground truth (MVTM_DATA) and hand-made hard cases.
// The numbers printed here are the ones quoted in the README and the closing notes.
#include "orb2colmap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "base/error.h"
#include "base/text.h"
#include "geometry/align.h"
#include "io/colmap_model.h"
#include "test_util.h"

namespace mvtm {
namespace {

std::vector<const ImageRecord*> InOrder(const Reconstruction& r) {
  std::vector<const ImageRecord*> v;
  for (const auto& [id, im] : r.images) v.push_back(&im);
  return v;
}

// TUM fr1_xyz: 32 monocular ORB-SLAM keyframes, interpolated to every ground-truth timestamp,
// Sim(3)-aligned to the mocap ground truth.
TEST(Orb2Colmap, TumFr1XyzKeyframesInterpolatedAgainstGroundTruth) {
  std::string data = test::DataDir();
  if (data.empty()) GTEST_SKIP() << "MVTM_DATA not present";
  std::string dir = data + "/slam_trajectories/tum_fr1_xyz/";
  auto out = test::FreshDir("o2c-tum");
  Trajectory gt = ReadTum(dir + "groundtruth.txt");
  // Frame list: every ground-truth timestamp (the mocap runs at 100 Hz).
  {
    std::ofstream f(out / "frames.txt");
    f.precision(17);
    for (const auto& p : gt.poses) f << p.time << "\n";
  }
  Orb2ColmapOptions o;
  o.trajectory = dir + "KeyFrameTrajectory_ORB_mono.txt";
  o.frames = (out / "frames.txt").string();
  o.camera = "PINHOLE 640 480 517.3 516.5 318.6 255.3";
  o.outdir = (out / "model").string();
  Orb2ColmapReport rep = RunOrb2Colmap(o);
  EXPECT_EQ(rep.keyframes, 32u);
  Reconstruction r = ReadColmapText(o.outdir);
  // Frames in the keyframe span were kept, the others dropped (and counted).
  EXPECT_EQ(rep.written + rep.dropped, gt.poses.size());
  std::vector<Eigen::Vector3d> est, truth, est_kf, truth_kf;
  auto ims = InOrder(r);
  size_t k = 0;
  Trajectory kf = ReadTum(o.trajectory);
  for (const auto& p : gt.poses) {
    if (p.time < kf.poses.front().time || p.time > kf.poses.back().time) continue;
    est.push_back(ims[k++]->world_to_camera.Centre());
    truth.push_back(p.pose.t);
  }
  ASSERT_EQ(k, ims.size());
  Sim3 T = AlignUmeyama(est, truth, true);
  double ate = AteRmse(T, est, truth);
  // The floor: the keyframes themselves against ground truth interpolated at keyframe times.
  std::vector<StampedPose> gtk = gt.poses;
  SortKeyframes(gtk, "gt");
  for (const auto& p : kf.poses) {
    est_kf.push_back(p.pose.t);
    truth_kf.push_back(InterpolateCameraToWorld(gtk, p.time, Outside::kClamp)->t);
  }
  double ate_kf = AteRmse(AlignUmeyama(est_kf, truth_kf, true), est_kf, truth_kf);
  std::printf(
      "[tum_fr1_xyz] %zu frames from 32 keyframes: ATE %.4f m (keyframes alone %.4f m), scale "
      "%.4f\n",
      est.size(), ate, ate_kf, T.scale);
  // Bound. The keyframes alone are 0.010 m from the truth; the interpolated frames 0.093 m.
  // The difference is the keyframe spacing, not the code: fr1_xyz is a hand-held sweep that
  // reverses about once a second, and 32 keyframes over 30 s cut every reversal. An independent
  // implementation (scipy Slerp + numpy interp + Umeyama, tests/peer/orb2colmap_scipy.py, which
  // also checks every pose to 1e-9) gives 0.09321 m for the same frames. We bound at 0.10 m:
  // the measured value plus 7 %; a drift in interpolation or alignment shows up here.
  EXPECT_GT(ate, ate_kf);
  EXPECT_LT(ate, 0.10);
  EXPECT_LT(ate_kf, 0.015);
}

// KITTI 00 ground truth: keep every 10th pose as a keyframe, interpolate the other nine.
TEST(Orb2Colmap, Kitti00EveryTenthPoseInterpolated) {
  std::string data = test::DataDir();
  if (data.empty()) GTEST_SKIP() << "MVTM_DATA not present";
  std::string dir = data + "/slam_trajectories/kitti00/";
  Trajectory gt = ReadKittiPoses(dir + "KITTI_00_gt.txt", dir + "times.txt");
  ASSERT_EQ(gt.poses.size(), 4541u);
  auto out = test::FreshDir("o2c-kitti");
  {
    std::ofstream f(out / "kf.txt");
    for (size_t i = 0; i < gt.poses.size(); i += 10) {
      Eigen::Matrix<double, 3, 4> m = gt.poses[i].pose.Matrix3x4();
      for (int j = 0; j < 12; ++j) f << (j ? " " : "") << FormatDouble(m(j / 4, j % 4));
      f << "\n";
    }
    std::ofstream t(out / "kf_times.txt");
    for (size_t i = 0; i < gt.poses.size(); i += 10) t << FormatDouble(gt.poses[i].time) << "\n";
  }
  Orb2ColmapOptions o;
  o.trajectory = (out / "kf.txt").string();
  o.trajectory_times = (out / "kf_times.txt").string();
  o.frames = dir + "times.txt";
  o.camera = "PINHOLE 1241 376 718.856 718.856 607.1928 185.2157";
  o.outdir = (out / "model").string();
  o.binary = true;
  Orb2ColmapReport rep = RunOrb2Colmap(o);
  // 4541 frames; the last keyframe is pose 4540, so nothing lies outside the span.
  EXPECT_EQ(rep.written, 4541u);
  Reconstruction r = ReadColmapBinary(o.outdir);
  auto ims = InOrder(r);
  double sum_t = 0, max_t = 0, sum_r = 0, max_r = 0;
  size_t n = 0;
  for (size_t i = 0; i < gt.poses.size(); ++i) {
    Rigid3d c2w = ims[i]->world_to_camera.Inverse();
    double et = (c2w.t - gt.poses[i].pose.t).norm();
    double er = RotationAngle(c2w.q, gt.poses[i].pose.q) * 180 / M_PI;
    if (i % 10 == 0) {
      EXPECT_LT(et, 1e-9);  // keyframes come back exactly (up to w2c↔c2w rounding)
      continue;
    }
    sum_t += et, sum_r += er, ++n;
    max_t = std::max(max_t, et), max_r = std::max(max_r, er);
  }
  std::printf(
      "[kitti00 1-in-10] %zu interpolated poses: translation mean %.4f m max %.4f m; "
      "rotation mean %.4f deg max %.4f deg\n",
      n, sum_t / n, max_t, sum_r / n, max_r);
  // Bounds. Keyframes are 1.0 s apart and the car drives up to ~13 m/s: in KITTI 00's 90° turns
  // the chord of a 1 s arc misses the arc by up to v·T·θ/8 ≈ 0.8 m, and the ground truth's
  // pitch/roll vibration (several Hz) cannot be recovered from 1 Hz samples, hence degrees of
  // rotation error at worst. scipy's Slerp + numpy interp on the same keyframes give exactly
  // these figures (tests/peer/orb2colmap_scipy.py: translation mean 0.1131 m, max 0.8429 m;
  // rotation mean 0.7397°, max 6.3263°). Bounds: those values plus ~5 %.
  EXPECT_LT(sum_t / n, 0.12);
  EXPECT_LT(max_t, 0.89);
  EXPECT_LT(sum_r / n, 0.78);
  EXPECT_LT(max_r, 6.65);
}

TEST(Orb2Colmap, HardCases) {
  auto d = test::FreshDir("o2c-hard");
  auto run = [&](const std::string& traj, const std::string& frames,
                 Outside outside = Outside::kDrop) {
    test::WriteFile(d / "kf.txt", traj);
    test::WriteFile(d / "frames.txt", frames);
    Orb2ColmapOptions o;
    o.trajectory = (d / "kf.txt").string();
    o.frames = (d / "frames.txt").string();
    o.camera = "PINHOLE 100 50 80 80 50 25";
    o.outdir = (d / "m").string();
    o.outside = outside;
    o.quiet = true;
    o.force = true;  // inputs change between runs faster than file times may resolve
    RunOrb2Colmap(o);
    return ReadColmapText(o.outdir);
  };
  const double s = std::sqrt(0.5);
  // Antipodal quaternions at consecutive keyframes: q(t=2) = −(rotation by 90° about y).
  std::string yaw90 = " 0 " + FormatDouble(s) + " 0 " + FormatDouble(s) + "\n";
  std::string yaw90neg = " 0 " + FormatDouble(-s) + " 0 " + FormatDouble(-s) + "\n";
  Reconstruction r = run("0 0 0 0 0 0 0 1\n1 1 0 0" + yaw90 + "2 2 0 0" + yaw90neg, "1.5 a.png\n");
  Rigid3d c2w = r.images.begin()->second.world_to_camera.Inverse();
  EXPECT_LT(RotationAngle(c2w.q, Eigen::Quaterniond(s, 0, s, 0)), 1e-12);  // not a 360° spin
  EXPECT_LT((c2w.t - Eigen::Vector3d(1.5, 0, 0)).norm(), 1e-12);
  // A timestamp exactly on a keyframe gives the keyframe pose exactly.
  r = run("0 0 0 0 0 0 0 1\n1 1 2 3" + yaw90, "1 a.png\n0 b.png\n");
  EXPECT_LT((r.images.at(1).world_to_camera.Inverse().t - Eigen::Vector3d(1, 2, 3)).norm(), 1e-14);
  EXPECT_EQ(r.images.at(2).world_to_camera.t, Eigen::Vector3d(0, 0, 0));
  // Unsorted keyframes are sorted; an exact duplicate is merged.
  r = run("1 1 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", "0.25 a.png\n");
  EXPECT_LT((r.images.at(1).world_to_camera.Inverse().t - Eigen::Vector3d(0.25, 0, 0)).norm(),
            1e-15);
  // Outside the span: dropped by default, clamped on request.
  r = run("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", "-1 a.png\n0.5 b.png\n2 c.png\n");
  EXPECT_EQ(r.images.size(), 1u);
  r = run("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", "-1 a.png\n0.5 b.png\n2 c.png\n", Outside::kClamp);
  EXPECT_EQ(r.images.size(), 3u);
  EXPECT_EQ(r.images.at(3).world_to_camera.Inverse().t, Eigen::Vector3d(1, 0, 0));
  // Errors naming the line.
  auto error_of = [&](const std::string& traj, const std::string& frames) -> std::string {
    try {
      run(traj, frames);
    } catch (const Error& e) {
      std::string w = e.what();
      return w.substr(w.rfind('/') + 1);
    }
    return "no error";
  };
  EXPECT_EQ(error_of("0 0 0 0 0 0 0 1\n1 1 0 nan 0 0 0 1\n", "0 a.png\n"),
            "kf.txt:2: tz: 'nan' is not finite");
  EXPECT_EQ(error_of("", "0 a.png\n"),
            "kf.txt: cannot tell the trajectory format: the file has no poses");
  EXPECT_EQ(error_of("0 0 0 0 0 0 0 1\n0 1 0 0 0 0 0 1\n", "0 a.png\n"),
            "kf.txt:2: timestamp 0.000000 repeats line 1 with a different pose");
  EXPECT_EQ(error_of("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", "0 a.png\n0.5 a.png\n"),
            "frames.txt:2: frame name 'a.png' repeats line 1");
  EXPECT_EQ(error_of("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", "5 a.png\n"),
            "kf.txt: no frame lies inside the pose time span (use --outside clamp?)");
}

}  // namespace
}  // namespace mvtm
