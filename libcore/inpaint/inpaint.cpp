#include "inpaint/inpaint.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "base/error.h"
#include "image/mask.h"

namespace mvtm {

namespace {

// Colour channels of an image: alpha (2 or 4 channels) is never touched.
int ColourChannels(const Image& im) {
  return im.channels == 2 || im.channels == 4 ? im.channels - 1 : im.channels;
}

// Factor from the 8-bit scale (0..255) to the image's own scale.
float ScaleFrom255(const Image& im) {
  return im.bits == 32 ? 1.f / 255.f : float(im.MaxValue() / 255.0);
}

// A pixel as RGB on the 8-bit scale (grey replicated).
std::array<float, 3> Rgb255(const Image& im, int x, int y) {
  const float s = 1.f / ScaleFrom255(im);
  if (ColourChannels(im) >= 3) return {im.at(x, y, 0) * s, im.at(x, y, 1) * s, im.at(x, y, 2) * s};
  float g = im.at(x, y, 0) * s;
  return {g, g, g};
}

// Stores an 8-bit-scale RGB value into the image's colour channels (grey = mean), at its depth.
void PutRgb255(Image& im, int x, int y, const std::array<float, 3>& rgb) {
  const float s = ScaleFrom255(im);
  auto conv = [&](float v) { return im.bits == 32 ? v * s : std::nearbyint(v * s); };
  if (ColourChannels(im) >= 3)
    for (int c = 0; c < 3; ++c) im.at(x, y, c) = conv(rgb[size_t(c)]);
  else
    im.at(x, y, 0) = conv((rgb[0] + rgb[1] + rgb[2]) / 3.f);
}

// The mask (image/mask.h: any channel non-zero) as CV_8U 0/255.
cv::Mat CvMask(const Image& m) {
  const Image set = MaskFromImage(m);
  cv::Mat b(m.height, m.width, CV_8U, cv::Scalar(0));
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) b.at<uint8_t>(y, x) = static_cast<uint8_t>(set.at(x, y));
  return b;
}

// The image unchanged, provenance all original, `masked` pixels counted.
Inpainted Start(const Image& image, size_t masked) {
  Inpainted r{image, Image(image.width, image.height, 1, 8, kProvenanceOriginal), {}};
  r.counts.masked = masked;
  return r;
}

// One colour channel (or all colour channels of an 8-bit RGB image) as an OpenCV matrix.
cv::Mat ToMat(const Image& im, int c0, int nc, int depth) {
  cv::Mat m(im.height, im.width, CV_MAKETYPE(depth, nc));
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      for (int c = 0; c < nc; ++c) {
        float v = im.at(x, y, c0 + c);
        if (depth == CV_8U)
          m.ptr<uint8_t>(y)[x * nc + c] = cv::saturate_cast<uint8_t>(v);
        else if (depth == CV_16U)
          m.ptr<uint16_t>(y)[x * nc + c] = cv::saturate_cast<uint16_t>(v);
        else
          m.ptr<float>(y)[x * nc + c] = v;
      }
  return m;
}

// OpenCV's inpainting of the pixels set in `mask` (CV_8U), channel by channel unless the image
// is 8-bit RGB (which cv::inpaint takes whole); they are marked kProvenance2d.
void FillOpenCv(Inpainted& r, const cv::Mat& mask, double radius, int flag) {
  Image& out = r.image;
  const int cc = ColourChannels(out);
  const int depth = out.bits == 8 ? CV_8U : out.bits == 16 ? CV_16U : CV_32F;
  const bool whole = out.bits == 8 && cc == 3;
  for (int c0 = 0; c0 < cc; c0 += whole ? 3 : 1) {
    const int nc = whole ? 3 : 1;
    cv::Mat src = ToMat(out, c0, nc, depth), dst;
    cv::inpaint(src, mask, dst, radius, flag);
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) {
        if (!mask.at<uint8_t>(y, x)) continue;
        for (int c = 0; c < nc; ++c)
          out.at(x, y, c0 + c) = depth == CV_8U    ? float(dst.ptr<uint8_t>(y)[x * nc + c])
                                 : depth == CV_16U ? float(dst.ptr<uint16_t>(y)[x * nc + c])
                                                   : dst.ptr<float>(y)[x * nc + c];
      }
  }
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      if (mask.at<uint8_t>(y, x)) r.provenance.at(x, y) = kProvenance2d, ++r.counts.two_d;
}

// Grey float (8-bit scale) for template matching.
cv::Mat GreyMat(const Image& im) {
  cv::Mat m(im.height, im.width, CV_32F);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      auto p = Rgb255(im, x, y);
      m.at<float>(y, x) = (p[0] + p[1] + p[2]) / 3.f;
    }
  return m;
}

struct Match {
  double score = INFINITY;  // mean squared difference per template pixel
  cv::Point offset;         // partner pixel = image pixel + offset
  size_t partner = 0;
};

// Thesis §5.2: templates left of, right of, above and below the blob's bounding box, matched in
// the partner by squared difference; the best one over all templates wins.
Match MatchBlob(const cv::Mat& grey, const cv::Rect& box, const cv::Mat& partner,
                size_t partner_rank) {
  Match best;
  const int t = std::clamp(std::max(box.width, box.height) / 3, 4, 32);
  const cv::Rect all(0, 0, grey.cols, grey.rows);
  const cv::Rect tmpl[4] = {{box.x - t, box.y, t, box.height},
                            {box.x + box.width, box.y, t, box.height},
                            {box.x, box.y - t, box.width, t},
                            {box.x, box.y + box.height, box.width, t}};
  for (const cv::Rect& r0 : tmpl) {
    cv::Rect r = r0 & all;
    if (r.width < 2 || r.height < 2 || r.width > partner.cols || r.height > partner.rows) continue;
    cv::Mat res;
    cv::matchTemplate(partner, grey(r), res, cv::TM_SQDIFF);
    double mn;
    cv::Point loc;
    cv::minMaxLoc(res, &mn, nullptr, &loc, nullptr);
    double score = mn / double(r.area());
    if (score < best.score) best = {score, loc - r.tl(), partner_rank};
  }
  return best;
}

// Copies each blob of `mask` from the partner and offset its templates match best; blobs no
// template fits are left alone (provenance stays original).
void CopyBestMatches(Inpainted& r, const cv::Mat& mask, const std::vector<const Image*>& partners) {
  cv::Mat labels, stats, centroids;
  int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  cv::Mat grey = GreyMat(r.image);
  std::vector<cv::Mat> pgrey;
  for (const Image* p : partners) pgrey.push_back(GreyMat(*p));
  for (int b = 1; b < n; ++b) {
    cv::Rect box(stats.at<int>(b, cv::CC_STAT_LEFT), stats.at<int>(b, cv::CC_STAT_TOP),
                 stats.at<int>(b, cv::CC_STAT_WIDTH), stats.at<int>(b, cv::CC_STAT_HEIGHT));
    Match best;
    for (size_t k = 0; k < partners.size(); ++k) {
      Match m = MatchBlob(grey, box, pgrey[k], k);
      if (m.score < best.score) best = m;
    }
    if (!std::isfinite(best.score)) continue;  // no template fits
    const Image& pimg = *partners[best.partner];
    for (int y = box.y; y < box.y + box.height; ++y)
      for (int x = box.x; x < box.x + box.width; ++x) {
        if (labels.at<int>(y, x) != b) continue;
        int px = std::clamp(x + best.offset.x, 0, pimg.width - 1),
            py = std::clamp(y + best.offset.y, 0, pimg.height - 1);
        PutRgb255(r.image, x, y, Rgb255(pimg, px, py));
        r.provenance.at(x, y) = uint8_t(best.partner + 1);
        ++r.counts.partners;
      }
  }
}

// The provenance of a masked pixel the renderer filled: `source` is the frame's (projector rank,
// kSourceVertex, kSourceBackground), `surface` whether the image's own view sees the mesh there.
uint8_t MeshProvenance(uint8_t source, bool surface, InpaintCounts& counts) {
  if (source == kSourceBackground) {
    ++counts.background;
    return kProvenanceBackground;
  }
  if (source == kSourceVertex) {
    ++counts.vertex;
    return kProvenanceVertex;
  }
  if (!surface) {
    ++counts.sky;
    return uint8_t(kProvenanceSkyOffset + source + 1);
  }
  ++counts.partners;
  return uint8_t(source + 1);
}

}  // namespace

Image DilateMask(const Image& mask, int radius) {
  cv::Mat m = CvMask(mask);
  if (radius > 0)
    cv::dilate(
        m, m,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1)));
  Image out(mask.width, mask.height, 1, 8);
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x) out.at(x, y) = m.at<uint8_t>(y, x);
  return out;
}

void CheckMaskSize(const Image& image, const Image& mask, const std::string& where) {
  if (mask.width != image.width || mask.height != image.height)
    throw Error(where, 0,
                "mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) +
                    ", image is " + std::to_string(image.width) + "x" +
                    std::to_string(image.height));
}

void CheckViewSize(const Image& image, const View& view, const std::string& where) {
  const Camera& cam = view.camera;
  if (int(cam.width) != image.width || int(cam.height) != image.height)
    throw Error(where, 0,
                "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", its camera " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
}

Inpainted InpaintOpenCv(const Image& image, const Image& mask, OpenCvInpaintMethod method,
                        double radius) {
  CheckMaskSize(image, mask);
  const cv::Mat m = CvMask(mask);
  Inpainted r = Start(image, size_t(cv::countNonZero(m)));
  if (r.counts.masked)
    FillOpenCv(r, m, radius,
               method == OpenCvInpaintMethod::kNs ? cv::INPAINT_NS : cv::INPAINT_TELEA);
  return r;
}

Inpainted InpaintPatch2d(const Image& image, const Image& mask,
                         const std::vector<const Image*>& partners, double radius) {
  if (partners.empty()) return InpaintOpenCv(image, mask, OpenCvInpaintMethod::kTelea, radius);
  CheckMaskSize(image, mask);
  const cv::Mat m = CvMask(mask);
  Inpainted r = Start(image, size_t(cv::countNonZero(m)));
  if (!r.counts.masked) return r;
  CopyBestMatches(r, m, partners);
  // Blobs no template could be placed for.
  cv::Mat rest = m.clone();
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (r.provenance.at(x, y) != kProvenanceOriginal) rest.at<uint8_t>(y, x) = 0;
  if (cv::countNonZero(rest)) FillOpenCv(r, rest, radius, cv::INPAINT_TELEA);
  return r;
}

Inpainted InpaintThroughMesh(Renderer& renderer, const View& view, const Image& image,
                             const Image& mask, const std::vector<Projector>& partners,
                             double bias) {
  CheckMaskSize(image, mask);
  CheckViewSize(image, view);
  const Image set = MaskFromImage(mask);
  Inpainted r = Start(image, CountSet(set));
  if (!r.counts.masked) return r;
  EffectsPlan plan;
  plan.ptm = true;
  plan.projectors = std::max<int>(1, int(partners.size()));
  plan.occlusion = plan.masks = plan.skybox = true;
  plan.bias = bias;
  Renderer::Frame f = renderer.Render(view, partners, plan);
  Image own_depth = renderer.RenderDepth(view);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      if (!set.at(x, y)) continue;
      PutRgb255(r.image, x, y, {f.colour.at(x, y, 0), f.colour.at(x, y, 1), f.colour.at(x, y, 2)});
      r.provenance.at(x, y) =
          MeshProvenance(uint8_t(f.source.at(x, y)), std::isfinite(own_depth.at(x, y)), r.counts);
    }
  return r;
}

}  // namespace mvtm
