// Trajectory readers: real TUM/KITTI/NeRF files from MVTM_DATA, hand-made files with known
// answers, and FILE:LINE errors.
#include "io/trajectory.h"

#include <gtest/gtest.h>

#include <sstream>
#include <streambuf>

#include "base/error.h"
#include "comma_locale.h"
#include "io/colmap_model.h"
#include "test_util.h"

namespace mvtm {
namespace {

TEST(Trajectory, TumConvertsAndNormalises) {
  auto d = test::FreshDir("tum");
  test::WriteFile(d / "t.txt",
                  "# t tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 0 2\n2.5 4 5 6 0 0.7071067811865476 0 "
                  "0.7071067811865476\n");
  EXPECT_EQ(DetectTrajectoryFormat((d / "t.txt").string()), TrajectoryFormat::kTum);
  Trajectory t = ReadTum((d / "t.txt").string());
  ASSERT_EQ(t.poses.size(), 2u);
  EXPECT_EQ(t.poses[0].time, 1.5);
  EXPECT_EQ(t.poses[0].pose.q.w(), 1.0);  // normalised from (0,0,0,2)
  EXPECT_EQ(t.poses[1].pose.t, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(t.poses[1].line, 3);
}

TEST(Trajectory, TumAndKittiRoundTripUnderCommaLocale) {
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");
  auto d = test::FreshDir("tum-rt");
  std::vector<StampedPose> poses;
  for (int i = 0; i < 5; ++i) {
    Eigen::Quaterniond q(Eigen::AngleAxisd(0.1 * i + 0.05, Eigen::Vector3d(1, 2, 3).normalized()));
    poses.push_back({1305031102.175304 + 0.1 * i,
                     Rigid3d(q, Eigen::Vector3d(451000.125 + i, 5410000.5, 120.0 / 7)), 0});
  }
  WriteTum((d / "t.txt").string(), poses);
  Trajectory t = ReadTum((d / "t.txt").string());
  ASSERT_EQ(t.poses.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(t.poses[i].time, poses[i].time);
    EXPECT_EQ(t.poses[i].pose.t, poses[i].pose.t);
    EXPECT_LT(RotationAngle(t.poses[i].pose.q, poses[i].pose.q), 1e-15);
  }
  WriteKittiPoses((d / "k.txt").string(), poses);
  Trajectory k = ReadKittiPoses((d / "k.txt").string());
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(k.poses[i].pose.t, poses[i].pose.t);
    EXPECT_LT(RotationAngle(k.poses[i].pose.q, poses[i].pose.q), 1e-15);
  }
}

TEST(Trajectory, ErrorsNameTheLine) {
  auto d = test::FreshDir("tum-bad");
  struct C {
    std::string text, msg;
  };
  std::vector<C> cases = {
      {"1 0 0 0 0 0 0 1\n2 0 0 nan 0 0 0 1\n", "t.txt:2: tz: 'nan' is not finite"},
      {"1 0 0 0 0 0 0 0\n", "t.txt:1: quaternion has zero norm"},
      {"1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n",
       "t.txt:2: TUM pose needs 8 fields (timestamp tx ty tz qx qy qz qw), found 7"},
      {"# only a comment\n", "t.txt: trajectory file has no poses"},
      {"", "t.txt: trajectory file has no poses"},
      {"1 0 0 0 0 0 0 x1\n", "t.txt:1: qw: 'x1' is not a number"},
  };
  for (const auto& c : cases) {
    test::WriteFile(d / "t.txt", c.text);
    try {
      ReadTum((d / "t.txt").string());
      ADD_FAILURE() << c.msg;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), (d / c.msg).string());
    }
  }
  test::WriteFile(d / "k.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 0 0\n");
  try {
    ReadKittiPoses((d / "k.txt").string());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              (d / "k.txt:2: rotation part is not a rotation (det 0)").string());
  }
}

// A forward-only stream like a pipe or std::cin: one character at a time, and seeking fails
// (and is counted, so a test can say it never happened).
class PipeBuf : public std::streambuf {
 public:
  explicit PipeBuf(std::string text) : text_(std::move(text)) {}
  int seeks = 0;

 protected:
  int_type underflow() override {
    if (next_ >= text_.size()) return traits_type::eof();
    c_ = text_[next_++];
    setg(&c_, &c_, &c_ + 1);
    return traits_type::to_int_type(c_);
  }
  pos_type seekoff(off_type, std::ios_base::seekdir, std::ios_base::openmode) override {
    ++seeks;
    return pos_type(off_type(-1));
  }
  pos_type seekpos(pos_type, std::ios_base::openmode) override {
    ++seeks;
    return pos_type(off_type(-1));
  }

 private:
  std::string text_;
  size_t next_ = 0;
  char c_ = 0;
};

void ExpectSameTrajectory(const Trajectory& a, const Trajectory& b) {
  ASSERT_EQ(a.poses.size(), b.poses.size());
  for (size_t i = 0; i < a.poses.size(); ++i) {
    EXPECT_EQ(a.poses[i].time, b.poses[i].time) << i;
    EXPECT_EQ(a.poses[i].line, b.poses[i].line) << i;
    EXPECT_EQ(a.poses[i].pose.t, b.poses[i].pose.t) << i;
    EXPECT_EQ(a.poses[i].pose.q.coeffs(), b.poses[i].pose.q.coeffs()) << i;
  }
  EXPECT_EQ(a.names, b.names);
}

std::vector<StampedPose> SomePoses() {
  std::vector<StampedPose> poses;
  for (int i = 0; i < 4; ++i) {
    Eigen::Quaterniond q(Eigen::AngleAxisd(0.2 * i + 0.1, Eigen::Vector3d(1, -2, 3).normalized()));
    poses.push_back(
        {100.25 + i, Rigid3d(q, Eigen::Vector3d(451000.5 + i, 5410000.25, 120.0 / 7)), 0});
  }
  return poses;
}

// Every format, read from a file, from an istringstream and from a pipe-like stream with the
// format detected from the stream itself: the same poses, times, lines and names.
TEST(Trajectory, StreamsGiveWhatTheFileGives) {
  test::ScopedCommaLocale comma;
  auto d = test::FreshDir("traj-stream");
  WriteTum((d / "t.txt").string(), SomePoses());
  WriteKittiPoses((d / "k.txt").string(), SomePoses());
  test::WriteFile(d / "k-gaps.txt", "\n# comment\n" + test::ReadFile(d / "k.txt") + "\n");
  Reconstruction model;
  for (const auto& p : SomePoses()) {
    ImageRecord im;
    im.id = static_cast<uint32_t>(p.time);
    im.camera_id = 1;
    im.name = "img" + std::to_string(im.id) + ".png";
    im.world_to_camera = p.pose.Inverse();
    model.images[im.id] = im;
  }
  WriteColmapText(model, (d / "sparse").string());
  const std::string images = (d / "sparse" / "images.txt").string();
  // Without its header comment a COLMAP images.txt is told by its 10 fields.
  std::string bare = test::ReadFile(images);
  bare = bare.substr(bare.find("\n", bare.rfind("# ")) + 1);
  test::WriteFile(d / "bare.txt", bare);

  struct Case {
    std::string file;
    TrajectoryFormat format;
  };
  for (const Case& c : {Case{(d / "t.txt").string(), TrajectoryFormat::kTum},
                        Case{(d / "k.txt").string(), TrajectoryFormat::kKitti},
                        Case{(d / "k-gaps.txt").string(), TrajectoryFormat::kKitti},
                        Case{images, TrajectoryFormat::kColmap},
                        Case{(d / "bare.txt").string(), TrajectoryFormat::kColmap}}) {
    SCOPED_TRACE(c.file);
    EXPECT_EQ(DetectTrajectoryFormat(c.file), c.format);
    const Trajectory file = ReadTrajectory(c.file);
    EXPECT_EQ(file.poses.size(), 4u);
    std::istringstream text(test::ReadFile(c.file));
    ExpectSameTrajectory(file, ReadTrajectory(text, c.file, c.format));
    PipeBuf pipe(test::ReadFile(c.file));
    std::istream in(&pipe);
    ExpectSameTrajectory(file, ReadTrajectory(in, c.file));
    EXPECT_EQ(pipe.seeks, 0);
  }
  // The per-format stream readers agree with their path versions too.
  std::istringstream tum(test::ReadFile(d / "t.txt"));
  ExpectSameTrajectory(ReadTum((d / "t.txt").string()), ReadTum(tum, (d / "t.txt").string()));
  std::istringstream kitti(test::ReadFile(d / "k.txt"));
  ExpectSameTrajectory(ReadKittiPoses((d / "k.txt").string()), ReadKittiPoses(kitti, "k"));
  // COLMAP images: camera-to-world poses, image ids as times, names, pose lines.
  const Trajectory colmap = ReadTrajectory(images);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(colmap.poses[i].time, SomePoses()[i].time - 0.25);
    EXPECT_EQ(colmap.poses[i].line, static_cast<long>(5 + 2 * i));
    EXPECT_LT((colmap.poses[i].pose.t - SomePoses()[i].pose.t).norm(), 1e-8);  // a few ulps of 5e6
    EXPECT_LT(RotationAngle(colmap.poses[i].pose.q, SomePoses()[i].pose.q), 1e-15);
  }
  EXPECT_EQ(colmap.names[3], "img103.png");
  // Timestamps.
  test::WriteFile(
      d / "rgb.txt",
      "# tum rgb.txt\n1305031102.175304 rgb/1305031102.175304.png\n1305031102.211214 rgb/b.png\n");
  std::istringstream ts(test::ReadFile(d / "rgb.txt"));
  auto from_file = ReadTimestamps((d / "rgb.txt").string());
  auto from_stream = ReadTimestamps(ts, "rgb");
  ASSERT_EQ(from_file.size(), 2u);
  ASSERT_EQ(from_stream.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(from_file[i].time, from_stream[i].time);
    EXPECT_EQ(from_file[i].name, from_stream[i].name);
    EXPECT_EQ(from_file[i].line, from_stream[i].line);
  }
}

// Errors from a stream name it as given, with the line counted across format detection.
TEST(Trajectory, PipeErrorsNameTheStreamAndLine) {
  struct C {
    std::string text, msg;
  };
  const std::vector<C> cases = {
      {"# c\n\n1 0 0 0 0 0 0 1\n2 0 0 nan 0 0 0 1\n", "-:4: tz: 'nan' is not finite"},
      {"1 0 0 0 0 0 0 1\n1 0 0 0 0 1 0 0 0 0 1 0\n",
       "-:2: TUM pose needs 8 fields (timestamp tx ty tz qx qy qz qw), found 12"},
      {"# c\n1 2 3 4 5\n",
       "-:2: cannot tell the trajectory format: 5 fields (TUM has 8, KITTI 12, COLMAP images.txt "
       "10)"},
      {"# only a comment\n", "-: cannot tell the trajectory format: the file has no poses"},
      {"", "-: cannot tell the trajectory format: the file has no poses"},
      {"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 0 0",
       "-:2: rotation part is not a rotation (det 0)"},
      {"1 0 0 0 0 0 0 0 1 a.png\n\n", "-:1: quaternion has zero norm"},
  };
  for (const auto& c : cases) {
    PipeBuf pipe(c.text);
    std::istream in(&pipe);
    try {
      ReadTrajectory(in, "-");
      ADD_FAILURE() << c.msg;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), c.msg);
    }
  }
}

TEST(Trajectory, KittiCalibAndOrbSettings) {
  auto d = test::FreshDir("calib");
  test::WriteFile(d / "calib.txt",
                  "P0: 7.070912000000e+02 0.000000000000e+00 6.018873000000e+02 0.000000000000e+00 "
                  "0.000000000000e+00 7.070912000000e+02 1.831104000000e+02 0.000000000000e+00 "
                  "0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n");
  Camera c = ReadKittiCalib((d / "calib.txt").string(), 0, 1226, 370);
  EXPECT_EQ(c.params, (std::vector<double>{707.0912, 707.0912, 601.8873, 183.1104}));
  EXPECT_THROW(ReadKittiCalib((d / "calib.txt").string(), 1, 1226, 370), Error);
  // ORB-SLAM2's KITTI00-02.yaml (values from Examples/Monocular/KITTI00-02.yaml).
  test::WriteFile(d / "orb.yaml",
                  "%YAML:1.0\nCamera.fx: 718.856\nCamera.fy: 718.856\nCamera.cx: 607.1928\n"
                  "Camera.cy: 185.2157\nCamera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\n"
                  "Camera.p2: 0.0\nCamera.fps: 10.0\nCamera.RGB: 1\n");
  EXPECT_THROW(ReadOrbSettings((d / "orb.yaml").string()), Error);  // no size
  Camera o = ReadOrbSettings((d / "orb.yaml").string(), 1241, 376);
  EXPECT_EQ(o.model, CameraModel::kPinhole);
  EXPECT_EQ(o.params, (std::vector<double>{718.856, 718.856, 607.1928, 185.2157}));
  // TUM1.yaml has distortion: OPENCV with k3 = 0 → 8 parameters.
  test::WriteFile(d / "tum.yaml",
                  "%YAML:1.0\nCamera.fx: 517.306408\nCamera.fy: 516.469215\nCamera.cx: 318.643040\n"
                  "Camera.cy: 255.313989\nCamera.k1: 0.262383\nCamera.k2: -0.953104\n"
                  "Camera.p1: -0.005358\nCamera.p2: 0.002628\nCamera.k3: 1.163314\n"
                  "Camera.width: 640\nCamera.height: 480\n");
  Camera t = ReadOrbSettings((d / "tum.yaml").string());
  EXPECT_EQ(t.model, CameraModel::kFullOpenCV);
  EXPECT_EQ(t.width, 640u);
  EXPECT_EQ(t.params[8], 1.163314);
}

TEST(Trajectory, NerfAxesConvertToCameraAxes) {
  // A camera at (1,2,3) with identity c2w in OpenGL axes looks down world −z, with image up = +y.
  auto d = test::FreshDir("nerf");
  test::WriteFile(d / "t.json",
                  R"({"w": 100, "h": 50, "fl_x": 80, "cx": 50, "cy": 25, "frames": [
                     {"file_path": "images/a.png", "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]}]})");
  NerfScene s = ReadNerfTransforms((d / "t.json").string());
  ASSERT_EQ(s.frames.poses.size(), 1u);
  Rigid3d w2c = s.frames.poses[0].pose.Inverse();
  EXPECT_LT((w2c.Centre() - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((w2c.ViewDirection() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  // A point above the camera (world +y) projects into the upper half: camera y < 0.
  EXPECT_LT((w2c * Eigen::Vector3d(1, 3, 0)).y(), 0);
  EXPECT_EQ(s.frames.names[0], "images/a.png");
  test::WriteFile(d / "bad.json", R"({"w": 100, "h": 50, "fl_x": "x", "frames": []})");
  try {
    ReadNerfTransforms((d / "bad.json").string());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), (d / "bad.json: /fl_x is not a number").string());
  }
}

TEST(Trajectory, RealFiles) {
  std::string data = test::DataDir();
  if (data.empty()) GTEST_SKIP() << "MVTM_DATA not present";
  std::string st = data + "/slam_trajectories/";
  Trajectory kf = ReadTrajectory(st + "tum_fr1_xyz/KeyFrameTrajectory_ORB_mono.txt");
  EXPECT_EQ(kf.poses.size(), 32u);  // SOURCE.md: 32 lines
  Trajectory gt = ReadTrajectory(st + "tum_fr1_xyz/groundtruth.txt");
  EXPECT_EQ(gt.poses.size(), 3000u);  // 3003 lines, 3 comments
  Trajectory k = ReadKittiPoses(st + "kitti00/KITTI_00_gt.txt", st + "kitti00/times.txt");
  EXPECT_EQ(k.poses.size(), 4541u);
  EXPECT_EQ(k.poses[0].time, 0.0);
  EXPECT_GT(k.poses[4540].time, 400.0);
  auto ts = ReadTimestamps(data + "/tum_fr1_desk_9frames/rgb.txt");
  EXPECT_EQ(ts.size(), 9u);
  EXPECT_EQ(ts[0].name.substr(0, 4), "rgb/");
  NerfScene fox = ReadNerfTransforms(data + "/instant_ngp_fox/transforms.json");
  EXPECT_EQ(fox.frames.poses.size(), 67u);  // README: 67 photos
  EXPECT_EQ(fox.camera.width, 1080u);
}

}  // namespace
}  // namespace mvtm
