#include "boresight.h"

#include <Eigen/Geometry>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "io/colmap_model.h"
#include "run/ledger.h"

namespace mvtm {

namespace fs = std::filesystem;

OptionTable DeclareOptions(BoresightToolOptions& o) {
  OptionTable t("boresight");
  t.Positional("MODEL", &o.model,
               "COLMAP model folder whose poses are of record (undistorted camera: run colmap "
               "image_undistorter first)")
      .Dir();
  t.Positional("OUTDIR", &o.outdir,
               "Folder for the turned model and boresight.json (may not be MODEL)")
      .Dir();
  t.Text("--exclude", &o.exclude,
         "File of image names, one per line, whose observations take no part in the fit (held-out "
         "photos); their poses are turned like the others")
      .File();
  t.Integer("--min-track", &o.min_track, "Observations in fitted images a point needs to take part")
      .Range(2, 1000);
  t.Real("--min-angle", &o.min_angle,
         "Degrees: a point takes part when two of its rays meet at this angle or more")
      .Range(0, 90);
  t.Real("--max-error", &o.max_error,
         "Pixels: observations farther from their point at the recorded attitude are outliers")
      .Above(0);
  t.Real("--conditioning", &o.conditioning,
         "A direction of rotation whose curvature is under this fraction of the best-determined "
         "one's stays as recorded (the roll about the optical axis on a straight road)")
      .Range(0, 1);
  t.Real("--min-gain", &o.min_gain,
         "The model is turned only when the fit removes at least this share of the median "
         "reprojection error; else it is written as recorded (0: always turned)")
      .Range(0, 1);
  t.Flag("--binary", &o.binary, "Write cameras.bin, images.bin, points3D.bin");
  t.Flag("--force", &o.force, "Rewrite the model even when it is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void BoresightToolOptions::Check() const {
  CheckDeclared(*this);
  std::error_code ec;
  if (fs::exists(outdir) && fs::equivalent(model, outdir, ec))
    throw UsageError("OUTDIR must not be MODEL (the model is read while the new one is written)");
}

namespace {

// Image names, one per line (blank lines and # comments skipped); each must name an image.
std::set<std::string> ReadExcluded(const std::string& file, const Reconstruction& rec) {
  LineReader r(file);
  std::set<std::string> names;
  std::string line;
  while (r.Next(line)) {
    if (!rec.FindImage(line)) r.Fail("image '" + line + "' is not in the model");
    names.insert(line);
  }
  return names;
}

nlohmann::json Record(const BoresightFit& f, size_t excluded) {
  const double deg = 180 / 3.14159265358979323846;
  nlohmann::json j;
  j["convention"] =
      "world_to_camera rotation of every image becomes R * R_recorded; centres unchanged; "
      "rotation vector in camera axes (x right: pitch, y down: yaw, z forward: roll)";
  j["rotation_deg"] = {{"pitch", f.rotation.x() * deg},
                       {"yaw", f.rotation.y() * deg},
                       {"roll", f.rotation.z() * deg}};
  j["angle_deg"] = f.rotation.norm() * deg;
  j["applied"] = f.applied;
  j["sigma_deg"] = f.sigma_deg;
  // The rotation the model was turned by: the fitted one, or the identity when not applied.
  const Eigen::Matrix3d R = f.applied ? f.R : Eigen::Matrix3d::Identity();
  for (int r = 0; r < 3; ++r) j["R"].push_back({R(r, 0), R(r, 1), R(r, 2)});
  j["frozen_directions"] = nlohmann::json::array();
  for (const auto& d : f.frozen) j["frozen_directions"].push_back({d.x(), d.y(), d.z()});
  j["curvature"] = {f.curvature(0), f.curvature(1), f.curvature(2)};
  j["images"] = f.images;
  j["excluded_images"] = excluded;
  j["points"] = f.points;
  j["observations"] = f.observations;
  j["outliers"] = f.outliers;
  j["iterations"] = f.iterations;
  j["reprojection_px"] = {{"median_before", f.median_before},
                          {"median_after", f.median_after},
                          {"mean_before", f.mean_before},
                          {"mean_after", f.mean_after}};
  return j;
}

}  // namespace

BoresightReport RunBoresight(const BoresightToolOptions& o) {
  o.Check();
  BoresightReport rep;
  std::vector<fs::path> inputs;
  for (const char* stem : {"cameras", "images", "points3D"})
    for (const char* ext : {".txt", ".bin"})
      inputs.push_back(fs::path(o.model) / (std::string(stem) + ext));
  if (!o.exclude.empty()) inputs.push_back(o.exclude);
  BoresightToolOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, "boresight", table, inputs, fs::path());
  std::vector<fs::path> outputs;
  for (const auto& f : ColmapModelFileNames(o.binary)) outputs.push_back(fs::path(o.outdir) / f);
  outputs.push_back(fs::path(o.outdir) / "boresight.json");
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(o.outdir);
  if (!stale) {
    rep.up_to_date = true;
    return rep;
  }
  Reconstruction rec = ReadColmapModel(o.model);
  BoresightOptions bo;
  if (!o.exclude.empty()) bo.exclude = ReadExcluded(o.exclude, rec);
  bo.min_track = static_cast<size_t>(o.min_track);
  bo.min_angle_deg = o.min_angle;
  bo.max_error_px = o.max_error;
  bo.conditioning = o.conditioning;
  bo.min_gain = o.min_gain;
  rep.excluded = bo.exclude.size();
  rep.fit = FitBoresight(rec, bo);
  if (rep.fit.applied) ApplyBoresight(rec, rep.fit.R, o.min_angle);
  CreateFolder(o.outdir);
  if (o.binary)
    WriteColmapBinary(rec, o.outdir);
  else
    WriteColmapText(rec, o.outdir);
  const nlohmann::json record = Record(rep.fit, rep.excluded);
  WriteTextAtomic(fs::path(o.outdir) / "boresight.json",
                  [&](std::ostream& out) { out << record.dump(2) << "\n"; });
  for (const fs::path& p : outputs) ledger.Done(p);
  ledger.Write();
  return rep;
}

}  // namespace mvtm
