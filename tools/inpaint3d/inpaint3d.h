// inpaint3d — removes masked (moving) objects from a workspace's images (thesis §5.3, Eq. 5.3,
// Alg. 4–5), with the 2-D baselines of §5.2 for comparison.
//
// For every image whose mask (masks/NAME.png) has a non-zero pixel, the pixels under the mask
// (dilated by `dilate` pixels) are replaced; every other pixel keeps its bytes. The methods are
// libcore/inpaint's (inpaint/inpaint.h):
//   3d       InpaintThroughMesh: the mesh rendered from the image's own pose, textured by its
//            partner images (partners.tsv, pickview --partners) with their own masks respected
//            and the occlusion test on; where no partner reaches, vertex colours; where the mesh
//            has no surface, the skybox (sky projected from the partners), else a constant
//            background.
//   telea    InpaintOpenCv: OpenCV cv::inpaint, INPAINT_TELEA, radius `radius`.
//   ns       InpaintOpenCv: OpenCV cv::inpaint, INPAINT_NS (Navier–Stokes), radius `radius`.
//   patch2d  InpaintPatch2d: thesis §5.2, templates around each blob matched in the partner
//            images, the blob copied from the best match. No partner: Telea.
// Inputs are always the recorded images (images/NAME), never textures/. Outputs, each written
// atomically and skipped when up to date (run/ledger.h: same options, unchanged inputs) unless
// `force`:
//   textures/NAME                          the image, same format, channel count and bit depth;
//                                          an image with no mask (or an empty one) is copied
//                                          byte for byte
//   textures/provenance/STEM.png           8-bit, where each pixel came from (kProvenance*)
// Images are processed in name order; --frames/--shard select among them (cli/selection.h).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cli/work.h"
#include "inpaint/inpaint.h"  // kProvenance* values
#include "render/context.h"
#include "run/option_table.h"

namespace mvtm {

// --method: partners through the mesh, OpenCV's Telea or Navier-Stokes, or thesis 5.2 templates.
enum class InpaintMethod { k3d, kTelea, kNs, kPatch2d };
inline const std::vector<std::pair<InpaintMethod, std::string>> kInpaintMethods = {
    {InpaintMethod::k3d, "3d"},
    {InpaintMethod::kTelea, "telea"},
    {InpaintMethod::kNs, "ns"},
    {InpaintMethod::kPatch2d, "patch2d"}};

struct Inpaint3dOptions : WorkOptions {
  std::string workspace;  // WS
  InpaintMethod method = InpaintMethod::k3d;
  int partners = 4;                 // partners used per image (ranks 1..N of partners.tsv), 1..16
  int dilate = 1;                   // pixels the mask is dilated by before inpainting, 0..64
  double radius = 3;                // telea/ns: inpainting radius in pixels, > 0
  double bias = 0.005;              // 3d: relative occlusion bias, [0, 1)
  GlBackend gl = GlBackend::kAuto;  // 3d: OpenGL backend

  void Check() const;  // throws UsageError naming the bad value
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of the outputs all come from it.
OptionTable DeclareOptions(Inpaint3dOptions& o);

struct Inpaint3dReport {
  size_t images = 0;     // selected
  size_t inpainted = 0;  // masked images written
  size_t copied = 0;     // unmasked images copied
  size_t skipped = 0;    // up to date
  size_t masked_pixels = 0, from_partners = 0, from_sky = 0, from_vertex = 0, from_background = 0,
         from_2d = 0;
  double ms = 0;  // total processing time of written images
  std::string gl;
  std::string why;  // why outputs were remade ("4 redone: --dilate changed"), "" when none was
};

// Runs the tool. Throws Error (data) / UsageError (options).
Inpaint3dReport RunInpaint3d(const Inpaint3dOptions& options);

}  // namespace mvtm
