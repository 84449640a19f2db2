// The GAZE reader (gaze/gaze_tsv.h): columns by header, invalid samples counted, errors on one
// line with FILE:LINE.
#include "gaze/gaze_tsv.h"

#include <gtest/gtest.h>

#include <sstream>

#include "base/error.h"

namespace mvtm {
namespace {

GazeTrace Read(const std::string& text) {
  std::istringstream in(text);
  return ReadGazeTsv(in, "g.tsv");
}

std::string ErrorOf(const std::string& text) {
  try {
    Read(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(GazeTsv, ReadsColumnsByNameAndCountsInvalidSamples) {
  const GazeTrace g = Read(
      "# tracker export\npupil\tvalid\ty\ttime\tx\n3.1\t1\t20.5\t0.000\t10\n"
      "3.0\t0\t20\t0.004\t11\n0\t1\tnan\t0.008\tnan\n3.2\t1\t21\t0.012\tinf\n3.2\t1\t22\t0."
      "016\t12\n");
  ASSERT_EQ(g.samples.size(), 5u);
  EXPECT_EQ(g.ignored, std::vector<std::string>{"pupil"});
  EXPECT_EQ(g.samples[0].x, 10);
  EXPECT_EQ(g.samples[0].y, 20.5);
  EXPECT_EQ(g.samples[0].line, 3);
  EXPECT_FALSE(g.samples[1].valid);  // valid = 0
  EXPECT_FALSE(g.samples[2].valid);  // nan
  EXPECT_FALSE(g.samples[3].valid);  // inf
  EXPECT_TRUE(g.samples[4].valid);
  EXPECT_EQ(g.invalid_flagged, 1u);
  EXPECT_EQ(g.invalid_nonfinite, 2u);
  // Without a valid column every finite sample is valid.
  EXPECT_TRUE(Read("time x y\n0 1 2\n1 3 4\n").samples[1].valid);
}

TEST(GazeTsv, ErrorsNameTheFileAndLine) {
  EXPECT_EQ(ErrorOf("0 1 2\n"),
            "g.tsv:1: expected a header naming the columns 'time x y [valid]', found a row of "
            "numbers");
  EXPECT_EQ(ErrorOf("time x\n"),
            "g.tsv:1: the header has no column 'y' (expected a header naming 'time x y [valid]')");
  EXPECT_EQ(ErrorOf("time x y\n0 1 2\n0.5 1\n"),
            "g.tsv:3: expected 3 fields as in the header, found 2");
  EXPECT_EQ(ErrorOf("time x y\n0 1 2\n1 1 2\n0.5 1 2\n"),
            "g.tsv:4: time 0.5 is before line 3's 1: samples must be in time order");
  EXPECT_EQ(ErrorOf("time x y\n0 1 2\n0 1 2\n"), "g.tsv:3: time 0 repeats line 2");
  EXPECT_EQ(ErrorOf("time x y\nnan 1 2\n"), "g.tsv:2: time: 'nan' is not finite");
  EXPECT_EQ(ErrorOf("time x y valid\n0 1 2 2\n"), "g.tsv:2: valid: '2' is not 0 or 1");
  EXPECT_EQ(ErrorOf("time x y\n0 1 2\n"), "g.tsv:2: needs at least two samples, found 1");
  EXPECT_EQ(ErrorOf("time x y\n0 a 2\n"), "g.tsv:2: x: 'a' is not a number");
}

}  // namespace
}  // namespace mvtm
