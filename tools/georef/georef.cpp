#include "georef.h"

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/work.h"
#include "geometry/align.h"
#include "io/colmap_model.h"
#include "io/trajectory.h"
#include "run/ledger.h"
#include "scene/upright.h"

namespace mvtm {

namespace fs = std::filesystem;

OptionTable DeclareOptions(GeorefOptions& o) {
  OptionTable t("georef");
  t.Positional("MODEL", &o.model, "COLMAP model folder (cameras, images, points3D; .txt or .bin)")
      .Dir();
  t.Positional("OUTDIR", &o.outdir,
               "Folder for the upright model and georef.json (may not be MODEL)")
      .Dir();
  t.Real("--camera-height", &o.camera_height,
         "The camera's height above the road in metres (KITTI: 1.65): the model is scaled to "
         "metres; 0 keeps the model's unit")
      .Range(0, 100);
  t.Text("--compare", &o.compare,
         "Reference trajectory (TUM or KITTI camera-to-world, e.g. ground truth): print the "
         "absolute trajectory error after a similarity fit; images match KITTI lines by the "
         "number in their name, TUM rows by the timestamp in their name, a COLMAP model's "
         "images (folder) by name")
      .File()
      .Cosmetic();
  t.Flag("--binary", &o.binary, "Write cameras.bin, images.bin, points3D.bin");
  t.Flag("--force", &o.force, "Rewrite the model even when it is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void GeorefOptions::Check() const {
  CheckDeclared(*this);
  std::error_code ec;
  if (fs::exists(outdir) && fs::equivalent(model, outdir, ec))
    throw UsageError("OUTDIR must not be MODEL (the model is read while the new one is written)");
}

namespace {

fs::path GeorefJson(const GeorefOptions& o) { return fs::path(o.outdir) / "georef.json"; }

nlohmann::json Record(const GroundFit& fit, const Sim3& T, double camera_height_metres) {
  nlohmann::json j;
  j["unit"] = camera_height_metres > 0 ? "metre" : "model";
  j["scale_source"] = camera_height_metres > 0 ? "camera-height" : "none";
  j["camera_height_metres"] = camera_height_metres;
  j["camera_height_model_units"] = fit.camera_height;
  j["up"] = "z";
  j["cameras"] = fit.cameras;
  j["cameras_with_ground"] = fit.cameras_with_ground;
  // x_out = scale * R * x_in + t: the input model's world to this one's.
  j["from_input"]["scale"] = T.scale;
  for (int r = 0; r < 3; ++r) {
    j["from_input"]["R"].push_back({T.R(r, 0), T.R(r, 1), T.R(r, 2)});
    j["from_input"]["t"].push_back(T.t[r]);
  }
  return j;
}

// The frame number or timestamp in an image name ("000012.png" → 12, "1305031102.175304.png").
bool NameNumber(const std::string& name, double& value) {
  std::string stem = fs::path(name).stem().string();
  if (stem.empty()) return false;
  char* end = nullptr;
  value = std::strtod(stem.c_str(), &end);
  return end && *end == '\0' && std::isfinite(value);
}

// Camera centres of `rec`'s images and of the reference poses they match: KITTI lines by the
// number in the image's name, TUM rows by the timestamp in it.
void MatchTrajectory(const Reconstruction& rec, const Trajectory& ref, TrajectoryFormat fmt,
                     std::vector<Eigen::Vector3d>& src, std::vector<Eigen::Vector3d>& dst) {
  for (const ImageRecord* im : rec.ImagesByName()) {
    double key;
    if (!NameNumber(im->name, key)) continue;
    const StampedPose* match = nullptr;
    if (fmt == TrajectoryFormat::kKitti) {
      const double idx = std::round(key);
      if (idx == key && idx >= 0 && idx < static_cast<double>(ref.poses.size()))
        match = &ref.poses[static_cast<size_t>(idx)];
    } else {
      for (const auto& p : ref.poses)
        if (std::abs(p.time - key) < 1e-4) match = &p;
    }
    if (!match) continue;
    const Rigid3d c2w = im->world_to_camera.Inverse();
    src.push_back(c2w.t);
    dst.push_back(match->pose.t);
  }
}

void Compare(const GeorefOptions& o, GeorefReport& rep) {
  const Reconstruction rec = ReadColmapModel(o.outdir);
  std::vector<Eigen::Vector3d> src, dst;
  if (fs::is_directory(o.compare)) {  // another model of the same photos: match by name
    const Reconstruction other = ReadColmapModel(o.compare);
    std::map<std::string, const ImageRecord*> by_name;
    for (const ImageRecord* im : other.ImagesByName()) by_name[im->name] = im;
    for (const ImageRecord* im : rec.ImagesByName()) {
      auto it = by_name.find(im->name);
      if (it == by_name.end()) continue;
      src.push_back(im->world_to_camera.Inverse().t);
      dst.push_back(it->second->world_to_camera.Inverse().t);
    }
  } else {
    const TrajectoryFormat fmt = DetectTrajectoryFormat(o.compare);
    if (fmt == TrajectoryFormat::kColmap)
      throw Error(o.compare, 0, "--compare takes a COLMAP model as its folder, not a file of it");
    MatchTrajectory(rec, ReadTrajectory(o.compare, fmt), fmt, src, dst);
  }
  rep.matched = src.size();
  if (src.size() < 3)
    throw Error(o.compare, 0,
                std::to_string(src.size()) + " images matched a reference pose: need 3");
  const Sim3 T = AlignUmeyama(src, dst, true);
  rep.ate_rmse = AteRmse(T, src, dst);
  rep.reference_scale = T.scale;
  rep.path_length = 0;
  for (size_t i = 1; i < dst.size(); ++i) rep.path_length += (dst[i] - dst[i - 1]).norm();
}

}  // namespace

GeorefReport RunGeoref(const GeorefOptions& o) {
  o.Check();
  GeorefReport rep;
  std::vector<fs::path> inputs;
  for (const char* stem : {"cameras", "images", "points3D"})
    for (const char* ext : {".txt", ".bin"})
      inputs.push_back(fs::path(o.model) / (std::string(stem) + ext));
  GeorefOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, "georef", table, inputs, fs::path());
  std::vector<fs::path> outputs;
  for (const auto& f : ColmapModelFileNames(o.binary)) outputs.push_back(fs::path(o.outdir) / f);
  outputs.push_back(GeorefJson(o));
  bool stale = false;
  for (const fs::path& p : outputs) stale = !ledger.Stale(p, {}, o.force).empty() || stale;
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(o.outdir);
  if (!stale) {
    rep.up_to_date = true;
  } else {
    Reconstruction rec = ReadColmapModel(o.model);
    const GroundFit fit = FitGround(rec);
    const Sim3 T = UprightTransform(rec, fit, o.camera_height);
    TransformModel(rec, T);
    CreateFolder(o.outdir);
    if (o.binary)
      WriteColmapBinary(rec, o.outdir);
    else
      WriteColmapText(rec, o.outdir);
    const nlohmann::json record = Record(fit, T, o.camera_height);
    WriteTextAtomic(GeorefJson(o), [&](std::ostream& out) { out << record.dump(2) << "\n"; });
    for (const fs::path& p : outputs) ledger.Done(p);
    ledger.Write();
    rep.cameras = fit.cameras;
    rep.cameras_with_ground = fit.cameras_with_ground;
    rep.ground_points = fit.ground_points;
    rep.camera_height = fit.camera_height;
    rep.height_spread = fit.height_spread;
    rep.scale = T.scale;
    rep.tilt_degrees =
        std::acos(std::clamp(fit.up.dot(fit.camera_up), -1.0, 1.0)) * 180 / 3.14159265358979323846;
  }
  if (!o.compare.empty()) Compare(o, rep);
  return rep;
}

}  // namespace mvtm
