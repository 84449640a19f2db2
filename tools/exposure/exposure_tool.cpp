#include "exposure_tool.h"

#include <algorithm>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/work.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/exposure_tsv.h"
#include "run/ledger.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(ExposureToolOptions& o) {
  OptionTable t("exposure");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/ with points, images/)").Dir();
  t.Flag("--offsets", &o.fit.offsets,
         "Fit offsets as well as gains (black-level changes; less robust to noisy samples)");
  t.Integer("--iterations", &o.fit.iterations, "Alternating least-squares rounds (1..1000)")
      .Range(1, 1000);
  t.Real("--outlier-mads", &o.fit.outlier_mads,
         "Observations further than this many median absolute deviations from the fit are dropped")
      .Above(0);
  t.Integer("--min-points", &o.fit.min_points,
            "Observations an image needs to be fitted (else identity)")
      .Range(2, 1000000);
  t.Flag("--force", &o.force, "Refit even when exposure.tsv is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void ExposureToolOptions::Check() const { CheckDeclared(*this); }

namespace {

std::vector<ExposureRow> Rows(const std::vector<const ImageRecord*>& images,
                              const std::vector<Exposure>& e,
                              const std::vector<ExposureObservation>& obs) {
  std::vector<int64_t> n(images.size(), 0);
  for (const auto& x : obs) ++n[x.image];
  std::vector<ExposureRow> rows;
  for (size_t i = 0; i < images.size(); ++i)
    rows.push_back({images[i]->name, e[i].gain, e[i].offset, e[i].fitted ? n[i] : 0});
  return rows;
}

void Summarise(const std::vector<Exposure>& e, ExposureToolReport& rep) {
  bool first = true;
  for (const auto& x : e) {
    if (!x.fitted) continue;
    ++rep.fitted;
    rep.gain_min = first ? x.gain : std::min(rep.gain_min, x.gain);
    rep.gain_max = first ? x.gain : std::max(rep.gain_max, x.gain);
    rep.offset_min = first ? x.offset : std::min(rep.offset_min, x.offset);
    rep.offset_max = first ? x.offset : std::max(rep.offset_max, x.offset);
    first = false;
  }
}

}  // namespace

ExposureToolReport RunExposure(const ExposureToolOptions& o) {
  o.Check();
  const Workspace ws(o.workspace);
  ws.Require("exposure", {WsItem::kSparse, WsItem::kImages});
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  const auto images = rec.ImagesByName();
  // exposure.tsv is made from the model and every image's pixels.
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  for (const ImageRecord* im : images) inputs.push_back(ws.ImagePath(im->name));
  ExposureToolOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(ws.root(), "exposure", table, inputs, ws.root());
  ExposureToolReport rep;
  if (ledger.Stale(ws.ExposurePath(), {}, o.force).empty()) {
    rep.up_to_date = true;
    return rep;
  }
  rep.why = ledger.Summary();
  std::vector<Image> pixels;
  for (const ImageRecord* im : images) {
    const std::string path = ws.ImagePath(im->name).string();
    pixels.push_back(ReadImage(path));
    const Camera& cam = rec.cameras.at(im->camera_id);
    RequireImageSize(pixels.back(), path, cam.width, cam.height);
  }
  const std::vector<ExposureObservation> obs = ObservePoints(rec, images, pixels);
  const std::vector<Exposure> e = FitExposure(obs, images.size(), o.fit);
  WriteExposureTsv(ws.ExposurePath().string(), Rows(images, e, obs));
  ledger.Done(ws.ExposurePath());
  rep.images = images.size();
  rep.observations = obs.size();
  Summarise(e, rep);
  ledger.Write();
  return rep;
}

}  // namespace mvtm
