// ptmrender — headless projective texture mapping of any trajectory (thesis Alg. 1–5).
#pragma once

#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include "cli/work.h"
#include "index/view_selection.h"
#include "render/context.h"
#include "render/renderer.h"
#include "run/option_table.h"

namespace mvtm {

// --mode: project photographs, or vertex colours only.
enum class PtmMode { kPtm, kVertex };
inline const std::vector<std::pair<PtmMode, std::string>> kPtmModes = {
    {PtmMode::kPtm, "ptm"}, {PtmMode::kVertex, "vertex"}};

// --render-exposure: the exposure the rendered camera records at (with exposure.tsv).
enum class RenderExposure { kNearest, kCommon };
inline const std::vector<std::pair<RenderExposure, std::string>> kRenderExposures = {
    {RenderExposure::kNearest, "nearest"}, {RenderExposure::kCommon, "common"}};

// Work items: the render poses in order (--frames/--shard select among them).
struct PtmRenderOptions : WorkOptions {
  std::string workspace, outdir;
  std::string poses;          // trajectory file (COLMAP images.txt, TUM, KITTI); else --at-images
  bool at_images = false;     // render at the workspace's own poses
  bool exclude_self = false;  // never project an image onto its own pose
  double lateral = 0;         // metres to the camera's left (+) or right (−): a lane change
  double yaw = 0;             // degrees, turn left (+) or right (−) about the camera's up axis
  PtmMode mode = PtmMode::kPtm;
  int projectors = 4;   // K: projectors tried per pixel, nearest first
  double bias = 0.005;  // relative occlusion bias
  bool no_occlusion = false, no_skybox = false, no_masks = false;
  bool no_exposure = false;  // ignore exposure.tsv (projectors at their own exposures)
  bool no_blend = false;     // the first projector that sees a point, not a weighted blend
  bool no_fill = false;      // constant background where nothing is seen, not push-pull
  double sky_distance = -1;  // skybox distance, model units (< 0: the scene's far end, 0: infinity)
  BlendWeights blend;        // --blend-power, --feather, --res-weight, --soft
  bool no_seen = false;      // never take what the projectors saw in front of the mesh
  SeenSurfaces seen;         // --seen-front, --seen-reach, --seen-projectors
  RenderExposure render_exposure = RenderExposure::kNearest;
  std::string size;         // WxH render size (default: the camera's)
  bool explain = false;     // print the effects plan as JSON and render nothing
  bool provenance = false;  // also write OUTDIR/provenance/NAME.png (source of each pixel)
  bool exr = false;         // write float EXR instead of PNG
  ViewSelectionOptions selection;
  GlBackend gl = GlBackend::kAuto;

  void Check() const;
};

// The option table (run/option_table.h), bound to `o`: --help, checks, provenance and the
// staleness key of the frames all come from it.
OptionTable DeclareOptions(PtmRenderOptions& o);

// Times are totals over the run's frames, in milliseconds.
struct PtmRenderReport {
  size_t frames = 0, rendered = 0, skipped = 0;
  double render_ms = 0;    // Renderer::Render: uploads, draw, readback
  double draw_ms = 0;      // ... of which the mesh pass (RenderStats::draw_ms)
  double shade_ms = 0;     // ... of which the texturing pass (RenderStats::shade_ms)
  double readback_ms = 0;  // ... of which reading the frame back from GL
  double fill_ms = 0;      // ... of which the push-pull fill (RenderStats::fill_ms)
  double depth_ms = 0;     // survey_ms + gathering depth maps (also in load_ms)
  double survey_ms = 0;    // the plan's depth passes (holes, coverage)
  double load_ms = 0;      // gathering each frame's projector images, masks and depth maps
  double write_ms = 0;     // waiting for the writer thread (encoding overlaps rendering)
  double frames_ms = 0;    // wall time from the plan's survey to the last frame written
  std::string gl;
  std::string why;  // why frames were (re)made: "2 new, 6 redone: --lateral changed"
};

// Renders (or with explain, prints the plan to `out`). Throws Error / UsageError.
PtmRenderReport RunPtmRender(const PtmRenderOptions& options, std::ostream& out);

}  // namespace mvtm
