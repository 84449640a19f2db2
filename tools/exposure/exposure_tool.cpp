#include "exposure_tool.h"

#include <algorithm>

#include "base/atomic_file.h"
#include "base/error.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "io/exposure_tsv.h"
#include "workspace/workspace.h"

namespace mvtm {

void ExposureToolOptions::Check() const { fit.Check(); }

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
  ExposureToolReport rep;
  const std::vector<fs::path> inputs = ws.SparseModelFiles();
  if (!o.force && IsUpToDate(ws.ExposurePath(), inputs)) {
    rep.up_to_date = true;
    return rep;
  }
  const Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  const auto images = rec.ImagesByName();
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
  rep.images = images.size();
  rep.observations = obs.size();
  Summarise(e, rep);
  nlohmann::json opts = {{"offsets", o.fit.offsets},
                         {"iterations", o.fit.iterations},
                         {"outlier_mads", o.fit.outlier_mads},
                         {"min_points", o.fit.min_points}};
  ws.WriteProvenance("exposure", opts, inputs);
  return rep;
}

}  // namespace mvtm
