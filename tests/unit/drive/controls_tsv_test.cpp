// The controls log reader: columns by name, ignored columns, and one-line FILE:LINE errors.
#include "drive/controls_tsv.h"

#include <gtest/gtest.h>

#include <sstream>

#include "base/error.h"

namespace mvtm {
namespace {

ControlsLog Read(const std::string& text) {
  std::istringstream in(text);
  return ReadControlsTsv(in, "c.tsv");
}

std::string Message(const std::string& text) {
  try {
    Read(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ControlsTsv, ColumnsByNameExtraColumnsIgnored) {
  const ControlsLog log = Read(
      "# a simulator log\nspeed\tthrottle\ttime\tsteer\tbrake\n10\t0.2\t0\t0\t0\n\n"
      "12.5 0.3 1.5 -30 0\n");
  ASSERT_EQ(log.samples.size(), 2u);
  EXPECT_EQ(log.samples[1].time, 1.5);
  EXPECT_EQ(log.samples[1].steer_deg, -30);
  EXPECT_EQ(log.samples[1].speed, 12.5);
  EXPECT_EQ(log.samples[1].line, 5);
  EXPECT_EQ(log.ignored, (std::vector<std::string>{"throttle", "brake"}));
}

TEST(ControlsTsv, Errors) {
  EXPECT_EQ(Message(""),
            "c.tsv: empty file: expected a header naming the columns 'time steer speed'");
  EXPECT_EQ(Message("0 0 10\n1 0 10\n"),
            "c.tsv:1: expected a header naming the columns 'time steer speed', found a row of "
            "numbers");
  EXPECT_EQ(
      Message("t steer speed\n0 0 10\n"),
      "c.tsv:1: the header has no column 'time' (expected a header naming 'time steer speed')");
  EXPECT_EQ(
      Message("time steer\n0 0\n"),
      "c.tsv:1: the header has no column 'speed' (expected a header naming 'time steer speed')");
  EXPECT_EQ(Message("time steer speed time\n"),
            "c.tsv:1: the header names the column 'time' twice");
  EXPECT_EQ(Message("time steer speed\n0 0 10\n1 0\n"),
            "c.tsv:3: expected 3 fields as in the header, found 2");
  EXPECT_EQ(Message("time steer speed\n0 0 10\n1 nan 10\n"), "c.tsv:3: steer: 'nan' is not finite");
  EXPECT_EQ(Message("time steer speed\n0 0 inf\n"), "c.tsv:2: speed: 'inf' is not finite");
  EXPECT_EQ(Message("time steer speed\n0 0 1O\n"), "c.tsv:2: speed: '1O' is not a number");
  EXPECT_EQ(Message("time steer speed\n0 0 10\n1 0 10\n1 5 10\n"),
            "c.tsv:4: time 1 repeats line 3");
  EXPECT_EQ(Message("time steer speed\n0 0 10\n2 0 10\n1 5 10\n"),
            "c.tsv:4: time 1 is before line 3's 2: samples must be in time order");
  EXPECT_EQ(Message("time steer speed\n0 0 10\n"),
            "c.tsv:2: needs at least two samples (the first and the last time), found 1");
}

}  // namespace
}  // namespace mvtm
