#include "run/option_table.h"
#include "track/tracker.h"

namespace mvtm {

void DeclareTrackOptions(OptionTable& t, TrackOptions& o) {
  t.Integer("--max-missed", &o.max_missed, "A track ends after N consecutive frames without a blob")
      .AtLeast(1);
  t.Integer("--max-gap", &o.max_gap, "Fill gaps of at most G missed frames by interpolation")
      .AtLeast(0);
  t.Real("--smooth", &o.smooth, "Gaussian sigma in frames for centroid and size (0: off)")
      .AtLeast(0);
  t.Integer("--min-life", &o.min_life,
            "Reject tracks (stretches between gaps over --max-gap) spanning fewer than N frames")
      .AtLeast(1);
  t.Real("--min-ratio", &o.min_ratio,
         "Reject tracks (stretches between gaps over --max-gap) detected in less than this "
         "share of their span")
      .Range(0, 1);
  t.Integer("--dilate", &o.dilate, "Dilate the masks by a disk of radius PX").Range(0, 1000);
}

}  // namespace mvtm
