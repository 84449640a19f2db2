#include "inpaint3d.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "base/atomic_file.h"
#include "cli/progress.h"
#include "base/error.h"
#include "cli/selection.h"
#include "base/text.h"
#include "image/mask.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "render/context.h"
#include "render/projector_sources.h"
#include "render/renderer.h"
#include "workspace/workspace.h"

namespace mvtm {

void Inpaint3dOptions::Check() const {
  if (partners < 1 || partners > 16)
    throw UsageError("--partners: " + std::to_string(partners) + " is not in 1..16");
  if (dilate < 0 || dilate > 64)
    throw UsageError("--dilate: " + std::to_string(dilate) + " is not in 0..64");
  if (!(radius > 0 && radius <= 1000)) throw UsageError("--radius: must be in (0, 1000]");
  if (!(bias >= 0 && bias < 1)) throw UsageError("--bias: must be in [0, 1)");
  CheckChoice(method, kInpaintMethods, "--method");
  CheckWork();
  ParseGlBackend(gl);
}

namespace {

using Clock = std::chrono::steady_clock;

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
cv::Mat BinaryMask(const Image& m) {
  const Image set = MaskFromImage(m);
  cv::Mat b(m.height, m.width, CV_8U, cv::Scalar(0));
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) b.at<uint8_t>(y, x) = static_cast<uint8_t>(set.at(x, y));
  return b;
}

// partners.tsv: query → partner names, rank order.
std::map<std::string, std::vector<std::string>> ReadPartners(const fs::path& path) {
  LineReader r(path.string());
  std::string line;
  if (!r.Next(line))
    r.Fail("empty file: expected the header 'query rank image distance heading_deg'");
  auto head = SplitBlank(line);
  if (head.size() != 5 || head[0] != "query" || head[1] != "rank" || head[2] != "image")
    r.Fail("expected the header 'query rank image distance heading_deg' (pickview --partners)");
  std::map<std::string, std::vector<std::pair<int64_t, std::string>>> rows;
  while (r.Next(line)) {
    auto f = SplitChar(line, '\t');
    if (f.size() != 5) r.Fail("expected 5 tab-separated fields, found " + std::to_string(f.size()));
    int64_t rank = ParseInt(f[1], r, "rank");
    if (rank < 1) r.Fail("rank must be >= 1");
    rows[std::string(f[0])].emplace_back(rank, std::string(f[2]));
  }
  std::map<std::string, std::vector<std::string>> out;
  for (auto& [q, v] : rows) {
    std::stable_sort(v.begin(), v.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [rank, n] : v) out[q].push_back(n);
  }
  return out;
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

// OpenCV's inpainting, channel by channel unless the image is 8-bit RGB (which cv::inpaint takes
// whole).
void Inpaint2d(Image& out, const cv::Mat& mask, double radius, int flag) {
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

}  // namespace

Inpaint3dReport RunInpaint3d(const Inpaint3dOptions& o) {
  o.Check();
  Workspace ws(o.workspace);
  const bool three_d = o.method == "3d", patch = o.method == "patch2d";
  std::vector<WsItem> needs = {WsItem::kSparse, WsItem::kImages};
  if (three_d) needs.push_back(WsItem::kMesh);
  if (three_d || patch) needs.push_back(WsItem::kPartners);
  ws.Require("inpaint3d", needs);
  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  auto images = rec.ImagesByName();
  std::map<std::string, size_t> index_of;
  for (size_t i = 0; i < images.size(); ++i) index_of[images[i]->name] = i;
  std::map<std::string, std::vector<std::string>> partners;
  if (three_d || patch) {
    partners = ReadPartners(ws.PartnersPath());
    for (const auto& [q, v] : partners)
      for (const auto& n : v)
        if (!index_of.count(n))
          throw Error(
              ws.PartnersPath().string(), 0,
              "partner '" + n + "' of '" + q + "' is not an image of the workspace's model");
  }
  Selection sel = o.Select();
  std::vector<size_t> chosen = sel.Apply(images.size());

  Inpaint3dReport rep;
  rep.images = chosen.size();
  std::unique_ptr<GlContext> ctx;
  std::unique_ptr<Mesh> mesh;
  std::unique_ptr<Renderer> renderer;
  // Partners are read from images/ (never textures/, so re-runs do not feed on earlier output).
  ProjectorSources sources(ws, rec, images, nullptr, /*prefer_textures=*/false);
  auto image_of = [&](size_t k) -> const Image& { return sources.ImageOf(k); };

  Progress bar("inpaint3d", chosen.size(), o.quiet);
  for (size_t i : chosen) {
    const std::string& name = images[i]->name;
    const fs::path src = ws.ImagePath(name), mp = ws.MaskPath(name), out = ws.TexturePath(name);
    const fs::path prov = ws.TexturePath(
        (fs::path("provenance") / fs::path(name).replace_extension(".png")).string());
    std::vector<fs::path> inputs = {src, mp};
    if (three_d || patch) inputs.push_back(ws.PartnersPath());
    if (three_d) inputs.push_back(ws.MeshPath());
    if (!o.force && IsUpToDate(out, inputs) && IsUpToDate(prov, inputs)) {
      ++rep.skipped;
      bar.Step();
      continue;
    }
    auto t0 = Clock::now();
    sources.Trim();  // between images only: projectors hold references into it
    cv::Mat mask;
    if (fs::exists(mp)) {
      Image m = ReadImage(mp.string());
      mask = BinaryMask(m);
      if (cv::countNonZero(mask) == 0) mask.release();
    }
    if (mask.empty()) {
      // No mask: the recorded file itself, byte for byte.
      ImageSpecInfo spec = ReadImageSpec(src.string());
      {
        AtomicFile af(out);
        fs::copy_file(src, af.temp_path(), fs::copy_options::overwrite_existing);
        af.Commit();
      }
      WriteImage(prov.string(), Image(spec.width, spec.height, 1, 8, kProvenanceOriginal));
      ++rep.copied;
      rep.ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      bar.Step();
      continue;
    }
    Image img = ReadImage(src.string());
    if (mask.cols != img.width || mask.rows != img.height)
      throw Error(mp.string(), 0,
                  "mask is " + std::to_string(mask.cols) + "x" + std::to_string(mask.rows) +
                      ", image is " + std::to_string(img.width) + "x" + std::to_string(img.height));
    if (o.dilate > 0)
      cv::dilate(mask, mask,
                 cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                           cv::Size(2 * o.dilate + 1, 2 * o.dilate + 1)));
    Image res = img;
    Image pv(img.width, img.height, 1, 8, kProvenanceOriginal);
    std::vector<size_t> ps;
    if (three_d || patch) {
      auto it = partners.find(name);
      if (it != partners.end())
        for (size_t r = 0; r < it->second.size() && r < size_t(o.partners); ++r)
          ps.push_back(index_of.at(it->second[r]));
    }
    size_t n_mask = size_t(cv::countNonZero(mask));
    rep.masked_pixels += n_mask;

    if (three_d) {
      if (!renderer) {
        mesh = std::make_unique<Mesh>(ReadMesh(ws.MeshPath().string()));
        if (mesh->faces.empty())
          throw Error(ws.MeshPath().string(), 0, "the mesh has no triangles");
        ctx = GlContext::Create(ParseGlBackend(o.gl));
        rep.gl = ctx->Describe();
        renderer = std::make_unique<Renderer>(*mesh);
        sources.SetRenderer(renderer.get());
      }
      std::vector<Projector> projs;
      for (size_t k : ps) {
        Projector p;
        p.view = sources.ViewOf(k);
        p.image = &sources.ImageOf(k);
        p.depth = &sources.DepthOf(k);
        p.mask = sources.MaskOf(k);
        p.key = static_cast<int64_t>(k);
        projs.push_back(p);
      }
      EffectsPlan plan;
      plan.ptm = true;
      plan.projectors = std::max<int>(1, int(projs.size()));
      plan.occlusion = plan.masks = plan.skybox = true;
      plan.bias = o.bias;
      const Camera& cam = rec.cameras.at(images[i]->camera_id);
      View view{cam, images[i]->world_to_camera};
      if (int(cam.width) != img.width || int(cam.height) != img.height)
        throw Error(src.string(), 0,
                    "image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                        ", its camera " + std::to_string(cam.width) + "x" +
                        std::to_string(cam.height));
      Renderer::Frame f = renderer->Render(view, projs, plan);
      Image own_depth = renderer->RenderDepth(view);
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
          if (!mask.at<uint8_t>(y, x)) continue;
          PutRgb255(res, x, y, {f.colour.at(x, y, 0), f.colour.at(x, y, 1), f.colour.at(x, y, 2)});
          const auto s = uint8_t(f.source.at(x, y));
          uint8_t v;
          if (s == kSourceBackground)
            v = kProvenanceBackground, ++rep.from_background;
          else if (s == kSourceVertex)
            v = kProvenanceVertex, ++rep.from_vertex;
          else if (!std::isfinite(own_depth.at(x, y)))
            v = uint8_t(kProvenanceSkyOffset + s + 1), ++rep.from_sky;
          else
            v = uint8_t(s + 1), ++rep.from_partners;
          pv.at(x, y) = v;
        }
    } else if (patch && !ps.empty()) {
      cv::Mat labels, stats, centroids;
      int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
      cv::Mat grey = GreyMat(img);
      std::vector<cv::Mat> pgrey;
      for (size_t k : ps) pgrey.push_back(GreyMat(image_of(k)));
      for (int b = 1; b < n; ++b) {
        cv::Rect box(stats.at<int>(b, cv::CC_STAT_LEFT), stats.at<int>(b, cv::CC_STAT_TOP),
                     stats.at<int>(b, cv::CC_STAT_WIDTH), stats.at<int>(b, cv::CC_STAT_HEIGHT));
        Match best;
        for (size_t r = 0; r < ps.size(); ++r) {
          Match m = MatchBlob(grey, box, pgrey[r], r);
          if (m.score < best.score) best = m;
        }
        const Image& pimg = image_of(ps[best.partner]);
        const bool found = std::isfinite(best.score);
        for (int y = box.y; y < box.y + box.height; ++y)
          for (int x = box.x; x < box.x + box.width; ++x) {
            if (labels.at<int>(y, x) != b) continue;
            if (!found) continue;  // no template fits: left to Telea below
            int px = std::clamp(x + best.offset.x, 0, pimg.width - 1),
                py = std::clamp(y + best.offset.y, 0, pimg.height - 1);
            PutRgb255(res, x, y, Rgb255(pimg, px, py));
            pv.at(x, y) = uint8_t(best.partner + 1);
            ++rep.from_partners;
          }
      }
      // Blobs no template could be placed for.
      cv::Mat rest = mask.clone();
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
          if (pv.at(x, y) != kProvenanceOriginal) rest.at<uint8_t>(y, x) = 0;
      if (cv::countNonZero(rest)) {
        Inpaint2d(res, rest, o.radius, cv::INPAINT_TELEA);
        for (int y = 0; y < img.height; ++y)
          for (int x = 0; x < img.width; ++x)
            if (rest.at<uint8_t>(y, x)) pv.at(x, y) = kProvenance2d, ++rep.from_2d;
      }
    } else {
      Inpaint2d(res, mask, o.radius, o.method == "ns" ? cv::INPAINT_NS : cv::INPAINT_TELEA);
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
          if (mask.at<uint8_t>(y, x)) pv.at(x, y) = kProvenance2d;
      rep.from_2d += n_mask;
    }
    WriteImage(out.string(), res);
    WriteImage(prov.string(), pv);
    ++rep.inpainted;
    rep.ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    bar.Step();
  }
  nlohmann::json opts = {{"method", o.method}, {"partners", o.partners}, {"dilate", o.dilate},
                         {"radius", o.radius}, {"bias", o.bias},         {"frames", o.frames},
                         {"shard", o.shard}};
  std::vector<fs::path> ins;
  if (three_d) ins.push_back(ws.MeshPath());
  if (three_d || patch) ins.push_back(ws.PartnersPath());
  ws.WriteProvenance(o.ProvenanceName("inpaint3d"), opts, ins);
  return rep;
}

}  // namespace mvtm
