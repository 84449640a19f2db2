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
