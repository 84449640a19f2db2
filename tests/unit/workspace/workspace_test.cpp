// Workspace: derived names, readiness checks, provenance.
#include "workspace/workspace.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

#include "base/atomic_file.h"
#include "base/error.h"
#include "image/image.h"
#include "support/killed_commit.h"
#include "workspace/assets.h"

namespace mvtm {
namespace {

TEST(Workspace, DerivedPaths) {
  Workspace ws("/w");
  EXPECT_EQ(ws.MaskPath("A_0001.jpg"), fs::path("/w/masks/A_0001.png"));
  EXPECT_EQ(ws.DepthPath("sub/A_0001.png"), fs::path("/w/depth/sub/A_0001.exr"));
  EXPECT_EQ(ws.ImagePath("A_0001.jpg"), fs::path("/w/images/A_0001.jpg"));
}

TEST(Workspace, MissingItemsAndProvenance) {
  fs::path d = fs::temp_directory_path() / ("mvtm-ws-" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d / "images");
  Workspace ws(d);
  auto miss = ws.Missing({WsItem::kSparse, WsItem::kImages, WsItem::kMesh});
  ASSERT_EQ(miss.size(), 2u);
  EXPECT_EQ(miss[0], "sparse/ (COLMAP model: cameras, images, points3D)");
  try {
    ws.Require("ptmrender", {WsItem::kMesh});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              d.string() + ": not ready for ptmrender: missing mesh.ply (or meshed-poisson.ply)");
  }
  std::ofstream(d / "meshed-poisson.ply") << "x";
  EXPECT_EQ(ws.MeshPath(), d / "meshed-poisson.ply");  // a COLMAP dense workspace works as is
  EXPECT_TRUE(ws.Missing({WsItem::kMesh}).empty());
  // FNV-1a 64 of "x" (0x78): (offset ^ 0x78) * prime mod 2^64, computed independently in Python.
  EXPECT_EQ(FileChecksum(d / "meshed-poisson.ply"), "44bda3d473cdc381");
  // The record that says the model is metric: any tool's with "metric": true, but never the
  // asking tool's own (drive's --metric would make its record an input of itself).
  fs::create_directories(d / "provenance");
  std::ofstream(d / "provenance/drive.json") << R"({"tool": "drive", "options": {"metric": true}})";
  EXPECT_EQ(ws.MetricRecord(), d / "provenance/drive.json");
  EXPECT_EQ(ws.MetricRecord("drive"), fs::path());
  std::ofstream(d / "provenance/roadmesh.json") << R"({"options": {"metric": true}})";
  std::ofstream(d / "provenance/exposure.json") << "{not json";
  EXPECT_EQ(ws.MetricRecord("drive"), d / "provenance/roadmesh.json");
  fs::remove_all(d);
}

// densify writes a depth map and its confidence as one step: killed between the two renames, it
// leaves the new map beside the old confidence, and the next reader finishes the pair first.
TEST(Workspace, KillBetweenAStereoPairsRenamesReadsTheNewPairWhole) {
  const fs::path d = fs::temp_directory_path() / ("mvtm-ws-pair-" + std::to_string(getpid()));
  fs::remove_all(d);
  const Workspace ws(d);
  const Camera cam{1, CameraModel::kPinhole, 8, 6, {10, 10, 4, 3}};
  const std::string depth = ws.StereoDepthPath("A.png").string(),
                    conf = ws.StereoConfidencePath("A.png").string();
  const Image old_depth(8, 6, 1, 32, 5.f), old_conf(8, 6, 1, 32, 0.25f);
  const Image new_depth(8, 6, 1, 32, 7.f), new_conf(8, 6, 1, 32, 0.75f);
  CreateFolder(ws.StereoDir());
  WriteImage(depth, old_depth);
  WriteImage(conf, old_conf);
  ASSERT_TRUE(test::CommitKilledAfterFirstRename([&] {
    WriteImagesTogether({{depth, &new_depth}, {conf, &new_conf}});
  }));
  // The mix the kill left: the new depth beside the old confidence.
  EXPECT_EQ(ReadFloatMap(depth).data.front(), 7.f);
  EXPECT_EQ(ReadFloatMap(conf).data.front(), 0.25f);
  const Image both = ReadSeenDepthAtCamera(ws, "A.png", cam);
  ASSERT_EQ(both.channels, 2);
  for (size_t i = 0; i < both.pixels(); ++i) {
    ASSERT_EQ(both.data[2 * i], 7.f);
    ASSERT_EQ(both.data[2 * i + 1], 0.75f);
  }
  // The pair and nothing else: no journal, no temporary.
  EXPECT_EQ(std::distance(fs::directory_iterator(ws.StereoDir()), fs::directory_iterator()), 2);
  fs::remove_all(d);
}

}  // namespace
}  // namespace mvtm
