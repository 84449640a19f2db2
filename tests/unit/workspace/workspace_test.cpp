// Workspace: derived names, readiness checks, provenance.
#include "workspace/workspace.h"

#include <gtest/gtest.h>

#include <fstream>

#include "base/error.h"

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

}  // namespace
}  // namespace mvtm
