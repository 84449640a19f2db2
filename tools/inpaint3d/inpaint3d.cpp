#include "inpaint3d.h"

#include <chrono>
#include <map>
#include <memory>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "cli/selection.h"
#include "image/mask.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/partners.h"
#include "render/context.h"
#include "run/ledger.h"
#include "workspace/projector_sources.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(Inpaint3dOptions& o) {
  OptionTable t("inpaint3d");
  t.Positional("WS", &o.workspace,
               "Workspace folder (sparse/, images/, masks/, partners.tsv, mesh.ply; depth/ used "
               "when present)")
      .Dir();
  t.Choice("--method", &o.method, kInpaintMethods,
           "3d: partners through the mesh; telea, ns: OpenCV inpainting; patch2d: thesis 5.2 "
           "templates");
  t.Integer("--partners", &o.partners, "N: partners used per image (ranks 1..N of partners.tsv)")
      .Range(1, 16);
  t.Integer("--dilate", &o.dilate, "Pixels the mask is dilated by before inpainting").Range(0, 64);
  t.Real("--radius", &o.radius, "telea, ns: inpainting radius in pixels").Range(0, 1000, true);
  t.Real("--bias", &o.bias, "3d: occlusion bias, relative: occluded when z > depth*(1+B)")
      .Range(0, 1, false, true);
  t.Choice("--gl", &o.gl, GlBackendTable(), "3d: OpenGL backend");
  DeclareWorkOptions(t, o, "images", "in name order", "Rewrite outputs that are up to date");
  return t;
}

void Inpaint3dOptions::Check() const { CheckDeclared(*this); }

namespace {

using Clock = std::chrono::steady_clock;

bool UsesMesh(const Inpaint3dOptions& o) { return o.method == InpaintMethod::k3d; }
bool UsesPartners(const Inpaint3dOptions& o) {
  return o.method == InpaintMethod::k3d || o.method == InpaintMethod::kPatch2d;
}

// What every image of the run shares: the model, its images in name order, their partners.
struct Inputs {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;                    // ImagesByName order
  std::map<std::string, size_t> index_of;                    // name → index in `images`
  std::map<std::string, std::vector<std::string>> partners;  // partners.tsv, rank order
};

Inputs ReadInputs(const Inpaint3dOptions& o, const Workspace& ws) {
  std::vector<WsItem> needs = {WsItem::kSparse, WsItem::kImages};
  if (UsesMesh(o)) needs.push_back(WsItem::kMesh);
  if (UsesPartners(o)) needs.push_back(WsItem::kPartners);
  ws.Require("inpaint3d", needs);
  Inputs in;
  in.rec = ReadColmapModel(ws.SparseDir().string());
  in.images = in.rec.ImagesByName();
  for (size_t i = 0; i < in.images.size(); ++i) in.index_of[in.images[i]->name] = i;
  if (!UsesPartners(o)) return in;
  in.partners = PartnersByQuery(ReadPartners(ws.PartnersPath().string()));
  for (const auto& [q, v] : in.partners)
    for (const auto& n : v)
      if (!in.index_of.count(n))
        throw Error(ws.PartnersPath().string(), 0,
                    "partner '" + n + "' of '" + q + "' is not an image of the workspace's model");
  return in;
}

// The indices of an image's partners, ranks 1..`limit`.
std::vector<size_t> PartnersOf(const Inputs& in, const std::string& name, int limit) {
  std::vector<size_t> ps;
  auto it = in.partners.find(name);
  if (it != in.partners.end())
    for (size_t r = 0; r < it->second.size() && r < size_t(limit); ++r)
      ps.push_back(in.index_of.at(it->second[r]));
  return ps;
}

// The mesh, GL context and renderer of the 3d method, made when the first image needs them.
class MeshStage {
 public:
  Renderer& Get(const Workspace& ws, GlBackend gl, ProjectorSources& sources,
                std::string& gl_description) {
    if (renderer_) return *renderer_;
    mesh_ = std::make_unique<Mesh>(ReadMesh(ws.MeshPath().string()));
    if (mesh_->faces.empty()) throw Error(ws.MeshPath().string(), 0, "the mesh has no triangles");
    ctx_ = GlContext::Create(gl);
    gl_description = ctx_->Describe();
    renderer_ = std::make_unique<Renderer>(*mesh_);
    sources.SetRenderer(renderer_.get());
    return *renderer_;
  }

 private:
  std::unique_ptr<GlContext> ctx_;
  std::unique_ptr<Mesh> mesh_;
  std::unique_ptr<Renderer> renderer_;
};

// The state one run carries from image to image.
struct Run {
  Run(const Inpaint3dOptions& options, const Workspace& workspace, const Inputs& inputs,
      Ledger& record)
      : o(options),
        ws(workspace),
        in(inputs),
        ledger(record),
        sources(ws, in.rec, in.images, nullptr, /*prefer_textures=*/false) {}

  const Inpaint3dOptions& o;
  const Workspace& ws;
  const Inputs& in;
  Ledger& ledger;  // the outputs' record: what is up to date, what this run wrote
  // Partners are read from images/ (never textures/, so re-runs do not feed on earlier output).
  ProjectorSources sources;
  MeshStage mesh;
  Inpaint3dReport rep;
};

std::vector<Projector> Projectors(ProjectorSources& sources, const std::vector<size_t>& ps) {
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
  return projs;
}

// Image `i` (read from `src`) inpainted under the (dilated) mask by the run's method.
Inpainted InpaintImage(Run& run, size_t i, const fs::path& src, const Image& img,
                       const Image& mask) {
  const std::vector<size_t> ps = PartnersOf(run.in, run.in.images[i]->name, run.o.partners);
  if (UsesMesh(run.o)) {
    Renderer& renderer = run.mesh.Get(run.ws, run.o.gl, run.sources, run.rep.gl);
    std::vector<Projector> projs = Projectors(run.sources, ps);
    const ImageRecord& im = *run.in.images[i];
    View view{run.in.rec.cameras.at(im.camera_id), im.world_to_camera};
    CheckViewSize(img, view, src.string());
    return InpaintThroughMesh(renderer, view, img, mask, projs, run.o.bias);
  }
  if (run.o.method == InpaintMethod::kPatch2d) {
    std::vector<const Image*> partners;
    for (size_t k : ps) partners.push_back(&run.sources.ImageOf(k));
    return InpaintPatch2d(img, mask, partners, run.o.radius);
  }
  return InpaintOpenCv(
      img, mask,
      run.o.method == InpaintMethod::kNs ? OpenCvInpaintMethod::kNs : OpenCvInpaintMethod::kTelea,
      run.o.radius);
}

void Add(Inpaint3dReport& rep, const InpaintCounts& c) {
  rep.masked_pixels += c.masked;
  rep.from_partners += c.partners;
  rep.from_sky += c.sky;
  rep.from_vertex += c.vertex;
  rep.from_background += c.background;
  rep.from_2d += c.two_d;
}

// No mask, or an empty one: the recorded file itself, byte for byte, and an all-original
// provenance image.
void CopyUnmasked(const fs::path& src, const fs::path& out, const fs::path& prov) {
  ImageSpecInfo spec = ReadImageSpec(src.string());
  {
    AtomicFile af(out);
    fs::copy_file(src, af.temp_path(), fs::copy_options::overwrite_existing);
    af.Commit();
  }
  WriteImage(prov.string(), Image(spec.width, spec.height, 1, 8, kProvenanceOriginal),
             PngCompression::kFastFlat);
}

// The files image i's outputs are made from beyond the run's inputs: its image and mask, and with
// partners its partners' images (patch2d, 3d) and masks and depth maps (3d). Absent ones count:
// a mask that appears makes the outputs stale.
std::vector<fs::path> ItemInputs(const Run& run, size_t i) {
  const Workspace& ws = run.ws;
  const std::string& name = run.in.images[i]->name;
  std::vector<fs::path> in = {ws.ImagePath(name), ws.MaskPath(name)};
  if (!UsesPartners(run.o)) return in;
  for (size_t k : PartnersOf(run.in, name, run.o.partners)) {
    const std::string& partner = run.in.images[k]->name;
    in.push_back(ws.ImagePath(partner));
    if (!UsesMesh(run.o)) continue;
    in.push_back(ws.MaskPath(partner));
    in.push_back(ws.DepthPath(partner));
  }
  return in;
}

// Writes textures/NAME and its provenance image for image `i`, unless both are up to date.
void ProcessImage(Run& run, size_t i) {
  const Workspace& ws = run.ws;
  const std::string& name = run.in.images[i]->name;
  const fs::path src = ws.ImagePath(name), mp = ws.MaskPath(name), out = ws.TexturePath(name);
  const fs::path prov = ws.TextureProvenancePath(name);
  const std::vector<fs::path> in = ItemInputs(run, i);
  // Each output is asked (so both count in the summary); either stale redoes both.
  bool stale = !run.ledger.Stale(out, in, run.o.force).empty();
  stale = !run.ledger.Stale(prov, in, run.o.force).empty() || stale;
  if (!stale) {
    ++run.rep.skipped;
    return;
  }
  auto t0 = Clock::now();
  run.sources.Trim();  // between images only: projectors hold references into it
  Image mask = fs::exists(mp) ? ReadMask(mp.string()) : Image();
  if (CountSet(mask) == 0) {
    CopyUnmasked(src, out, prov);
    ++run.rep.copied;
  } else {
    Image img = ReadImage(src.string());
    const Camera& cam = run.in.rec.cameras.at(run.in.images[i]->camera_id);
    RequireImageSize(img, src.string(), cam.width, cam.height);
    CheckMaskSize(img, mask, mp.string());
    Inpainted r = InpaintImage(run, i, src, img, DilateMask(mask, run.o.dilate));
    WriteImage(out.string(), r.image, PngCompression::kFast);  // photo-like: fast settings
    WriteImage(prov.string(), r.provenance, PngCompression::kFastFlat);
    Add(run.rep, r.counts);
    ++run.rep.inpainted;
  }
  run.ledger.Done(out, in);
  run.ledger.Done(prov, in);
  run.rep.ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The files every output depends on: the model, and the mesh and partners.tsv when the method
// uses them.
std::vector<fs::path> RunInputs(const Inpaint3dOptions& o, const Workspace& ws) {
  std::vector<fs::path> ins = ws.SparseModelFiles();
  if (UsesMesh(o)) ins.push_back(ws.MeshPath());
  if (UsesPartners(o)) ins.push_back(ws.PartnersPath());
  return ins;
}

}  // namespace

Inpaint3dReport RunInpaint3d(const Inpaint3dOptions& o) {
  o.Check();
  Workspace ws(o.workspace);
  const Inputs in = ReadInputs(o, ws);
  const std::vector<size_t> chosen = o.Select().Apply(in.images.size());
  Inpaint3dOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  // The outputs are inside the workspace: its record, provenance/inpaint3d.json (a shard's own).
  Ledger ledger(ws.root(), o.ProvenanceName("inpaint3d"), table, RunInputs(o, ws), ws.root());
  Run run(o, ws, in, ledger);
  run.rep.images = chosen.size();
  // A killed run's leftovers go, even when every output is up to date.
  RemoveStaleTemporaries(ws.TexturesDir());
  RemoveStaleTemporaries(ws.TexturesDir() / "provenance");
  Progress bar("inpaint3d", chosen.size(), o.quiet);
  for (size_t i : chosen) {
    ProcessImage(run, i);
    bar.Step();
  }
  run.rep.why = ledger.Summary();
  if (run.rep.inpainted + run.rep.copied > 0) ledger.Write({{"gl_used", run.rep.gl}});
  return run.rep;
}

}  // namespace mvtm
