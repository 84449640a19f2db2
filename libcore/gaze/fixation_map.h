// mvtm — fixations onto the road and back (thesis App. B.1): for each I-VT fixation (gaze/ivt.h)
// the frame on screen at its middle, the 3-D point on the mesh under it and the source
// photographs that see that point (gaze/mapping.h), then its area of interest (gaze/aoi.h).
//
//  * Frame: the one on screen (FrameClock::FrameAt) at (start + end) / 2; the ray is the render
//    camera's through the fixation's screen position (ScreenRay) at that frame's pose; its
//    closest hit on the mesh is X, `distance` the ray origin's distance to X; sources: SourcesOf.
//  * AOI, in this order: "no-surface" when the ray hit nothing; with boxes, the first box
//    containing X (BoxContaining) or "outside"; else with label images, the CamVid class
//    (CamVidClassName) at the fixation's pixel (floor(u), floor(v)) in the nearest of its source
//    photos (smallest depth, ties by view order) that has a label image, or "unknown" when none
//    has; else "surface".
// Thread safety: functions are reentrant; MeshRaycaster is used through its const interface.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "gaze/aoi.h"
#include "gaze/ivt.h"
#include "gaze/mapping.h"
#include "geometry/rigid.h"
#include "image/image.h"
#include "raycast/mesh_raycaster.h"

namespace mvtm {

struct MappedFixation {
  Fixation fixation;
  size_t frame = 0;  // the frame on screen at the fixation's middle
  bool hit = false;  // its ray hit the mesh
  Eigen::Vector3d X = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double distance = std::numeric_limits<double>::quiet_NaN();  // ray origin to X
  std::vector<SourceHit> sources;                              // the views that see X
  std::string aoi;                                             // set by AssignAois
};

// The frames shown: frame i on screen by `clock`, rendered by `render` at world-to-camera pose
// w2c[i], shown full screen at screen.width_px × screen.height_px.
struct ShownFrames {
  const FrameClock& clock;
  const std::vector<Rigid3d>& w2c;
  const Camera& render;
  const ScreenGeometry& screen;
};

// One MappedFixation per fixation, in order (aoi left empty). Throws Error when a fixation's
// middle is outside the frames' display times or the clock and poses differ in length.
std::vector<MappedFixation> MapFixations(const std::vector<Fixation>& fixations,
                                         const ShownFrames& frames, const MeshRaycaster& mesh,
                                         const std::vector<SourceView>& views,
                                         const DepthLookup& depth,
                                         const VisibilityOptions& options);

// The label image of view i (CamVid class ids, the view's size), or nullptr when it has none.
using LabelLookup = std::function<const Image*(size_t view)>;

// Sets every fixation's aoi (see above). `boxes` empty: no boxes; `labels` empty: no label images.
void AssignAois(std::vector<MappedFixation>& mapped, const std::vector<AoiBox>& boxes,
                const LabelLookup& labels);

}  // namespace mvtm
