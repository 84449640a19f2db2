// mvtm — multi-view plane-sweep stereo on the CPU (Collins 1996; Gallup et al. 2007, "Real-time
// plane-sweeping stereo with multiple sweeping directions").
//
// Conventions:
//  * Everything is in the reference camera's coordinates (x right, y down, z forward). A sweep
//    plane is the set of points X with n·X = d, |n| = 1. A pixel's depth on a plane is the z of
//    the ray through the pixel centre where it meets the plane.
//  * Pixel centres follow COLMAP (top-left pixel centre at (0.5, 0.5)); images are grey float
//    (CV_32F) on the 0..255 scale of 8-bit images (min_texture is in those units). ZNCC does not
//    care about gain or offset, so exposure changes between photos do not bias the match.
//  * Lengths (plane offsets, depths) are in the model's own unit; nothing assumes metres.
//  * Matching cost: zero-mean normalised cross-correlation (ZNCC) over a square window between
//    the reference image and each neighbour warped onto it through the plane-induced
//    homography. Occlusion-robust aggregation: the mean of the best k of the neighbours' ZNCC.
//    Each sweep family (a normal and its plane offsets, ordered) is searched exhaustively; the
//    best plane is refined by a parabola through its neighbours' scores (sub-plane). Then each
//    pixel's winning plane is refined on its own (`refine` > 0): the aggregated ZNCC is
//    evaluated again at `refine` sub-steps per plane spacing on both sides of it, the window
//    warped by the homography of the pixel's own plane, and a parabola through the best
//    sub-step and its two sides gives the depth. Precision is then no longer bound by the plane
//    spacing (a facade 10 m to the side swept in 0.6 m steps), at about one sweep family's cost.
//  * Output: linear depth z (float32), +inf where nothing is trusted (score below the minimum,
//    a best plane that does not stand out from the others — no parallax, as near the epipole of
//    a forward-moving camera, or a repetitive texture —, a textureless window, fewer than k
//    neighbours that see the pixel, no plane in front), and a confidence in [0, 1]: the smaller
//    of the aggregated ZNCC and its margin over the family's mean (0 where the depth is +inf).
//
// Hard cases, all handled without NaN: a plane through the reference centre (d = 0: skipped),
// a plane through a neighbour's centre (singular homography: that neighbour abstains for that
// plane), a neighbour with no baseline (every plane maps alike: its scores do not discriminate;
// select neighbours with SelectStereoNeighbours), a textureless image (+inf everywhere), no
// neighbours (+inf everywhere).
//
// Thread safety: SweepDepth is reentrant; it parallelises over planes with OpenCV's pool.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"
#include "image/image.h"

namespace mvtm {

struct StereoView {
  Camera camera;            // undistorted, the size of `grey`
  Rigid3d world_to_camera;  // the pose of record
  cv::Mat grey;             // CV_32F
};

// One sweeping direction: a unit normal in the reference camera's coordinates and the plane
// offsets d to try, in increasing order (evenly spaced in `param`: see MakeSweep*).
struct SweepFamily {
  std::string name;  // "fronto", "ground", "facade"
  Eigen::Vector3d normal{0, 0, 1};
  std::vector<double> offsets;   // d of each plane
  bool inverse_spacing = false;  // offsets evenly spaced in 1/d (fronto: inverse depth), else in d
};

struct PlaneSweepOptions {
  int window = 7;          // ZNCC window side, odd, 3..31
  int best_k = 2;          // neighbours aggregated per pixel (the best k of N), ≥ 1
  double min_score = 0.5;  // aggregated ZNCC below which a pixel gets no depth, in [-1, 1]
  double min_texture =
      2.0;  // grey standard deviation (0..255 scale) below which a window is textureless
  double min_margin =
      0.2;         // best score minus the family's mean score below which the match is ambiguous
  int refine = 4;  // sub-steps per plane spacing of the per-pixel refinement (0: parabola only)

  void Check() const;  // throws UsageError naming the option
};

struct DepthMap {
  Image depth;       // 1 channel, bits 32: linear z, +inf = none
  Image confidence;  // 1 channel, bits 32: 0..1
};

// Fronto-parallel planes (n = +z) at depths near..far, evenly spaced in inverse depth.
SweepFamily MakeFrontoSweep(double near_z, double far_z, int planes);
// Planes with normal n (unit, reference coordinates) at offsets lo..hi, evenly spaced.
SweepFamily MakeOffsetSweep(const std::string& name, const Eigen::Vector3d& normal, double lo,
                            double hi, int planes);

// The plane-sweep depth map of `ref` against `neighbours` over every family.
DepthMap SweepDepth(const StereoView& ref, const std::vector<StereoView>& neighbours,
                    const std::vector<SweepFamily>& families, const PlaneSweepOptions& options);

// The homography taking reference pixels (COLMAP pixel coordinates, homogeneous) to neighbour
// pixels for the plane n·X = d of the reference frame. Exposed for tests.
Eigen::Matrix3d PlaneHomography(const StereoView& ref, const StereoView& neighbour,
                                const Eigen::Vector3d& n, double d);

}  // namespace mvtm
