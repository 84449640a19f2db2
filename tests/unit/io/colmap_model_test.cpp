// COLMAP model I/O: exact round trips (text and binary, under a comma-decimal locale) and
// FILE:LINE errors for every kind of malformed input.
#include "io/colmap_model.h"

#include <gtest/gtest.h>

#include <chrono>
#include <clocale>
#include <future>
#include <locale>
#include <random>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "comma_locale.h"
#include "support/killed_commit.h"
#include "test_util.h"

namespace mvtm {
namespace {

Reconstruction RandomModel(int n_images, int n_points, uint32_t seed) {
  std::mt19937 g(seed);
  std::normal_distribution<double> nd;
  Reconstruction r;
  Camera c = ParseCameraSpec("PINHOLE 1241 376 718.856 718.856 607.1928 185.2157");
  c.id = 3;
  r.cameras[3] = c;
  Camera d = ParseCameraSpec("OPENCV 640 480 500.5 501.25 320.1 239.9 0.1 -0.01 0.001 0.0002");
  d.id = 7;
  r.cameras[7] = d;
  for (int i = 0; i < n_images; ++i) {
    ImageRecord im;
    im.id = static_cast<uint32_t>(10 + i * 3);
    im.camera_id = i % 2 ? 3 : 7;
    im.name = "seq/" + std::to_string(i) + ".png";
    im.world_to_camera = Rigid3d(Eigen::Quaterniond(nd(g), nd(g), nd(g), nd(g)).normalized(),
                                 Eigen::Vector3d(nd(g), nd(g), nd(g)) * 5e6);
    for (int k = 0; k < 5; ++k)
      im.points2D.push_back({Eigen::Vector2d(nd(g) * 100, nd(g) * 100), kInvalidPoint3DId});
    r.images[im.id] = im;
  }
  for (int p = 0; p < n_points; ++p) {
    Point3D pt;
    pt.id = static_cast<uint64_t>(p + 1);
    pt.xyz = Eigen::Vector3d(nd(g), nd(g), nd(g)) * 1e3 + Eigen::Vector3d(451000, 5410000, 120);
    pt.rgb[0] = static_cast<uint8_t>(p);
    pt.rgb[1] = 255;
    pt.error = std::abs(nd(g));
    auto it = r.images.begin();
    std::advance(it, p % n_images);
    uint32_t idx = static_cast<uint32_t>(p % 5);
    pt.track.push_back({it->first, idx});
    it->second.points2D[idx].point3D_id = pt.id;
    r.points3D[pt.id] = pt;
  }
  return r;
}

void ExpectSame(const Reconstruction& a, const Reconstruction& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, c] : a.cameras) {
    EXPECT_EQ(c.model, b.cameras.at(id).model);
    EXPECT_EQ(c.params, b.cameras.at(id).params);
    EXPECT_EQ(c.width, b.cameras.at(id).width);
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (const auto& [id, im] : a.images) {
    const auto& o = b.images.at(id);
    EXPECT_EQ(im.name, o.name);
    EXPECT_EQ(im.camera_id, o.camera_id);
    EXPECT_EQ(im.world_to_camera.t, o.world_to_camera.t);
    EXPECT_LT(RotationAngle(im.world_to_camera.q, o.world_to_camera.q), 1e-15);
    ASSERT_EQ(im.points2D.size(), o.points2D.size());
    for (size_t k = 0; k < im.points2D.size(); ++k) {
      EXPECT_EQ(im.points2D[k].xy, o.points2D[k].xy);
      EXPECT_EQ(im.points2D[k].point3D_id, o.points2D[k].point3D_id);
    }
  }
  ASSERT_EQ(a.points3D.size(), b.points3D.size());
  for (const auto& [id, p] : a.points3D) {
    const auto& o = b.points3D.at(id);
    EXPECT_EQ(p.xyz, o.xyz);
    EXPECT_EQ(p.error, o.error);
    EXPECT_EQ(p.track.size(), o.track.size());
    EXPECT_EQ(p.rgb[0], o.rgb[0]);
  }
}

TEST(ColmapModel, TextRoundTripIsExactUnderCommaLocale) {
  test::ScopedCommaLocale comma;
  ASSERT_EQ(test::ScopedCommaLocale::Probe(), "1.234,5");  // the locale is really in effect
  auto d = test::FreshDir("colmap-text");
  Reconstruction r = RandomModel(6, 20, 1);
  WriteColmapText(r, d.string());
  Reconstruction back = ReadColmapText(d.string());
  ExpectSame(r, back);
  // Writing what was read gives the same bytes (quaternions are already canonical).
  WriteColmapText(back, (d / "again").string());
  for (const char* f : {"cameras.txt", "images.txt", "points3D.txt"})
    EXPECT_EQ(test::ReadFile(d / f), test::ReadFile(d / "again" / f)) << f;
  // Under the comma locale, numbers are still written with a point.
  std::string cams = test::ReadFile(d / "cameras.txt");
  EXPECT_NE(
      cams.find(
          "3 PINHOLE 1241 376 718.85599999999999 718.85599999999999 607.19280000000003 185.2157\n"),
      std::string::npos)
      << cams;
}

TEST(ColmapModel, BinaryRoundTripIsExact) {
  auto d = test::FreshDir("colmap-bin");
  Reconstruction r = RandomModel(5, 12, 2);
  WriteColmapBinary(r, d.string());
  Reconstruction back = ReadColmapModel(d.string());  // picks binary
  ExpectSame(r, back);
  WriteColmapText(back, (d / "t").string());
  ExpectSame(back, ReadColmapText((d / "t").string()));
}

TEST(ColmapModel, WritingOneFormatRemovesTheOther) {
  // A model rewritten as text where a binary one was must be what is read back (binary is read
  // first), and the other way round.
  auto d = test::FreshDir("colmap-formats");
  const Reconstruction old_model = RandomModel(4, 6, 5), new_model = RandomModel(3, 5, 6);
  WriteColmapBinary(old_model, d.string());
  WriteColmapText(new_model, d.string());
  EXPECT_FALSE(std::filesystem::exists(d / "images.bin"));
  EXPECT_FALSE(IsColmapBinaryModel(d.string()));
  ExpectSame(new_model, ReadColmapModel(d.string()));
  WriteColmapBinary(old_model, d.string());
  EXPECT_FALSE(std::filesystem::exists(d / "cameras.txt"));
  EXPECT_EQ(ColmapModelFiles(d.string()).size(), 3u);
  ExpectSame(old_model, ReadColmapModel(d.string()));
}

// A writer killed between the three renames (after cameras.txt, a forked child SIGKILLing itself
// there) leaves a journal: the next ReadColmapModel reads the new model whole, never the mix.
TEST(ColmapModel, KillBetweenRenamesReadsTheNewModelWhole) {
  for (bool old_binary : {true, false}) {
    auto d = test::FreshDir("colmap-kill");
    const Reconstruction old_model = RandomModel(4, 6, 5), new_model = RandomModel(3, 5, 6);
    if (old_binary)
      WriteColmapBinary(old_model, d.string());
    else
      WriteColmapText(old_model, d.string());
    ASSERT_TRUE(
        test::CommitKilledAfterFirstRename([&] { WriteColmapText(new_model, d.string()); }));
    // Killed between cameras.txt's rename and images.txt's: the old binary model is gone and the
    // new one incomplete, or the old text's images and points sit beside the new cameras.
    EXPECT_EQ(std::filesystem::exists(d / "images.txt"), !old_binary);
    ExpectSame(new_model, ReadColmapModel(d.string()));
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(d),
                            std::filesystem::directory_iterator()),
              3);
  }
}

// A live writer between its renames: ReadColmapModel waits for it (the folder's lock) and reads
// the new model whole, never its new cameras beside the old images.
TEST(ColmapModel, ALiveWritersRenamesAreWaitedFor) {
  auto d = test::FreshDir("colmap-live");
  const Reconstruction old_model = RandomModel(4, 6, 5), new_model = RandomModel(3, 5, 6);
  WriteColmapText(old_model, d.string());
  test::PausedCommit writer([&] { WriteColmapText(new_model, d.string()); });
  auto reader = std::async(std::launch::async, [&] { return ReadColmapModel(d.string()); });
  EXPECT_EQ(reader.wait_for(std::chrono::milliseconds(300)), std::future_status::timeout);
  writer.Resume();
  ExpectSame(new_model, reader.get());
  EXPECT_TRUE(writer.Finished());
}

// The names of a model's images, read from its images file alone: the same in either format as
// the model's, and a live commit from text to binary (the text files removed first) is waited
// for, not taken for a folder without a model.
TEST(ColmapModel, ImageNamesWaitForALiveCommitOfTheOtherFormat) {
  auto d = test::FreshDir("colmap-names");
  const Reconstruction old_model = RandomModel(4, 6, 5), new_model = RandomModel(3, 5, 7);
  const auto names = [](const Reconstruction& r) {
    std::vector<std::string> n;
    for (const auto& [id, im] : r.images) n.push_back(im.name);
    return n;
  };
  WriteColmapBinary(new_model, d.string());
  EXPECT_EQ(ReadColmapImageNames(d.string()), names(new_model));
  WriteColmapText(old_model, d.string());
  EXPECT_EQ(ReadColmapImageNames(d.string()), names(old_model));
  test::PausedCommit writer([&] { WriteColmapBinary(new_model, d.string()); });
  auto reader = std::async(std::launch::async, [&] { return ReadColmapImageNames(d.string()); });
  EXPECT_EQ(reader.wait_for(std::chrono::milliseconds(300)), std::future_status::timeout);
  writer.Resume();
  EXPECT_EQ(reader.get(), names(new_model));
  EXPECT_TRUE(writer.Finished());
  std::filesystem::remove(d / "images.bin");
  std::filesystem::remove(d / "cameras.bin");
  EXPECT_THROW(ReadColmapImageNames(d.string()), Error);
}

TEST(ColmapModel, EmptyPointsLineAndEmptyModel) {
  auto d = test::FreshDir("colmap-empty");
  Reconstruction r = RandomModel(3, 0, 3);
  for (auto& [id, im] : r.images) im.points2D.clear();
  WriteColmapText(r, d.string());
  Reconstruction back = ReadColmapText(d.string());
  EXPECT_EQ(back.images.size(), 3u);
  EXPECT_TRUE(back.points3D.empty());
}

// The stream readers are what the path reader runs: from an istringstream they give the same
// model, and their messages name the stream as given.
TEST(ColmapModel, StreamReadersGiveWhatTheFileGives) {
  test::ScopedCommaLocale comma;
  auto d = test::FreshDir("colmap-stream");
  Reconstruction r = RandomModel(6, 20, 5);
  WriteColmapText(r, d.string());
  Reconstruction file = ReadColmapText(d.string());
  Reconstruction stream;
  std::istringstream cams(test::ReadFile(d / "cameras.txt"));
  std::istringstream imgs(test::ReadFile(d / "images.txt"));
  std::istringstream pts(test::ReadFile(d / "points3D.txt"));
  stream.cameras = ReadColmapCamerasText(cams, "cams");
  stream.images = ReadColmapImagesText(imgs, "imgs");
  stream.points3D = ReadColmapPoints3DText(pts, "pts");
  ExpectSame(file, stream);
  ExpectSame(r, stream);
  for (const auto& [id, im] : file.images)
    EXPECT_EQ(im.world_to_camera.q.coeffs(), stream.images.at(id).world_to_camera.q.coeffs());

  // File order and pose lines (after the 4 header lines, two lines per image).
  std::istringstream again(test::ReadFile(d / "images.txt"));
  std::vector<std::pair<uint32_t, long>> seen;
  ForEachColmapImageText(again, "imgs",
                         [&](ImageRecord&& im, long line) { seen.emplace_back(im.id, line); });
  ASSERT_EQ(seen.size(), r.images.size());
  long line = 5;
  auto it = r.images.begin();
  for (const auto& [id, at] : seen) {
    EXPECT_EQ(id, (it++)->first);
    EXPECT_EQ(at, line);
    line += 2;
  }

  std::istringstream bad("1 1 0 0 0 0 0 0 1 a.png\n\n1 1 0 0 0 0 0 0 1 b.png\n\n");
  try {
    ReadColmapImagesText(bad, "-");
    ADD_FAILURE() << "duplicate IMAGE_ID not reported";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "-:3: duplicate IMAGE_ID 1");
  }
  std::istringstream bad_cam("1 PINHOLE 100 50 80 80 50\n");
  try {
    ReadColmapCamerasText(bad_cam, "-");
    ADD_FAILURE() << "short camera line not reported";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "-:1: PINHOLE takes 4 parameters, found 3");
  }
}

struct BadCase {
  const char* file;
  std::string content;
  std::string message;  // expected what(), with DIR/ prefix replaced
};

TEST(ColmapModel, MalformedInputNamesFileAndLine) {
  const std::string cams = "1 PINHOLE 100 50 80 80 50 25\n";
  const std::string img1 = "1 1 0 0 0 0 0 0 1 a.png\n\n";
  const std::string pts = "";
  std::vector<BadCase> cases = {
      {"cameras.txt", "# c\n1 PINHOLE 100 50 80 80 50\n",
       "cameras.txt:2: PINHOLE takes 4 parameters, found 3"},
      {"cameras.txt", cams + "1 PINHOLE 100 50 80 80 50 25\n",
       "cameras.txt:2: duplicate CAMERA_ID 1"},
      {"cameras.txt", "1 NOPE 100 50 1\n", "cameras.txt:1: unknown camera model 'NOPE'"},
      {"images.txt", "1 0 0 0 0 0 0 0 1 a.png\n\n", "images.txt:1: quaternion has zero norm"},
      {"images.txt", "1 1 0 0 0 0 nan 0 1 a.png\n\n", "images.txt:1: TY: 'nan' is not finite"},
      {"images.txt", "1 1 0 0 0 0 0 1 a.png\n\n",
       "images.txt:1: image line needs 10 fields (IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME), "
       "found 9"},
      {"images.txt", img1 + "1 1 0 0 0 0 0 0 1 b.png\n\n", "images.txt:3: duplicate IMAGE_ID 1"},
      {"images.txt", "1 1 0 0 0 0 0 0 9 a.png\n\n",
       "images.txt: image 1 names camera 9 which does not exist"},
      {"images.txt", "1 1 0 0 0 0 0 0 1 a.png\n1 2 5\n",
       "images.txt: image 1 observes 3-D point 5 which does not exist"},
      {"images.txt", "1 1 0 0 0 0 0 0 1 a.png\n1 2\n",
       "images.txt:2: POINTS2D needs triples X Y POINT3D_ID"},
      {"images.txt", "1 1 0 0 0 0 0 0 1 a.png\n", "images.txt:1: image 1 has no POINTS2D line"},
      {"points3D.txt", "1 0 0 0 0 0 0 0.5 4 0\n",
       "points3D.txt: point 1 has a track element in image 4 which does not exist"},
      {"points3D.txt", "1 0 0 0 0 0 0 0.5 1 3\n",
       "points3D.txt: point 1 names 2-D point 3 of image 1 which has only 0"},
      {"points3D.txt", "1 0 0 0 300 0 0 0.5\n", "points3D.txt:1: colour component out of 0..255"},
  };
  for (const auto& c : cases) {
    auto d = test::FreshDir("colmap-bad");
    test::WriteFile(d / "cameras.txt", cams);
    test::WriteFile(d / "images.txt", img1);
    test::WriteFile(d / "points3D.txt", pts);
    test::WriteFile(d / c.file, c.content);
    try {
      ReadColmapText(d.string());
      ADD_FAILURE() << "no error for " << c.message;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), (d / c.message).string()) << c.content;
    }
  }
}

TEST(ColmapModel, TruncatedBinaryIsAnErrorNotACrash) {
  auto d = test::FreshDir("colmap-trunc");
  WriteColmapBinary(RandomModel(3, 4, 4), d.string());
  std::string img = test::ReadFile(d / "images.bin");
  for (size_t cut : {size_t(3), size_t(20), img.size() / 2, img.size() - 1}) {
    test::WriteFile(d / "images.bin", img.substr(0, cut));
    EXPECT_THROW(ReadColmapBinary(d.string()), Error) << cut;
  }
  // A count far larger than the file is rejected before allocating.
  std::string huge = img;
  huge[7] = '\x7f';
  test::WriteFile(d / "images.bin", huge);
  EXPECT_THROW(ReadColmapBinary(d.string()), Error);
}

TEST(ColmapModel, ReadsTheRealKittiModel) {
  std::string data = test::DataDir();
  if (data.empty()) GTEST_SKIP() << "MVTM_DATA not present";
  std::string dir = data + "/kitti_odom06_f000-050/colmap/sparse";
  if (!std::filesystem::exists(dir + "/images.txt") &&
      !std::filesystem::exists(dir + "/images.bin")) {
    for (auto& e : std::filesystem::directory_iterator(dir)) dir = e.path().string();
  }
  Reconstruction r = ReadColmapModel(dir);
  EXPECT_EQ(r.images.size(), 51u);  // SOURCE.md: 51/51 registered
  EXPECT_GT(r.points3D.size(), 1000u);
}

}  // namespace
}  // namespace mvtm

namespace mvtm {
namespace {

// The peer: COLMAP converts our text model to its binary; our binary reader must read back the
// same values (and COLMAP's text of our binary is checked in tests/peer/colmap_roundtrip.sh).
TEST(ColmapPeer, OurBinaryReaderReadsColmapsBinary) {
  if (std::system("command -v colmap >/dev/null 2>&1") != 0) GTEST_SKIP() << "colmap not installed";
  auto d = test::FreshDir("colmap-peer");
  Reconstruction r = RandomModel(8, 30, 9);
  WriteColmapText(r, (d / "txt").string());
  std::filesystem::create_directories(d / "bin");
  std::string cmd = "colmap model_converter --input_path " + (d / "txt").string() +
                    " --output_path " + (d / "bin").string() + " --output_type BIN >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  Reconstruction ours = ReadColmapText((d / "txt").string());
  Reconstruction theirs = ReadColmapBinary((d / "bin").string());
  ExpectSame(ours, theirs);
  // Bit-exact quaternions: COLMAP renormalised them on the way and nothing moved.
  for (const auto& [id, im] : ours.images)
    EXPECT_EQ(im.world_to_camera.q.coeffs(), theirs.images.at(id).world_to_camera.q.coeffs());
}

}  // namespace
}  // namespace mvtm
