// AOIs (gaze/aoi.h): class names, boxes, the dwell table.
#include "gaze/aoi.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/error.h"

namespace mvtm {
namespace {

TEST(Aoi, ClassNamesAreCamVids) {
  EXPECT_EQ(CamVidClassName(3), "road");
  EXPECT_EQ(CamVidClassName(1), "building");
  EXPECT_EQ(CamVidClassName(8), "car");
  EXPECT_EQ(CamVidClassName(11), "unlabelled");
  EXPECT_EQ(CamVidClassName(200), "class-200");
}

TEST(Aoi, BoxesFirstContainingWinsAndDwellSums) {
  const auto p = std::filesystem::temp_directory_path() / "mvtm-aoi-boxes.txt";
  std::ofstream(p) << "# name xmin ymin zmin xmax ymax zmax\nsign 0 0 0 1 1 1\n"
                      "verge -1 -1 -1 2 2 2\n";
  const auto boxes = ReadAoiBoxes(p.string());
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(BoxContaining(boxes, {0.5, 0.5, 0.5}), "sign");
  EXPECT_EQ(BoxContaining(boxes, {1, 1, 1}), "sign");  // faces included
  EXPECT_EQ(BoxContaining(boxes, {1.5, 0, 0}), "verge");
  EXPECT_EQ(BoxContaining(boxes, {3, 0, 0}), "");
  std::ofstream(p) << "a 0 0 0 1 1 1\nb 0 0 5 1 1 1\n";
  try {
    ReadAoiBoxes(p.string());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), p.string() + ":2: zmin 5 is greater than zmax 1");
  }
  std::filesystem::remove(p);
  const auto t = DwellTable({"road", "sign", "road", "car"}, {0.25, 0.5, 0.5, 0.125});
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].aoi, "road");
  EXPECT_EQ(t[0].fixations, 2u);
  EXPECT_EQ(t[0].dwell, 0.75);
  EXPECT_EQ(t[1].aoi, "sign");
  EXPECT_EQ(t[2].aoi, "car");
  EXPECT_DOUBLE_EQ(t[0].share, 0.75 / 1.375);
}

}  // namespace
}  // namespace mvtm
