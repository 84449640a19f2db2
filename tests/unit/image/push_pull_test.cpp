// image/push_pull: hand-derived properties of push-pull filling. Every filled value is a convex
// combination of known values (a constant stays that constant; values stay within the known
// range), known pixels are untouched, a mirror-symmetric layout fills mirror-symmetrically, and a
// gap between two flat regions fills monotonically from one to the other.
#include "image/push_pull.h"

#include <gtest/gtest.h>

#include "base/error.h"

namespace mvtm {
namespace {

TEST(PushPull, ConstantKnownPixelsFillTheHolesWithThatConstant) {
  Image img(37, 23, 3, 8, 0.f);  // odd sizes: pyramid levels with a ragged edge
  std::vector<uint8_t> known(img.pixels(), 1);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const bool hole = (x > 5 && x < 20 && y > 3 && y < 15) || (x == 36) || (y == 0);
      known[size_t(y) * img.width + x] = !hole;
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = hole ? 0.f : float(40 + 50 * c);
    }
  ASSERT_TRUE(PushPullFill(img, known));
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(img.at(x, y, c), 40 + 50 * c, 1e-4) << x << "," << y;
}

TEST(PushPull, KnownPixelsAreUntouchedAndFilledOnesStayInTheKnownRange) {
  Image img(50, 30, 1, 8);
  std::vector<uint8_t> known(img.pixels());
  uint32_t state = 12345;
  for (size_t p = 0; p < img.pixels(); ++p) {
    state = state * 1664525u + 1013904223u;
    known[p] = (state >> 24) % 3 == 0;  // a third known, at random
    img.data[p] = known[p] ? float(20 + (state >> 8) % 200) : -1.f;
  }
  const Image before = img;
  ASSERT_TRUE(PushPullFill(img, known));
  for (size_t p = 0; p < img.pixels(); ++p) {
    if (known[p]) {
      ASSERT_EQ(img.data[p], before.data[p]);
    } else {
      ASSERT_GE(img.data[p], 20.f - 1e-3f);
      ASSERT_LE(img.data[p], 220.f + 1e-3f);
    }
  }
}

TEST(PushPull, GapBetweenTwoFlatRegionsFillsSymmetricallyAndMonotonically) {
  // 16 columns: 0..5 at 0, 10..15 at 100, 6..9 unknown. Mirroring x → 15 − x maps the layout and
  // every pyramid level onto itself with the values v → 100 − v, so f(x) + f(15 − x) = 100.
  Image img(16, 16, 1, 8);
  std::vector<uint8_t> known(img.pixels());
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      known[size_t(y) * 16 + x] = x < 6 || x > 9;
      img.at(x, y) = x < 6 ? 0.f : x > 9 ? 100.f : 55.f;
    }
  ASSERT_TRUE(PushPullFill(img, known));
  for (int y = 0; y < 16; ++y) {
    for (int x = 6; x <= 9; ++x) EXPECT_NEAR(img.at(x, y) + img.at(15 - x, y), 100.f, 1e-3);
    EXPECT_GT(img.at(6, y), 0.f);
    EXPECT_LT(img.at(6, y), img.at(7, y));
    EXPECT_LT(img.at(7, y), img.at(8, y));
    EXPECT_LT(img.at(8, y), img.at(9, y));
    EXPECT_LT(img.at(9, y), 100.f);
  }
}

TEST(PushPull, OneKnownPixelColoursEverythingAndNoneChangesNothing) {
  Image img(9, 7, 3, 8, 5.f);
  std::vector<uint8_t> known(img.pixels(), 0);
  const Image before = img;
  EXPECT_FALSE(PushPullFill(img, known));
  EXPECT_EQ(img.data, before.data);
  img.at(8, 6, 0) = 200, img.at(8, 6, 1) = 100, img.at(8, 6, 2) = 0;
  known.back() = 1;
  ASSERT_TRUE(PushPullFill(img, known));
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 9; ++x) {
      EXPECT_NEAR(img.at(x, y, 0), 200.f, 1e-3);
      EXPECT_NEAR(img.at(x, y, 1), 100.f, 1e-3);
      EXPECT_NEAR(img.at(x, y, 2), 0.f, 1e-3);
    }
  EXPECT_THROW(PushPullFill(img, std::vector<uint8_t>(3, 1)), Error);
}

}  // namespace
}  // namespace mvtm
