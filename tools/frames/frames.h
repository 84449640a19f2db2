// frames — a dashcam video → the images of a road build (video/frame_select.h): frames chosen by
// travelled image motion and sharpness, the crop applied, burned-in overlays found, a timestamp
// per frame.
//
// Outputs (OUT/):
//   images/NNNNNN.png  the kept frames, named by their index in the video (sorted = time order)
//   frames.tsv         name, frame index, time (seconds from the video's start), sharpness,
//                      motion since the previous kept frame (fraction of the width)
//   mask.png           8-bit, 255 = not the scene (the overlay found, with --mask), in the
//                      cropped frame's size; absent when nothing is masked
//   colmap_mask.png    the same mask the other way round (0 = not the scene), for COLMAP's
//                      feature_extractor --ImageReader.camera_mask_path
// Decoding is one sequential pass (a video cannot be split without decoding it), so the tool
// takes no --shard; a rerun decodes again but writes only the images that are not up to date,
// and removes images of an earlier selection that this one does not keep.
#pragma once

#include <string>

#include "run/option_table.h"
#include "video/frame_select.h"

namespace mvtm {

struct FramesOptions {
  std::string video;
  std::string outdir;
  FrameSelectOptions select;  // --spacing, --blur-ratio, --blur-window, --no-overlay
  std::string crop;           // WxH+X+Y
  std::string mask;           // PNG, non-zero = not the scene (full frame size)
  bool force = false;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(FramesOptions& o);

struct FramesReport {
  bool up_to_date = false;
  std::string why;
  size_t decoded = 0, kept = 0, blurred = 0, still = 0, written = 0, removed = 0;
  size_t expected = 0;        // frames the container announces (0: unknown)
  size_t overlay_pixels = 0;  // found automatically
  double duration = 0;        // seconds decoded
};

FramesReport RunFrames(const FramesOptions& options);

}  // namespace mvtm
