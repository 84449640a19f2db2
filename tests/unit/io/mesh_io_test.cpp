// PLY through OpenMesh: round trips with colour and normals, UTM-sized coordinates, what is
// missing from a file, and errors.
#include "io/mesh_io.h"

#include <gtest/gtest.h>

#include "base/error.h"
#include "test_util.h"

namespace mvtm {
namespace {

Mesh Quad(Eigen::Vector3d origin) {
  Mesh m;
  m.vertices = {origin, origin + Eigen::Vector3d(1, 0, 0), origin + Eigen::Vector3d(1, 1, 0),
                origin + Eigen::Vector3d(0, 1, 0)};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  m.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {10, 20, 30}};
  m.ComputeNormals();
  return m;
}

TEST(MeshIo, RoundTripBinaryAndAscii) {
  auto d = test::FreshDir("mesh");
  for (bool ascii : {false, true}) {
    Mesh m = Quad({0.5, 0.25, 2});
    WriteMesh((d / "m.ply").string(), m, ascii);
    Mesh r = ReadMesh((d / "m.ply").string());
    ASSERT_EQ(r.vertices.size(), 4u);
    ASSERT_EQ(r.faces.size(), 2u);
    EXPECT_TRUE(r.missing.empty());
    EXPECT_EQ(r.vertices[2], m.vertices[2]);
    EXPECT_EQ(r.colors[3], m.colors[3]);
    EXPECT_LT((r.normals[0] - Eigen::Vector3f(0, 0, 1)).norm(), 1e-6);
    EXPECT_EQ(r.faces[1], m.faces[1]);
  }
}

TEST(MeshIo, UtmCoordinatesKeepMillimetres) {
  // A float32 PLY would round 5,410,000.123 m to 0.5 m steps.
  auto d = test::FreshDir("mesh-utm");
  Mesh m = Quad({451000.123, 5410000.456, 120.789});
  WriteMesh((d / "m.ply").string(), m);
  Mesh r = ReadMesh((d / "m.ply").string());
  for (size_t i = 0; i < 4; ++i) EXPECT_LT((r.vertices[i] - m.vertices[i]).norm(), 1e-6);
}

// A mesh written in parts (mkroad's long roads) reads back as the joined mesh: each part's face
// indices shifted by the vertices before it, at UTM coordinates and in ascii; parts that do not
// add up to the totals are an error and leave no file.
TEST(MeshIo, PartsReadBackAsTheJoinedMesh) {
  auto d = test::FreshDir("mesh-parts");
  const std::vector<Mesh> parts = {Quad({451000, 5410000, 120}), Quad({451002, 5410000, 120}),
                                   Quad({451004, 5410001, 121})};
  MeshTotals t;
  t.lo = Eigen::Vector3d::Constant(1e300);
  t.hi = -t.lo;
  for (const Mesh& p : parts) {
    t.vertices += p.vertices.size();
    t.faces += p.faces.size();
    for (const auto& v : p.vertices) t.lo = t.lo.cwiseMin(v), t.hi = t.hi.cwiseMax(v);
  }
  t.normals = t.colours = true;
  auto each = [&](bool, const MeshPartEmitter& emit) {
    for (const Mesh& p : parts) emit(p);
  };
  for (bool ascii : {false, true}) {
    WriteMeshParts((d / "parts.ply").string(), t, each, ascii);
    const Mesh r = ReadMesh((d / "parts.ply").string());
    ASSERT_EQ(r.vertices.size(), 12u);
    ASSERT_EQ(r.faces.size(), 6u);
    for (size_t k = 0; k < 3; ++k)
      for (size_t f = 0; f < 2; ++f)
        for (size_t c = 0; c < 3; ++c) {
          const uint32_t own = parts[k].faces[f][c];
          const uint32_t joined = r.faces[2 * k + f][c];
          EXPECT_EQ(joined, 4 * k + own);
          EXPECT_LT((r.vertices[joined] - parts[k].vertices[own]).norm(), 1e-6);
          EXPECT_EQ(r.colors[joined], parts[k].colors[own]);
        }
  }
  MeshTotals wrong = t;
  wrong.faces = 5;
  EXPECT_THROW(WriteMeshParts((d / "wrong.ply").string(), wrong, each), Error);
  EXPECT_FALSE(std::filesystem::exists(d / "wrong.ply"));
}

// roadmesh --dense marks its corridor faces (FaceKind) as the face property "mvtm_fill": it reads
// back in both encodings, a polygon's triangles take its kind, a mesh without one kind per face
// writes none, and a kind out of range is an error naming the file.
TEST(MeshIo, FaceKindsRoundTripAsAFaceProperty) {
  auto d = test::FreshDir("mesh-kinds");
  for (bool ascii : {false, true}) {
    Mesh m = Quad({0.5, 0.25, 2});
    m.face_kinds = {kFaceObserved, kFaceFillWall};
    WriteMesh((d / "m.ply").string(), m, ascii);
    const Mesh r = ReadMesh((d / "m.ply").string());
    EXPECT_EQ(r.face_kinds, m.face_kinds);
    EXPECT_EQ(r.faces, m.faces);
    EXPECT_EQ(r.colors, m.colors);
    m.face_kinds = {kFaceFillGround};  // not one per face: left out
    WriteMesh((d / "m.ply").string(), m, ascii);
    EXPECT_TRUE(ReadMesh((d / "m.ply").string()).face_kinds.empty());
  }
  // A quad (one polygon, kind 1) between two properties the reader does not know.
  test::WriteFile(d / "poly.ply",
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 2\nproperty float area\n"
                  "property list uchar int vertex_indices\nproperty uchar mvtm_fill\n"
                  "property list uchar float uv\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                  "1 4 0 1 2 3 1 2 0 0\n0.5 3 0 2 3 2 0\n");
  const Mesh r = ReadMesh((d / "poly.ply").string());
  ASSERT_EQ(r.faces.size(), 3u);
  EXPECT_EQ(r.face_kinds, (std::vector<uint8_t>{kFaceFillGround, kFaceFillGround, kFaceFillWall}));
  test::WriteFile(d / "bad.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                  "property uchar mvtm_fill\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 3\n");
  try {
    ReadMesh((d / "bad.ply").string());
    ADD_FAILURE() << "a kind of 3 was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("mvtm_fill"), std::string::npos) << e.what();
  }
}

TEST(MeshIo, ReportsWhatIsMissing) {
  auto d = test::FreshDir("mesh-missing");
  test::WriteFile(d / "p.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                  "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  Mesh r = ReadMesh((d / "p.ply").string());
  EXPECT_EQ(r.missing, (std::vector<std::string>{"normals", "colours"}));
  EXPECT_EQ(r.faces.size(), 1u);
  EXPECT_THROW(ReadMesh((d / "nope.ply").string()), Error);
  test::WriteFile(d / "junk.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_he");
  EXPECT_THROW(ReadMesh((d / "junk.ply").string()), Error);
}

}  // namespace
}  // namespace mvtm
