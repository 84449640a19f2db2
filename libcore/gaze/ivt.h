// mvtm — the I-VT fixation filter (velocity-threshold identification; thesis App. A.1) as in the
// Tobii I-VT filter (A. Olsen, "The Tobii I-VT Fixation Filter", Tobii Technology, 2012), and the
// eye-to-screen geometry it measures angles with.
//
// Screen geometry. Gaze positions are screen pixels (gaze/gaze_tsv.h: (0, 0) the top-left corner,
// x right, y down). With a physical screen (width_mm × height_mm for width_px × height_px) seen
// from distance_mm, the eye sits on the normal through the screen's centre and the angle between
// two gaze points is the angle between the eye's rays to them (ocular degrees, not pixels: a pixel
// near the screen's edge subtends less than one at its centre). With px_per_degree instead, the
// angle is the pixel distance divided by it (a small-angle model, for when the geometry is not
// known).
//
// The filter, a pure function of the samples; its steps in Tobii's order:
//  1. Gap fill-in: a run of invalid samples with valid samples p before and q after is filled by
//     linear interpolation in time between p and q when t_q − t_p ≤ max_gap (0: off). Runs at the
//     start or the end of the trace stay invalid.
//  2. Noise reduction (median_window N > 0, odd): x and y of each valid sample are replaced by the
//     medians of the valid samples among the N centred on it (the window clipped at the ends; an
//     even count takes the mean of the two middle values). Off by default, as in Tobii's.
//  3. Velocity: at sample i, the angle between samples i − k and i + k (clipped to the trace)
//     over their time difference, in degrees per second, with k = max(1, round(window /
//     (2·dt))) and dt the median sample interval: a window of the given duration centred on the
//     sample, at least three samples. Undefined (NaN) when sample i or either end is invalid.
//  4. Classification: velocity < threshold: fixation; ≥ threshold: saccade; undefined: invalid.
//     A fixation is a maximal run of fixation samples: start = time of its first sample,
//     end = time of its last, duration = end − start; position = mean x, y of its samples.
//  5. Merge adjacent fixations: a fixation is merged into the one before it when the time between
//     them (its start − the other's end) < merge_time and the angle between their positions
//     < merge_angle (merge_time 0: off). The merged fixation spans both; its position is the mean
//     of all their fixation samples; it may merge with the next in turn.
//  6. Discard short fixations: those with duration < min_duration (0: off) are dropped and their
//     samples classified kDiscarded.
// Thread safety: functions are reentrant.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "gaze/gaze_tsv.h"

namespace mvtm {

struct ScreenGeometry {
  double width_px = 0, height_px = 0;  // the screen's resolution (> 0)
  double width_mm = 0, height_mm = 0;  // its physical size (0: use px_per_degree)
  double distance_mm = 0;              // eye to screen centre, along the screen's normal
  double px_per_degree = 0;            // used when width_mm is 0

  // Unit direction from the eye to screen point (x, y): x right, y down, z into the screen.
  // Physical geometry only.
  Eigen::Vector3d Direction(double x, double y) const;
  // Ocular angle between two screen points, degrees (see above).
  double AngleDeg(double x1, double y1, double x2, double y2) const;
};

struct IvtOptions {
  double max_gap = 0.075;          // seconds; gaps up to this are filled (0: off)
  int median_window = 0;           // samples, odd >= 3 (0: no noise reduction)
  double velocity_window = 0.020;  // seconds
  double threshold = 30;           // degrees per second
  double merge_time = 0.075;       // seconds (0: no merging)
  double merge_angle = 0.5;        // degrees
  double min_duration = 0.060;     // seconds (0: keep all)
};

enum class SampleClass { kInvalid, kFixation, kSaccade, kDiscarded };

struct Fixation {
  double start = 0, end = 0;   // seconds: first and last sample's time
  double x = 0, y = 0;         // mean screen position of its fixation samples
  size_t first = 0, last = 0;  // sample indices (inclusive)
  size_t samples = 0;          // fixation samples averaged (merged: of all parts)
  double duration() const { return end - start; }
};

struct IvtResult {
  std::vector<GazeSample> filtered;  // after gap fill-in and noise reduction
  std::vector<double> velocity;      // degrees per second, NaN where undefined
  std::vector<SampleClass> classes;
  std::vector<Fixation> fixations;
  size_t gaps_filled = 0, samples_filled = 0;
  size_t merged = 0, discarded = 0;  // merges done; fixations dropped as too short
  int velocity_half_window = 1;      // k of step 3
};

// Throws Error when there are fewer than two samples or times do not strictly increase.
IvtResult RunIvt(const std::vector<GazeSample>& samples, const ScreenGeometry& screen,
                 const IvtOptions& options);

}  // namespace mvtm
