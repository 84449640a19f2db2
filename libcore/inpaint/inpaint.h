// mvtm — inpainting: the masked pixels of an image replaced from elsewhere (thesis §5.2, §5.3).
//
// Methods, each a function of in-memory images (the 3-D one also of a Renderer):
//   InpaintThroughMesh  thesis §5.3, Eq. 5.3, Alg. 4–5: the mesh rendered from the image's own
//                       view, textured by partner images (projectors, rank order) with their
//                       masks respected and the occlusion test on; where no partner reaches,
//                       vertex colours; where the image's own view sees no surface, the sky
//                       (skybox from the partners), else the constant background (black).
//   InpaintOpenCv       OpenCV cv::inpaint, Telea or Navier–Stokes, radius in pixels. OpenCV's
//                       Telea adds its gradient term (in [−√2, √2]) and 0.5 in sample units, so
//                       a constant region comes back within ±2 on 8 and 16 bits, and float
//                       images (0..1) get offsets of that size: use ns or 3d for them.
//   InpaintPatch2d      thesis §5.2: for each blob (8-connected component of the mask) four
//                       templates (strips left of, right of, above and below its bounding box,
//                       each max(w, h)/3 clamped to 4..32 pixels thick) are matched in each
//                       partner by squared difference on grey (cv::matchTemplate TM_SQDIFF); the
//                       template and partner with the least mean squared difference per pixel
//                       give an offset, and the blob's pixels are copied from that partner at
//                       that offset (clamped to its border). Blobs no template fits, and every
//                       blob when there is no partner: Telea.
// Conventions:
//  * Images are image/image.h Images of any size, 1–4 channels, 8 or 16 bits or float. Only
//    colour channels are written; alpha (2 or 4 channels) keeps its values, and every pixel
//    outside the mask keeps its exact value. Colours move between images on the 8-bit scale
//    (0..255: ×257 for 16 bits, ÷255 for float, integers rounded to nearest); a grey image takes
//    the mean of RGB, RGB from a grey image replicates it. Telea/NS work on 8-bit RGB whole,
//    on everything else channel by channel (16 bits and float at their own depth).
//  * Masks follow image/mask.h: a pixel is set when any channel is non-zero. A mask must have
//    the image's size (Error otherwise). An empty mask returns the image unchanged. Callers
//    dilate with DilateMask first when they want a margin.
//  * Provenance: one 8-bit channel per pixel, the kProvenance* values below.
//  * Partners are in rank order: rank r (0-based) is recorded as provenance r + 1.
//  * Errors are thrown (Error from base/error.h); nothing is printed.
// Thread safety: InpaintOpenCv, InpaintPatch2d, DilateMask and the checks are reentrant;
// InpaintThroughMesh uses the Renderer, which belongs to the thread holding the GL context.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"
#include "render/renderer.h"

namespace mvtm {

// Provenance image values.
inline constexpr uint8_t kProvenanceOriginal = 0;  // outside the mask: the recorded pixel
// 1..16: partner of rank r projected onto the mesh (3d) or copied (patch2d)
inline constexpr uint8_t kProvenanceSkyOffset = 100;   // 101..116: sky from partner of rank r (3d)
inline constexpr uint8_t kProvenance2d = 253;          // telea / ns (and patch2d's fallback)
inline constexpr uint8_t kProvenanceVertex = 254;      // vertex colour (3d)
inline constexpr uint8_t kProvenanceBackground = 255;  // constant background (3d)

// Pixels of one image by where they came from.
struct InpaintCounts {
  size_t masked = 0;      // pixels under the mask
  size_t partners = 0;    // kProvenance 1..16
  size_t sky = 0;         // kProvenanceSkyOffset + 1..16
  size_t vertex = 0;      // kProvenanceVertex
  size_t background = 0;  // kProvenanceBackground
  size_t two_d = 0;       // kProvenance2d
};

struct Inpainted {
  Image image;       // the input with the masked pixels replaced; same size, channels and bits
  Image provenance;  // 1 channel, 8 bits, same size: kProvenance* per pixel
  InpaintCounts counts;
};

enum class OpenCvInpaintMethod { kTelea, kNs };

// The mask (image/mask.h rule) dilated by a disk of `radius` pixels (OpenCV's elliptical
// structuring element of size 2·radius + 1); 1 channel, 0 or 255. radius 0: not dilated.
Image DilateMask(const Image& mask, int radius);

// Throw Error(where, 0, "mask is WxH, image is WxH") / Error(where, 0, "image is WxH, its camera
// WxH") when the sizes differ; `where` names the mask / image file in the message ("" = none).
void CheckMaskSize(const Image& image, const Image& mask, const std::string& where = "");
void CheckViewSize(const Image& image, const View& view, const std::string& where = "");

// OpenCV inpainting of the masked pixels, `radius` pixels around each considered.
Inpainted InpaintOpenCv(const Image& image, const Image& mask, OpenCvInpaintMethod method,
                        double radius);

// Thesis §5.2 templates; `partners` in rank order (any sizes); `radius` for the Telea fallback.
Inpainted InpaintPatch2d(const Image& image, const Image& mask,
                         const std::vector<const Image*>& partners, double radius);

// Thesis §5.3: `view` is the image's own (its camera must have the image's size), `partners`
// the projectors in rank order (at most 16; depth maps required, masks optional), `bias` the
// relative occlusion bias (EffectsPlan::bias). Renders with PTM, occlusion, masks and skybox on
// and max(1, partners) projectors.
Inpainted InpaintThroughMesh(Renderer& renderer, const View& view, const Image& image,
                             const Image& mask, const std::vector<Projector>& partners,
                             double bias);

}  // namespace mvtm
