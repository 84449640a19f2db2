// The I-VT filter against hand-built traces, one case per rule (gaze/ivt.h). Samples are 1/128 s
// apart (exact in binary), so every duration below is exact and the expected fixations are
// worked out by hand in the comments.
#include "gaze/ivt.h"

#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"

namespace mvtm {
namespace {

constexpr double kDt = 1.0 / 128;

struct P {
  double x, y;
  bool valid = true;
};

std::vector<GazeSample> Trace(const std::vector<P>& pts) {
  std::vector<GazeSample> s;
  for (size_t i = 0; i < pts.size(); ++i)
    s.push_back({static_cast<double>(i) * kDt, pts[i].x, pts[i].y, pts[i].valid, long(i + 2)});
  return s;
}

void Hold(std::vector<P>& pts, int n, double x, double y = 100, bool valid = true) {
  for (int i = 0; i < n; ++i) pts.push_back({x, y, valid});
}

ScreenGeometry Ppd40() {
  ScreenGeometry g;
  g.width_px = 1000;
  g.height_px = 1000;
  g.px_per_degree = 40;
  return g;
}

TEST(Ivt, SaccadeSplitsFixationsAtTheThreshold) {
  // 20 samples at x = 100, 20 at x = 300: velocity at 19 and 20 spans the jump, 200 px = 5° over
  // 2 dt = 320°/s; everywhere else 0. Fixations: 0..18 and 21..39.
  std::vector<P> p;
  Hold(p, 20, 100);
  Hold(p, 20, 300);
  const IvtResult r = RunIvt(Trace(p), Ppd40(), {});
  EXPECT_EQ(r.velocity_half_window, 1);  // 20 ms / (2 · 7.8 ms) rounds to 1: three samples
  EXPECT_DOUBLE_EQ(r.velocity[19], 5 / (2 * kDt));
  EXPECT_EQ(r.classes[19], SampleClass::kSaccade);
  EXPECT_EQ(r.classes[18], SampleClass::kFixation);
  ASSERT_EQ(r.fixations.size(), 2u);
  EXPECT_EQ(r.fixations[0].first, 0u);
  EXPECT_EQ(r.fixations[0].last, 18u);
  EXPECT_EQ(r.fixations[0].end, 18 * kDt);
  EXPECT_EQ(r.fixations[1].first, 21u);
  EXPECT_EQ(r.fixations[1].x, 300);
  // The threshold is strict: a velocity equal to it is a saccade.
  IvtOptions o;
  o.threshold = 5 / (2 * kDt);
  EXPECT_EQ(RunIvt(Trace(p), Ppd40(), o).classes[19], SampleClass::kSaccade);
  // Just above it, nothing is a saccade: one fixation of all 40 samples at their mean.
  o.threshold = std::nextafter(o.threshold, 1e9);
  const IvtResult all = RunIvt(Trace(p), Ppd40(), o);
  ASSERT_EQ(all.fixations.size(), 1u);
  EXPECT_EQ(all.fixations[0].x, 200);
}

TEST(Ivt, AVelocityWindowLongerThanTheTraceSpansIt) {
  // Samples 2^-69 s apart and a 31 ms window: the half window would be ~10^19 samples (i + k
  // overflowed a long before). Beyond the trace it is the trace: every velocity spans first to
  // last sample, 200 px = 5° over 39 · 2^-69 s.
  std::vector<P> p;
  Hold(p, 20, 100);
  Hold(p, 20, 300);
  std::vector<GazeSample> s = Trace(p);
  for (size_t i = 0; i < s.size(); ++i) s[i].time = std::ldexp(double(i), -69);
  IvtOptions o;
  o.velocity_window = 0.031;
  o.min_duration = 0;
  const IvtResult r = RunIvt(s, Ppd40(), o);
  EXPECT_EQ(r.velocity_half_window, 40);
  EXPECT_DOUBLE_EQ(r.velocity[0], 5 / std::ldexp(39.0, -69));
  EXPECT_DOUBLE_EQ(r.velocity[39], r.velocity[0]);
}

TEST(Ivt, VelocityIsInOcularDegreesNotPixels) {
  // Screen 1000 px = 500 mm wide (0.5 mm per px) seen from 500 mm. The same drift of 2 px per
  // sample is faster in degrees at the centre than near the edge (230 mm out); a threshold
  // between the two speeds makes the drift at the centre a saccade and the one at the edge a
  // fixation, which no threshold in pixels per second could do. Speeds from the geometry by hand.
  ScreenGeometry g;
  g.width_px = g.height_px = 1000;
  g.width_mm = g.height_mm = 500;
  g.distance_mm = 500;
  EXPECT_NEAR(g.AngleDeg(500, 500, 600, 500), std::atan(0.1) * 180 / M_PI, 1e-12);
  EXPECT_NEAR(g.AngleDeg(900, 500, 1000, 500), (std::atan(0.5) - std::atan(0.4)) * 180 / M_PI,
              1e-12);
  auto drift = [&](double x0, double step) {
    std::vector<P> p;
    for (int i = 0; i < 12; ++i) p.push_back({x0 + i * step, 500});
    return Trace(p);
  };
  const double step = 2.0;  // px per sample
  // Velocity at sample 5: the angle between samples 4 and 6 over 2 dt.
  auto speed = [](double xa, double xb) {
    return (std::atan((xb - 500) * 0.5 / 500) - std::atan((xa - 500) * 0.5 / 500)) * 180 / M_PI /
           (2 * kDt);
  };
  const double v_centre = speed(502, 506), v_edge = speed(968, 972);
  IvtOptions o;
  o.threshold = 0.5 * (v_centre + v_edge);  // between the two: pixels alone cannot separate them
  o.min_duration = 0;
  const IvtResult centre = RunIvt(drift(494, step), g, o);
  const IvtResult edge = RunIvt(drift(960, step), g, o);
  EXPECT_NEAR(centre.velocity[5], v_centre, 1e-9 * v_centre);
  EXPECT_NEAR(edge.velocity[5], v_edge, 1e-9 * v_edge);
  EXPECT_TRUE(centre.fixations.empty());
  ASSERT_EQ(edge.fixations.size(), 1u);
  EXPECT_EQ(edge.fixations[0].first, 0u);
  EXPECT_EQ(edge.fixations[0].last, 11u);
}

TEST(Ivt, GapFillInBridgesShortGapsOnly) {
  // 8 invalid samples: the valid neighbours are 9 dt = 70.3 ms apart (<= 75): filled, one
  // fixation. 9 invalid: 10 dt = 78.1 ms: a blink; the samples next to it have no velocity, so
  // fixations 0..8 and 20..39 (not merged: 11 dt = 85.9 ms apart).
  std::vector<P> a;
  Hold(a, 10, 100);
  Hold(a, 8, NAN, NAN, false);
  Hold(a, 20, 100);
  const IvtResult ra = RunIvt(Trace(a), Ppd40(), {});
  EXPECT_EQ(ra.gaps_filled, 1u);
  EXPECT_EQ(ra.samples_filled, 8u);
  ASSERT_EQ(ra.fixations.size(), 1u);
  EXPECT_EQ(ra.fixations[0].last, 37u);
  EXPECT_EQ(ra.fixations[0].samples, 38u);

  std::vector<P> b;
  Hold(b, 10, 100);
  Hold(b, 9, NAN, NAN, false);
  Hold(b, 20, 100);
  const IvtResult rb = RunIvt(Trace(b), Ppd40(), {});
  EXPECT_EQ(rb.gaps_filled, 0u);
  EXPECT_EQ(rb.classes[9], SampleClass::kInvalid);
  ASSERT_EQ(rb.fixations.size(), 2u);
  EXPECT_EQ(rb.fixations[0].last, 8u);
  EXPECT_EQ(rb.fixations[1].first, 20u);
  // --max-gap 0: the short gap is not filled either.
  IvtOptions off;
  off.max_gap = 0;
  EXPECT_EQ(RunIvt(Trace(a), Ppd40(), off).fixations.size(), 2u);
}

TEST(Ivt, MovingMedianRemovesSpikes) {
  // 32 samples at x = 100 with a one-sample spike to 160 at 4, 9, ..., 29. Without noise
  // reduction the spikes' neighbours are saccades (60 px = 1.5° over 2 dt = 96°/s) and the
  // fragments left (at most 3 samples, 15.6 ms) are discarded as short; a 3-sample median
  // removes every spike: one fixation over all 32 samples at exactly x = 100.
  std::vector<P> p;
  for (int i = 0; i < 32; ++i) p.push_back({(i % 5 == 4 && i < 30) ? 160.0 : 100.0, 100});
  EXPECT_TRUE(RunIvt(Trace(p), Ppd40(), {}).fixations.empty());
  IvtOptions o;
  o.median_window = 3;
  const IvtResult r = RunIvt(Trace(p), Ppd40(), o);
  ASSERT_EQ(r.fixations.size(), 1u);
  EXPECT_EQ(r.fixations[0].samples, 32u);
  EXPECT_EQ(r.fixations[0].x, 100);
}

TEST(Ivt, MergesAdjacentFixationsCloseInTimeAndAngle) {
  // 20 samples at 100, a 2-sample glitch at 400, 20 samples at 104 (0.1°). Fixations 0..18 and
  // 23..42, 5 dt = 39 ms apart: merged; the position is the mean of their 39 samples.
  auto trace = [](double second_x, int glitch) {
    std::vector<P> p;
    Hold(p, 20, 100);
    Hold(p, glitch, 400);
    Hold(p, 20, second_x);
    return Trace(p);
  };
  const IvtResult r = RunIvt(trace(104, 2), Ppd40(), {});
  EXPECT_EQ(r.merged, 1u);
  ASSERT_EQ(r.fixations.size(), 1u);
  EXPECT_EQ(r.fixations[0].first, 0u);
  EXPECT_EQ(r.fixations[0].last, 41u);
  EXPECT_EQ(r.fixations[0].samples, 19u + 19u);
  EXPECT_DOUBLE_EQ(r.fixations[0].x, (19 * 100.0 + 19 * 104.0) / 38);
  // 0.75° apart: not merged.
  EXPECT_EQ(RunIvt(trace(130, 2), Ppd40(), {}).fixations.size(), 2u);
  // A 9-sample glitch: 12 dt = 94 ms apart: not merged.
  EXPECT_EQ(RunIvt(trace(104, 9), Ppd40(), {}).fixations.size(), 2u);
  // --merge-time 0: never merged.
  IvtOptions off;
  off.merge_time = 0;
  EXPECT_EQ(RunIvt(trace(104, 2), Ppd40(), off).fixations.size(), 2u);
}

TEST(Ivt, DiscardsFixationsShorterThanTheMinimum) {
  // 30 samples at 100, n at 300, 30 at 500: the middle fixation keeps n − 2 samples (its first
  // and last see the saccades), lasting (n − 3) dt: n = 10 → 54.7 ms < 60: discarded;
  // n = 11 → 62.5 ms: kept.
  auto trace = [](int n) {
    std::vector<P> p;
    Hold(p, 30, 100);
    Hold(p, n, 300);
    Hold(p, 30, 500);
    return Trace(p);
  };
  const IvtResult a = RunIvt(trace(10), Ppd40(), {});
  EXPECT_EQ(a.discarded, 1u);
  ASSERT_EQ(a.fixations.size(), 2u);
  EXPECT_EQ(a.classes[35], SampleClass::kDiscarded);
  const IvtResult b = RunIvt(trace(11), Ppd40(), {});
  EXPECT_EQ(b.discarded, 0u);
  ASSERT_EQ(b.fixations.size(), 3u);
  EXPECT_EQ(b.fixations[1].duration(), 8 * kDt);
  EXPECT_EQ(b.fixations[1].x, 300);
}

TEST(Ivt, RejectsTimesThatDoNotIncrease) {
  std::vector<GazeSample> s = Trace({{1, 1}, {2, 2}, {3, 3}});
  s[2].time = s[1].time;
  EXPECT_THROW(RunIvt(s, Ppd40(), {}), Error);
}

}  // namespace
}  // namespace mvtm
