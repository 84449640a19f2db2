// mvtm — which frames of a dashcam video make a road build (frames): chosen by travelled image
// motion, not by time, so a stop at a red light gives one frame, not 300; blurred frames
// dropped; burned-in overlays (timestamp text, logos) found as the pixels that keep their edges
// while the scene moves.
//
//  * Sharpness: the variance of the Laplacian of the grey frame (Pech-Pacheco et al. 2000), on
//    the frame scaled to at most 640 pixels wide (so the measure does not depend on the video's
//    resolution), per tile of an 8 × 4 grid; the frame's sharpness is the upper quartile of its
//    tiles (the textured part of the view decides; a sharp overlay burned in after the blur
//    covers too few tiles to hide it). A frame is blurred when its sharpness is below `blur_ratio`
//    × the median sharpness of the previous `blur_window` decoded frames (a causal window: one pass
//    over the video, and a slow change of scene texture is not blur).
//  * Motion: corners (Shi-Tomasi, up to 500, masked by the overlay and the user's mask) of each
//    decoded frame tracked into the next by pyramidal Lucas-Kanade (forward-backward checked,
//    1 px); a step's motion is the median displacement of the tracked corners divided by the
//    frame's width, and the travelled motion since the last kept frame is the sum of the steps.
//    (Tracking from the kept frame itself fails on fast roads: the near corners are lost first
//    and the median of the survivors stalls.) When fewer than 20 % of the corners (or fewer
//    than 15) survive a step, the view has changed (a cut): the motion counts as infinite.
//  * Selection: the first sharp frame is kept; then a frame is kept when it is sharp and its
//    motion since the last kept frame reaches `spacing`. A stationary stretch never reaches it.
//  * Overlay: over consecutive kept frames (the scene has moved between them by `spacing`), a
//    pixel is static when its grey level changed by at most 6 in at least 97 % of the pairs
//    while a strong edge (Sobel magnitude ≥ 40) stayed on it in at least 80 % of the kept frames;
//    static pixels are
//    closed and dilated (7 px: the strokes of text that changes, such as clock digits, and the
//    halo of compression) into the overlay mask. Featureless static areas (a saturated sky, a
//    bonnet's flat paint) are not overlays: crop or mask them explicitly. Needs at least 8 pairs.
// Thread safety: a FrameSelector is stateful; one per video.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace mvtm {

struct FrameSelectOptions {
  double spacing = 0.01;    // median image motion between kept frames, fraction of the width
  double blur_ratio = 0.5;  // sharper than this × the recent median, or the frame is blurred
  int blur_window = 15;     // decoded frames in that median
  bool no_overlay = false;  // do not look for burned-in overlays
};

// The upper quartile over 8 × 4 tiles of the variance of the Laplacian of an 8-bit grey image
// (scaled to ≤ 640 wide first).
double Sharpness(const cv::Mat& grey);

struct FrameDecision {
  bool keep = false;
  bool blurred = false;
  double sharpness = 0;
  double motion = 0;  // since the last kept frame (fraction of the width; inf: moved on)
};

class FrameSelector {
 public:
  // `mask`: 8-bit, non-zero = not the scene (bonnet, a known overlay); may be empty.
  FrameSelector(const FrameSelectOptions& options, cv::Mat mask);

  // Decides on the next decoded frame (8-bit grey, constant size).
  FrameDecision Next(const cv::Mat& grey);

  // The overlay found so far (8-bit, 255 = overlay): empty when fewer than 8 moving pairs were
  // seen or no pixel is static.
  cv::Mat Overlay() const;
  size_t moving_pairs() const { return pairs_; }

 private:
  void Keep(const cv::Mat& grey);
  double StepMotion(const cv::Mat& small) const;
  void Corners(const cv::Mat& small);

  FrameSelectOptions o_;
  cv::Mat mask_;                // user mask (non-zero = not scene)
  std::vector<double> recent_;  // recent sharpness values (ring)
  size_t recent_next_ = 0;
  bool have_key_ = false;
  cv::Mat key_grey_;    // the last kept frame
  cv::Mat prev_small_;  // the previous decoded frame (working size) and its corners
  std::vector<cv::Point2f> prev_pts_;
  double travelled_ = 0;  // image motion since the last kept frame
  cv::Mat overlay_;       // Overlay() as of the last kept frame
  bool overlay_dirty_ = false;
  cv::Mat unchanged_, edged_;  // per-pixel counts over kept pairs / kept frames (CV_32S)
  size_t pairs_ = 0, kept_ = 0;
};

}  // namespace mvtm
