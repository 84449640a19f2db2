// mvtm — what is not the static road, without labels: per-pixel evidence from the photographs
// of one drive and the static reconstruction (issue 21; dynmask).
//
// The method. A static surface point seen by the target photo at pixel p with the
// reconstruction's depth z(p) projects into a neighbouring photo j at q = π_j(X(p)); for a static
// scene, the photo's colour at p and j's at q agree (up to exposure and sampling), and the image
// motion between the target and j, once j is warped into the target through the static depth, is
// zero. A vehicle (or a cyclist, a pedestrian) moves between the exposures: at its pixels the
// warped neighbour shows something else (the road it was covering, or another part of it), and
// the residual motion is its own motion. Per neighbour j:
//  * Warp: j's luma resampled at q (bilinear) for each target pixel with finite depth; a
//    pixel is not valid for j when X is behind j, q falls outside j's image, or j's own static
//    depth at q is nearer than X by more than depth_tolerance · z (X is hidden in j), or j's own
//    first-pass probability at q is 0.5 or more (X is hidden in j by something that moves: the
//    road a vehicle covers in j is not evidence against this photo's road), or z(p) is under
//    j's `beyond` (a partner chosen for the far surfaces compares those only).
//  * Exposure: j's warped luma times the gain exp(median(log target − log warped)) over the
//    valid pixels (a camera's auto exposure changes between photos); with `colour`, each colour
//    channel warped and gained alike on its own (another white balance).
//  * Photometric residual: the distance of the target's luma to the interval [min, max] of the
//    gained warp over (2·slack+1)² pixels around p (Birchfield–Tomasi: a misalignment of up to
//    `slack` pixels, from pose or depth error, costs nothing at edges), averaged over a
//    window × window box (valid pixels only). With `colour`, when both views have colour
//    images and the target's is not grey (its channels all equal), the largest of that distance
//    over the three channels, times threshold / colour_threshold (a blue car on a grey road of
//    its brightness differs in its channels, not in its luma).
//  * Flow residual (optional): the length of DIS optical flow (OpenCV, coarse to fine) from the
//    target to the warp (invalid warp pixels replaced by the target's own, so they do not move),
//    in pixels: a vehicle moving with the camera keeps its place in the photos, but not in the
//    warp through the static depth behind it. Where the rigid motion |q − p| is large (the near
//    road), the warp is distorted more: the residual counts relative to
//    max(flow_threshold, flow_relative · |q − p|).
// Each pixel's residuals over its valid neighbours are reduced to their `quantile` (0: the
// smallest, the default: a static pixel needs one neighbour that agrees, so a vehicle passing
// over the road in some neighbours does not mask the road in this photo; a vehicle pixel must
// disagree with every neighbour). The pixel's probability of "not static" is then max over the
// cues of a logistic in residual / threshold (0.5 at the threshold, 0.05 at 0.4×, 0.95 at 1.6×);
// a pixel without depth (sky, or no reconstruction there) or seen by no neighbour has no
// evidence: probability 0.
// Regions: a uniform vehicle body agrees with a warp that shows the same paint elsewhere, and
// only its outline and windows disagree. So evidence is weighed by texture (the local mean luma
// gradient / `texture`, at most 1: a textureless pixel tells nothing) and spread over the
// target's regions (Felzenszwalb–Huttenlocher graph segmentation of the colour image, OpenCV
// ximgproc, k = `segments`): a region's probability is the texture-weighted mean of its pixels'
// when their weight sums to at least 5 % of its area, and each pixel with depth takes
// weight·own + (1 − weight)·region's. A pixel without depth takes its region's probability when
// more than `region_depth` of the region has depth (a vehicle's roof against the sky), else 0.
//
// Conventions: cameras are undistorted (PINHOLE), of the image's size; poses COLMAP's
// world-to-camera; luma float 0..1; depth float linear camera-space z, +inf/NaN/≤0 = none.
// Pixel centres at +0.5 (COLMAP). Lengths are relative (depth tolerance) or in pixels of the
// images given (slack, window): the caller picks the working resolution. Everything is invariant
// under similarity transforms of the world (`beyond` is a depth: the caller scales it with it).
// Thread safety: pure functions (OpenCV's thread pool inside).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "camera/camera.h"
#include "geometry/rigid.h"

namespace mvtm {

struct DynamicView {
  Camera camera;            // undistorted, of grey's and depth's size
  Rigid3d world_to_camera;  // pose of record
  cv::Mat grey;             // CV_32F luma 0..1
  cv::Mat depth;            // CV_32F linear z of the static reconstruction; inf/NaN/<=0: none
  cv::Mat colour;           // CV_8UC3 of the same size for the segmentation, or empty (luma)
  cv::Mat dynamic;          // CV_32F: this view's own probability from a first pass, or empty
  cv::Mat seen;       // CV_32F linear z of what this photo saw (densify's map: a parked vehicle
                      // included), or empty; as a neighbour or partner, a point farther than it is
                      // hidden in this view like one behind its static depth
  double beyond = 0;  // as a neighbour or partner: compared with the target's pixels whose
                      // static depth is at least this only (0: all)
  cv::Mat guessed;    // CV_8U, non-zero where the static depth is a guessed surface (a corridor
                      // wall closing a hole of the fused facades), or empty
};

struct DynamicOptions {
  double threshold = 0.05;          // photometric residual (luma 0..1) at which p = 0.5, > 0
  bool colour = true;               // the photometric residual over the colour channels
  double colour_threshold = 0.065;  // ... a channel's residual (0..1) at which p = 0.5, > 0
  bool flow = true;                 // also the flow residual
  double flow_threshold = 2.5;      // flow residual in pixels (DIS's noise is ~1 px) at p = 0.5
  double flow_relative = 0;         // ... or this share of the rigid motion, when larger, [0, 10)
  double quantile = 0;              // of the residuals over the neighbours, in [0, 1]; 0: min
  double depth_tolerance = 0.05;    // relative: occlusion test in the neighbour, in (0, 1)
  int slack = 1;                    // pixels of misalignment forgiven, 0..5
  int window = 5;                   // box averaging the photometric residual, odd, 1..31
  double segments = 300;            // Felzenszwalb's k for the regions evidence spreads over; 0 off
  double texture = 0.02;            // luma gradient (per pixel) at which a pixel's evidence is full
  double region_depth = 0.5;        // a pixel without depth takes its region's probability when
                                    // more than this share of the region has depth, [0, 1]; 1 never
  double partners_veto = 1;         // with partners and flow: where they agree with the target
                                    // (residual under this × threshold), the flow residual is
                                    // dropped (view-dependent light); 0 off, [0, 10]
  double ahead_veto = 0.5;          // with partners: the photos farther along veto the partners'
                                    // residual where theirs is under this × threshold; 0 off

  void Check() const;  // throws UsageError naming the option
};

struct DynamicEvidence {
  cv::Mat probability;  // CV_32F 0..1: "not static"
  cv::Mat photometric;  // CV_32F: the reduced photometric residual, NaN where no evidence
  cv::Mat flow;         // CV_32F: the reduced flow residual in pixels (empty when flow is off;
                        // NaN where the partners veto it, partners_veto)
  cv::Mat across;       // CV_32F: the photometric residual reduced over the partners (NaN where
                        // none saw the pixel; empty without partners)
  cv::Mat ahead_photo;  // CV_32F: the photometric residual reduced over the photos of the drive
                        // farther along the road (NaN where none saw it; empty without them,
                        // and when they veto the partners' evidence rather than being a cue)
  int neighbours = 0;   // neighbours that saw any of the target's pixels
  int partners = 0;     // partners that saw any of the target's pixels
  int ahead = 0;        // photos farther along that saw any of the target's pixels
};

// The target's evidence against `neighbours` (any number, even none: then all zero). Throws
// Error when a view's images are not of its camera's size or type, or a camera is distorted.
//
// Partners (optional) are photos of another drive of the same road, taken minutes or days
// apart: a vehicle parked in the target's drive is consistent across its own neighbours but not
// there in another drive. Their photometric residuals are computed as the neighbours' and
// reduced apart (the same quantile: a pixel must disagree with every partner), another cue of
// the probability. No flow against partners: another drive's light and lane (wet patches,
// shadows, a lateral baseline) make flow residuals there mostly false evidence (measured on
// mkroad: mean IoU 0.72 with it, 0.74 without). The reverse case (a vehicle parked in the partner's
// drive, on the road the target sees) must not mask the target's road: the partner's `seen` depth
// (what it photographed, the parked vehicle included) hides the road point behind it, so give
// partners their own depth maps where they exist. A pixel seen by no partner has no evidence from
// them.
//
// Where the partners agree with the target (their reduced residual under partners_veto ×
// threshold), the static point looked as it does now minutes or days later from another lane:
// the motion the target's own neighbours show there (the flow residual) is light that changes
// with the viewpoint, not something that moved: the sky mirrored in a shop window or on a wet
// road moves in the flow as a point far behind the surface would, just as a vehicle moving
// along the road does. The flow residual is dropped there (NaN); the photometric residual of the
// neighbours stays (dropping it too lost near vehicles whose paint is the road's on mkroad's
// 12-photo roads). "Agree" is the reduced residual (the smallest over the partners, at the
// default quantile): one partner that saw the point alike vetoes. A vehicle of this drive is not
// there in the other drive's photos, so they disagree with it and veto it only where its paint
// has the grey of the road they saw (by chance: about 12 % of the unit test's blocky car); a
// pixel no partner saw (NaN), or one a partner's first pass marked, is not vetoed.
//
// Photos farther along (optional, `ahead`) are photos of the target's own drive taken metres
// farther along the road, each with its `beyond` set: a vehicle keeping its distance ahead of
// the camera keeps its pixels in the neighbours, but a photo taken metres ahead sees the road it
// covers in the target below the vehicle's image in its own. Their photometric residuals are
// reduced apart (the same quantile), one more cue; no flow (metres apart, the near road's warp
// is too distorted). With partners too and `ahead_veto` > 0 they are not a cue but a veto: where
// one's residual is under ahead_veto × threshold, the target's own drive saw that static point
// as the target does, and what the partners disagree with there is their drive's own traffic (a
// vehicle keeping its place ahead of the other drive's camera, which that drive's own first pass
// cannot see move): the partners' residual is dropped there. A view behind the target (its
// centre at z <= 0 in the target's camera: the photos just behind a drive's last photo) vetoes
// only where its own pixel at the same place, unwarped, is not under that bound as well: a
// vehicle keeping the target camera's pace keeps its place in them, and its uniform panels agree
// with their warp moved a pixel or two. Give them their `seen` maps then: a
// vehicle parked in the target's drive hides from them the road its pixels warp to (its uniform
// paint would otherwise agree with itself, seen nearer and larger).
DynamicEvidence EstimateDynamic(const DynamicView& target,
                                const std::vector<const DynamicView*>& neighbours,
                                const DynamicOptions& options,
                                const std::vector<const DynamicView*>& partners = {},
                                const std::vector<const DynamicView*>& ahead = {});

// Vehicles, cyclists and pedestrians stand on the road; mistakes of a photo-built mesh (tree
// canopies, facade edges, poles) float above it. Sets to 0 the probability of every blob (8-
// connected pixels at or above `at`) whose foot does not touch the ground: the static 3-D points
// of the pixels just below its lowest pixel in each column, taken along `up` (unit, world), must
// include one within `tolerance` × the camera's height above the ground of the ground's height.
// The ground's height under this camera is the median height along `up` of the static points
// seen in the lower middle of the image (its lowest fifth, middle half: the road ahead); without
// such points, nothing is removed. A blob whose foot is out of the image or has no depth is kept.
// Returns the number of blobs removed.
int KeepGrounded(const DynamicView& target, const Eigen::Vector3d& up, double at, double tolerance,
                 cv::Mat& probability);

struct MaskOptions {
  double probability = 0.4;  // pixels at or above are "not static", in (0, 1)
  int open = 1;              // radius of the opening that removes specks (pixels), 0..50
  double close = 0.02;       // radius of the closing that joins a vehicle's parts, in image
                             // widths (rounded to pixels), [0, 0.2]
  double min_area = 2e-4;    // blobs smaller than this share of the image are dropped, [0, 1)

  void Check() const;
};

// Binary mask (CV_8U, 255 = not static) from a probability map: threshold, opening, closing,
// holes filled (a region enclosed by the mask is the vehicle's body), small blobs dropped.
cv::Mat MaskFromProbability(const cv::Mat& probability, const MaskOptions& options);

// What stays "not static" only where something stands on the road and the photo's own depth
// does not show the static surface:
//  * explained pixels: where `target.seen` (densify's depth of this very photo, from stereo with
//    its neighbours) is the static depth within `seen_tolerance` (relative), the photo saw the
//    static surface: probability 0. A vehicle's pixels have no consistent depth or a wrong one
//    (moving: its motion read as parallax) or a nearer one (parked in this drive only: a mesh
//    fused without it). Pixel by pixel, so a vehicle merged with a patch of road keeps its
//    body. Without `seen`, nothing is cleared.
//  * lying blobs: then the blobs of the mask `mask` makes of the probability (a vehicle whole,
//    its outline's evidence closed and filled) that lie in the road rather than stand on it go
//    too: in no column does the blob's highest pixel reach `min_height` × the camera's height
//    above the ground at its foot. The foot is the static point of the column's lowest blob
//    pixel (or of the one below it, when that has no depth); the top, the column's highest blob
//    pixel's ray where it passes the foot's distance from the camera (across `up`). Vehicles,
//    cyclists and pedestrians stand a good share of a camera's height (a car 1.45 m, a dashcam
//    1.2-1.7 m high); a wet patch, a shadow or a stain of the road flickers in the photos but
//    lies flat: its top reaches (far - near) / far of the camera's height, its near and far
//    edges' distances (a patch 10 to 20 m ahead: half). `up` is normalised here. The camera's
//    height is KeepGrounded's (the static points of the image's lower middle); without them no
//    blob is judged, and a blob without a column whose foot has depth is kept.
//  * blobs on the static surface: a vehicle, a cyclist, a pedestrian stands in front of the
//    static surface and hides what lies behind it: above its middle, the static depth of its
//    pixels is well beyond its foot's (the road behind a car, the facade across the street, the
//    sky). A blob whose upper pixels' static depth is its foot's (a door, a shop front, a stretch
//    of facade whose mesh is wrong, the photo's border where few neighbours see it) stands for
//    nothing in front of the surface: it goes when under `occludes` of its upper pixels (in each
//    column, those above the middle between its top and lowest pixel) have a static depth over
//    (1 + `occlusion_gap`) × the foot's (the column's lowest pixel's or the one below's), or
//    none. Needs no ground; a blob without a column whose foot has depth is kept.
//  * blobs on a guessed surface: where `target.guessed` marks the static depth as a guess (a
//    corridor wall that roadmesh --dense puts behind a hole of the fused facades: an alley, a gap
//    between buildings, a near corner no second photo saw), a neighbour warped through it
//    disagrees with the photo by the parallax of the guess although nothing moved. In a blob
//    more than `max_guessed` of whose pixels are there, those pixels get probability 0 (before
//    the two tests above, which then judge what is left: a vehicle merged with such a blob keeps
//    its body on the road). A vehicle stands on the road, which is measured or the corridor's
//    ground (not a guess of this kind), and hides a wall's hole with its upper part only.
//    Without `guessed`, nothing is cleared.
// seen_tolerance 0, min_height 0, occludes 0 or max_guessed 1 turns a test off.
struct BlobTestOptions {
  double min_height = 0.5;       // × the camera's height above the ground, >= 0; 0 off
  double seen_tolerance = 0.05;  // relative, in [0, 1); 0 off
  double occludes = 0.2;         // share of a blob's upper pixels, in [0, 1]; 0 off
  double occlusion_gap = 0.25;   // relative depth beyond the foot that counts as behind, > 0
  double max_guessed = 0.5;      // share of a blob's pixels on guessed depth, [0, 1]; 1 off
};
struct BlobTestCounts {
  size_t explained = 0;  // pixels at or above mask.probability cleared: the seen static surface
  int lying = 0;         // blobs left out: flat in the road
  int surface = 0;       // blobs left out: on the static surface, hiding nothing behind them
  int guessed = 0;       // blobs cleared where the static depth is a guess (mostly there)
};
BlobTestCounts KeepStandingUnexplained(const DynamicView& target, const Eigen::Vector3d& up,
                                       const MaskOptions& mask, const BlobTestOptions& options,
                                       cv::Mat& probability);

// Completes each blob of the mask `mask` makes of the probability with GrabCut (Rother et al.
// 2004, "GrabCut": OpenCV's grabCut on `t.colour`) seeded by it. The evidence finds the parts of
// a vehicle, a cyclist or a pedestrian that move against the static surface behind them; the
// parts seen against the far background (a cyclist's body, moving with the camera) or against
// surfaces of their own colour show none. In the blob's box widened by half its width on each
// side and by its height upwards, the box's border and every pixel the photo's own depth explains
// (`t.seen` within `tolerance` of the static depth: the photo saw the static surface there, so
// nothing stood in front of it; without this, a car's colour model leaks into a facade of its
// colour) are sure background, the rest probable background, except the blob's own pixels:
// probable foreground, its core (eroded by 2 pixels) sure. The foreground connected to the blob is
// added (probability raised to mask.probability) unless it adds more than max_grow × the blob's
// area. Returns the number of blobs grown. Without `t.colour` or `t.seen`, or with max_grow 0,
// nothing changes. Throws Error on options out of range or a probability not float of the depth's
// size.
struct BlobCompletion {
  double max_grow = 3;      // largest growth, × the blob's area, >= 0; 0 off
  double tolerance = 0.05;  // relative, in (0, 1): explained pixels are sure background
  int iterations = 3;       // GrabCut's, >= 1
};
int CompleteBlobs(const DynamicView& target, const MaskOptions& mask, const BlobCompletion& options,
                  cv::Mat& probability);

// Where a car drove, nothing static stands: the space a drive's camera passed through, the width
// of a lane around its path and up to about the car's height above the road, was empty when it
// passed. A static surface there (one the photo saw and the static reconstruction agrees with:
// several photos saw it in one place) is a vehicle, a cyclist or a pedestrian that stood still
// long enough to be fused, and was gone when the car passed (or came after it): a car parked in
// a lane another drive took, a vehicle waiting ahead. Such a vehicle is as consistent as the
// road in the photos of one drive; its place, not its appearance, gives it away.
// A path is the camera centres of one drive in the order it took them (a drive registered in
// two pieces is two paths: the caller breaks it, so that it does not sweep across what lies
// between; centres repeated where the car stood are taken once) and the camera's height above
// the road (model units, > 0; a path without one is skipped): the road under the path is that
// far below its centres along `up`, whatever the grade. Every pixel whose seen point
// (`target.seen`, densify's map) is the static one (depth within `agree` of `target.depth`,
// relative: a lone photo's stereo mistake, such as a wet patch's reflection read as a surface,
// is not in the fused mesh) and lies, for some stretch of some path, within `half_width` × that
// path's camera height of it (measured across `up`), beside it (not beyond the path's first or
// last centre) and between `above` and `below` × that height above the road under it there,
// gets probability 1, after the marked pixels are opened (radius `open`) and their blobs under
// `min_area` of the image dropped, as the masks' are. With `grow`, the static surface
// (`target.depth`, the mesh) in that space, 8-connected to a marked blob, is marked too: the
// rest of the vehicle, where the photo's depth has none (a dark body, a window) or another.
// Without `target.seen` nothing is marked.
// Returns the number of pixels raised. Throws Error on options out of range or a probability
// not float of the depth's size.
struct DrivenSpace {
  double half_width = 1.0;  // × the camera's height, > 0: a lane's half-width for a dashcam
  double above = 0.15;      // × the camera's height above the road, >= 0: not kerbs, bumps
  double below = 1.2;       // × the camera's height, > above: a car's roof, not branches over it
  double agree = 0.1;       // seen depth within this of the static depth, relative, (0, 1)
  int open = 1;             // the marked pixels' opening radius (pixels), >= 0
  double min_area = 2e-4;   // ... and their blobs under this share of the image go, [0, 1)
  bool grow = true;         // the mesh's surface in the space joined to a marked blob: marked
};
struct DrivenPath {
  std::vector<Eigen::Vector3d> centres;  // world, in the order the drive took them
  double height = 0;                     // the camera's height above the road, model units
};
size_t MarkDriven(const DynamicView& target, const std::vector<DrivenPath>& paths,
                  const Eigen::Vector3d& up, const DrivenSpace& options, cv::Mat& probability);

}  // namespace mvtm
