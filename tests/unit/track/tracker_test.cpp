// Tracking cases whose answers are derived by hand: the frames are drawn from known boxes, so the
// expected boxes, states and track ids come from the drawing, not from the tracker.
#include "track/tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "base/error.h"
#include "track/blobs.h"

using namespace mvtm;

namespace {

constexpr int kW = 120, kH = 80;

struct Box {
  int x, y, w, h;
};

std::vector<uint8_t> Draw(const std::vector<Box>& boxes) {
  std::vector<uint8_t> m(kW * kH, 0);
  for (const Box& b : boxes)
    for (int y = std::max(0, b.y); y < std::min(kH, b.y + b.h); ++y)
      for (int x = std::max(0, b.x); x < std::min(kW, b.x + b.w); ++x) m[y * kW + x] = 1;
  return m;
}

std::vector<const TrackRow*> RowsOf(const TrackResult& r, int frame) {
  std::vector<const TrackRow*> out;
  auto [b, e] = r.FrameRows(frame);
  for (size_t i = b; i < e; ++i) out.push_back(&r.rows[i]);
  return out;
}

}  // namespace

TEST(BlobFinder, BoxesAndCentroids) {
  BlobFinder f;
  auto m = Draw({{10, 5, 4, 3}, {50, 2, 1, 1}});
  m[20 * kW + 30] = 1, m[21 * kW + 31] = 1;  // diagonal neighbours: one 8-connected blob
  auto blobs = f.Find(m.data(), kW, kH);
  ASSERT_EQ(blobs.size(), 3u);
  // Raster order of the first pixel: (50,2), (10,5), (30,20).
  EXPECT_EQ(blobs[0].x, 50);
  EXPECT_EQ(blobs[0].area, 1);
  EXPECT_EQ(blobs[1].x, 10);
  EXPECT_EQ(blobs[1].w, 4);
  EXPECT_EQ(blobs[1].h, 3);
  EXPECT_EQ(blobs[1].area, 12);
  EXPECT_DOUBLE_EQ(blobs[1].cx, 11.5);
  EXPECT_DOUBLE_EQ(blobs[1].cy, 6.0);
  EXPECT_EQ(blobs[2].area, 2);
  EXPECT_DOUBLE_EQ(blobs[2].cx, 30.5);
}

// A 10x8 box moving at (7, 3) px/frame over 9 frames; frame 4 has no blob. The interpolated
// blob must be the true box of frame 4 exactly, with and without smoothing.
TEST(Tracker, DroppedFrameIsInterpolatedExactly) {
  for (double sigma : {0.0, 1.0, 2.5}) {
    TrackOptions o;
    o.smooth = sigma;
    Tracker t(kW, kH, o);
    for (int f = 0; f < 9; ++f) {
      Box b{5 + 7 * f, 10 + 3 * f, 10, 8};
      auto m = Draw(f == 4 ? std::vector<Box>{} : std::vector<Box>{b});
      t.AddFrame(m.data());
    }
    TrackResult r = t.Finish();
    EXPECT_EQ(r.summary.tracks, 1);
    EXPECT_EQ(r.summary.kept, 1);
    EXPECT_EQ(r.summary.interpolated, 1u);
    auto rows = RowsOf(r, 4);
    ASSERT_EQ(rows.size(), 1u) << "sigma " << sigma;
    EXPECT_EQ(rows[0]->state, RowState::kInterpolated);
    EXPECT_EQ(rows[0]->x, 5 + 28);
    EXPECT_EQ(rows[0]->y, 10 + 12);
    EXPECT_EQ(rows[0]->w, 10);
    EXPECT_EQ(rows[0]->h, 8);
    EXPECT_EQ(rows[0]->area, 80);
    EXPECT_NEAR(rows[0]->scx, 5 + 28 + 4.5, 1e-9);
    // The rendered mask equals the drawn truth of frame 4.
    std::vector<uint8_t> mask;
    r.RenderMask(4, 0, mask);
    auto truth = Draw({{5 + 28, 10 + 12, 10, 8}});
    for (size_t i = 0; i < mask.size(); ++i)
      ASSERT_EQ(mask[i] != 0, truth[i] != 0) << "pixel " << i;
  }
}

// A box that grows by 2 px per frame in each direction: the gap is filled with the scaled blob.
TEST(Tracker, GrowingBoxIsScaled) {
  TrackOptions o;
  o.smooth = 0;
  Tracker t(kW, kH, o);
  for (int f = 0; f < 5; ++f) {
    auto m = Draw(f == 2 ? std::vector<Box>{}
                         : std::vector<Box>{{40 - f, 30 - f, 10 + 2 * f, 6 + 2 * f}});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  auto rows = RowsOf(r, 2);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0]->state, RowState::kInterpolated);
  EXPECT_EQ(rows[0]->x, 38);
  EXPECT_EQ(rows[0]->y, 28);
  EXPECT_EQ(rows[0]->w, 14);
  EXPECT_EQ(rows[0]->h, 10);
  EXPECT_EQ(rows[0]->area, 140);
}

// A blob seen in one frame only is a false positive: rejected, not in the mask.
TEST(Tracker, OneFrameSpuriousBlobIsRejected) {
  Tracker t(kW, kH, TrackOptions{});
  for (int f = 0; f < 6; ++f) {
    std::vector<Box> boxes{{10 + 2 * f, 40, 8, 8}};
    if (f == 3) boxes.push_back({90, 5, 5, 5});  // far from the car: a track of its own
    auto m = Draw(boxes);
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  EXPECT_EQ(r.summary.tracks, 2);
  EXPECT_EQ(r.summary.kept, 1);
  EXPECT_EQ(r.summary.rejected, 1);
  EXPECT_EQ(r.summary.rejected_blobs, 1u);
  auto rows = RowsOf(r, 3);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0]->track, 1);
  EXPECT_EQ(rows[0]->state, RowState::kDetected);
  EXPECT_EQ(rows[1]->track, 2);
  EXPECT_EQ(rows[1]->state, RowState::kRejected);
  std::vector<uint8_t> mask;
  r.RenderMask(3, 0, mask);
  EXPECT_EQ(mask[7 * kW + 92], 0);
  EXPECT_EQ(mask[44 * kW + 20], 255);
}

// Rejection by the detected/span ratio: seen in frames 0, 4, 8 (3 of a span of 9 < 0.5).
TEST(Tracker, LowRatioTrackIsRejected) {
  TrackOptions o;
  o.max_gap = 3;
  Tracker t(kW, kH, o);
  for (int f = 0; f < 9; ++f) {
    auto m = Draw(f % 4 == 0 ? std::vector<Box>{{50, 50, 6, 6}} : std::vector<Box>{});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  EXPECT_EQ(r.summary.tracks, 1);
  EXPECT_EQ(r.summary.rejected, 1);
  EXPECT_EQ(r.summary.interpolated, 0u);
  o.min_ratio = 0.3;  // 3/9 passes
  Tracker t2(kW, kH, o);
  for (int f = 0; f < 9; ++f) {
    auto m = Draw(f % 4 == 0 ? std::vector<Box>{{50, 50, 6, 6}} : std::vector<Box>{});
    t2.AddFrame(m.data());
  }
  TrackResult r2 = t2.Finish();
  EXPECT_EQ(r2.summary.kept, 1);
  EXPECT_EQ(r2.summary.interpolated, 6u);
}

// Rejection per stretch: a blob in frame 0 (a flicker), none for 12 frames (longer than max_gap,
// shorter than max_missed: the same track takes the next blob), then a vehicle at the same place
// in frames 13..20. Judged as one track, 9 detections over a span of 21 (< 0.5) would reject the
// vehicle with the flicker; cut at the gap never filled, the flicker (span 1 < min_life) goes and
// the vehicle (8 of 8) stays, and the gap stays open.
TEST(Tracker, RejectionIsJudgedPerStretchBetweenUnfilledGaps) {
  TrackOptions o;
  o.max_gap = 10;
  Tracker t(kW, kH, o);
  for (int f = 0; f < 21; ++f) {
    auto m = Draw(f == 0 || f >= 13 ? std::vector<Box>{{50, 50, 6, 6}} : std::vector<Box>{});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  EXPECT_EQ(r.summary.tracks, 1);
  EXPECT_EQ(r.summary.kept, 1);
  EXPECT_EQ(r.summary.rejected_blobs, 1u);
  EXPECT_EQ(r.summary.detected, 8u);
  EXPECT_EQ(r.summary.interpolated, 0u);
  EXPECT_EQ(r.summary.unfilled_gaps, 1u);
  ASSERT_EQ(RowsOf(r, 0).size(), 1u);
  EXPECT_EQ(RowsOf(r, 0)[0]->state, RowState::kRejected);
  EXPECT_TRUE(RowsOf(r, 5).empty());
  ASSERT_EQ(RowsOf(r, 15).size(), 1u);
  EXPECT_EQ(RowsOf(r, 15)[0]->state, RowState::kDetected);
  std::vector<uint8_t> mask;
  r.RenderMask(0, 0, mask);
  EXPECT_EQ(mask[52 * kW + 52], 0);
  r.RenderMask(15, 0, mask);
  EXPECT_EQ(mask[52 * kW + 52], 255);
}

// Two 8x8 boxes cross: A moves right along row 46..53, B down along column 56..63; at frame 5
// both are at (56, 46) and merge into one blob. Identities must survive the crossing, and the
// track that lost the merged blob is interpolated at its true position.
TEST(Tracker, CrossingTracksKeepTheirIds) {
  TrackOptions o;
  o.smooth = 0;
  Tracker t(kW, kH, o);
  auto a = [](int f) { return Box{6 + 10 * f, 46, 8, 8}; };
  auto b = [](int f) { return Box{56, -4 + 10 * f, 8, 8}; };
  for (int f = 1; f < 8; ++f) {
    auto m = Draw({a(f), b(f)});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  EXPECT_EQ(r.summary.tracks, 2);
  EXPECT_EQ(r.summary.kept, 2);
  for (int fi = 0; fi < 7; ++fi) {
    const int f = fi + 1;
    auto rows = RowsOf(r, fi);
    ASSERT_EQ(rows.size(), 2u) << "frame " << f;
    for (const TrackRow* row : rows) {
      const Box want =
          row->track == 1 ? b(f) : a(f);  // B's first pixel comes first in raster order
      EXPECT_EQ(row->x, want.x) << "frame " << f << " track " << row->track;
      EXPECT_EQ(row->y, std::max(0, want.y)) << "frame " << f << " track " << row->track;
    }
  }
  // Frame 5 (index 4): one detected (the merged blob), one interpolated.
  auto rows = RowsOf(r, 4);
  EXPECT_NE(rows[0]->state, rows[1]->state);
}

TEST(Tracker, TrackEndsAfterMaxMissed) {
  TrackOptions o;
  o.max_missed = 2;
  o.min_life = 1;
  Tracker t(kW, kH, o);
  for (int f = 0; f < 8; ++f) {
    // Seen at 0, 1, then 3 (1 missed: same track), then 6 (2 missed: a new track).
    bool seen = f == 0 || f == 1 || f == 3 || f == 6;
    auto m = Draw(seen ? std::vector<Box>{{20, 20, 5, 5}} : std::vector<Box>{});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  EXPECT_EQ(r.summary.tracks, 2);
  ASSERT_EQ(RowsOf(r, 6).size(), 1u);
  EXPECT_EQ(RowsOf(r, 6)[0]->track, 2);
  ASSERT_EQ(RowsOf(r, 2).size(), 1u);
  EXPECT_EQ(RowsOf(r, 2)[0]->state, RowState::kInterpolated);
}

TEST(Tracker, DilateGrowsTheMaskByADisk) {
  Tracker t(kW, kH, TrackOptions{});
  for (int f = 0; f < 3; ++f) {
    auto m = Draw({{60, 40, 1, 1}});
    t.AddFrame(m.data());
  }
  TrackResult r = t.Finish();
  std::vector<uint8_t> mask;
  r.RenderMask(1, 2, mask);
  int n = 0;
  for (uint8_t v : mask) n += v == 255;
  EXPECT_EQ(n, 13);  // the pixels within distance 2: 1 + 3 + 5 + 3 + 1
  EXPECT_EQ(mask[40 * kW + 62], 255);
  EXPECT_EQ(mask[42 * kW + 62], 0);
}

// The artefact RejectUnsupportedGaps is for: a small blob (frames 0-2) is lost, and two frames
// on the track takes another, larger thing 36 px away (frames 5-7); the gap between is filled
// with the small blob scaled and moved across the empty road. With evidence 0 on the filled
// pixels both filled rows go; with 0.3 on them they stay. Then fills under another track's
// detected blob: only the pixels outside it are judged.
TEST(Tracker, GapsTheEvidenceDoesNotSupportAreRejected) {
  TrackOptions o;
  o.smooth = 0;
  auto run = [&o] {
    Tracker t(kW, kH, o);
    for (int f = 0; f < 8; ++f) {
      auto m = Draw(f < 3   ? std::vector<Box>{{20, 20, 6, 6}}
                    : f < 5 ? std::vector<Box>{}
                            : std::vector<Box>{{40, 30, 30, 20}});
      t.AddFrame(m.data());
    }
    return t.Finish();
  };
  TrackResult r = run();
  ASSERT_EQ(r.summary.tracks, 1);
  ASSERT_EQ(r.summary.interpolated, 2u);
  std::vector<float> evidence(kW * kH, 0.f);
  for (int f : {3, 4}) {
    ASSERT_EQ(RowsOf(r, f).size(), 1u);
    EXPECT_EQ(RowsOf(r, f)[0]->state, RowState::kInterpolated);
    EXPECT_EQ(RejectUnsupportedGaps(r, f, evidence.data(), 0.1), 1u);
    EXPECT_EQ(RowsOf(r, f)[0]->state, RowState::kRejected);
    std::vector<uint8_t> mask;
    r.RenderMask(f, 0, mask);
    EXPECT_EQ(std::count(mask.begin(), mask.end(), 255), 0);
  }
  EXPECT_EQ(r.summary.interpolated, 0u);
  EXPECT_EQ(r.summary.unsupported_gaps, 2u);
  // Frames without an interpolated row are untouched.
  EXPECT_EQ(RejectUnsupportedGaps(r, 6, evidence.data(), 0.1), 0u);
  EXPECT_EQ(RowsOf(r, 6)[0]->state, RowState::kDetected);

  // Evidence of 0.3 on the filled pixels (and 0 elsewhere): kept at 0.1, rejected at 0.35.
  r = run();
  for (int f : {3, 4}) {
    std::vector<uint8_t> mask;
    r.RenderMask(f, 0, mask);
    for (size_t i = 0; i < mask.size(); ++i) evidence[i] = mask[i] ? 0.3f : 0.f;
    EXPECT_EQ(RejectUnsupportedGaps(r, f, evidence.data(), 0.1), 0u);
    EXPECT_EQ(RowsOf(r, f)[0]->state, RowState::kInterpolated);
    EXPECT_EQ(RejectUnsupportedGaps(r, f, evidence.data(), 0.35), 1u);
  }

  // Blobs by hand (AddBlobs): a wide box (rows 0-11) detected in every frame, and a 6x6 box
  // lost in frame 2 and filled there.
  auto box_blob = [](const Box& b) {
    return Blob{b.x,
                b.y,
                b.w,
                b.h,
                b.x + (b.w - 1) / 2.0,
                b.y + (b.h - 1) / 2.0,
                b.w * b.h,
                std::vector<uint8_t>(size_t(b.w * b.h), 1)};
  };
  auto fill_under_wide_box = [&](int small_y) {
    Tracker t(kW, kH, o);
    for (int f = 0; f < 5; ++f) {
      std::vector<Blob> blobs{box_blob({0, 0, kW, 12})};
      if (f != 2) blobs.push_back(box_blob({50, small_y, 6, 6}));
      t.AddBlobs(blobs);
    }
    TrackResult res = t.Finish();
    EXPECT_EQ(res.summary.interpolated, 1u);
    return res;
  };
  // Evidence 1 under the wide box, 0 elsewhere. Wholly under it (rows 2-7): nothing of its own
  // to judge, it stays.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) evidence[y * kW + x] = y < 12 ? 1.f : 0.f;
  TrackResult covered = fill_under_wide_box(2);
  EXPECT_EQ(RejectUnsupportedGaps(covered, 2, evidence.data(), 0.5), 0u);
  EXPECT_EQ(covered.summary.interpolated, 1u);
  // Rows 8-13: its 12 pixels below the wide box have evidence 0 and it goes; the covered pixels'
  // evidence (1) must not count, or the mean would be 24/36 or 24/12 and it would stay.
  TrackResult half = fill_under_wide_box(8);
  EXPECT_EQ(RejectUnsupportedGaps(half, 2, evidence.data(), 0.5), 1u);
}

TEST(TrackOptions, CheckNamesTheBadValue) {
  TrackOptions o;
  o.max_jump = 0;
  EXPECT_THROW(o.Check(), UsageError);
  o = TrackOptions{};
  o.min_ratio = 1.5;
  try {
    o.Check();
    FAIL();
  } catch (const FieldError& e) {  // named by its field; the tool's table names the flag
    EXPECT_EQ(e.field(), "min_ratio");
    EXPECT_STREQ(e.what(), "min_ratio: must be in 0..1, got 1.5");
  }
}
