#include "georef.h"

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/work.h"
#include "geo/gps_align.h"
#include "geo/gps_log.h"
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
  t.Text("--gps", &o.gps,
         "GPS log (GPX, or NMEA RMC/GGA with checksums): the model goes to UTM (x east, y north, "
         "z up, metres about the origin in georef.json); needs --times")
      .File();
  t.Text("--times", &o.times,
         "Each image's time in seconds: frames' frames.tsv, lines NAME TIME, or KITTI times.txt "
         "(line k = the image numbered k)")
      .File();
  t.Real("--gps-offset", &o.gps_offset,
         "Seconds from the GPS log's first fix to the frames' time 0 (frames with absolute times, "
         "> 1e8 s: added to them)")
      .Range(-1e9, 1e9);
  t.Real("--gps-search", &o.gps_search,
         "Seconds either side of --gps-offset searched for the offset at which the drive fits "
         "the log best (0: use --gps-offset as it is)")
      .Range(0, 3600);
  t.Real("--gps-max-gap", &o.gps_max_gap,
         "Longest gap, in seconds, between the two frames around a fix across which the camera's "
         "position at the fix is interpolated")
      .Range(0, 1e6, true);
  t.Real("--height-sigma", &o.height_sigma,
         "Relative standard error of the camera-height scale, weighing it against GPS's when "
         "both are given")
      .Range(0, 1, true);
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
  if (!gps.empty() && times.empty())
    throw UsageError("--gps needs --times: the time of each image, to find it in the log");
  if (gps.empty() && !times.empty()) throw UsageError("--times is used only with --gps");
}

namespace {

fs::path GeorefJson(const GeorefOptions& o) { return fs::path(o.outdir) / "georef.json"; }

nlohmann::json Record(const GroundFit& fit, const Sim3& T, double camera_height_metres,
                      const GpsAlignment* gps, const GeorefOptions& o) {
  nlohmann::json j;
  j["unit"] = camera_height_metres > 0 || gps ? "metre" : "model";
  j["scale_source"] = gps ? gps->scale_source : camera_height_metres > 0 ? "camera-height" : "none";
  if (gps) {
    // UTM = origin + local (x east, y north, z up).
    j["crs"]["utm_zone"] = gps->zone.Name();
    j["crs"]["epsg"] = gps->zone.Epsg();
    j["crs"]["datum"] = "WGS84";
    j["crs"]["origin"] = {gps->origin.x(), gps->origin.y(), gps->origin.z()};
    j["crs"]["altitude"] = gps->has_altitude ? "from the log" : "none in the log: 0 at the road";
    j["gps"]["log"] = o.gps;
    j["gps"]["offset_seconds"] = gps->offset;
    j["gps"]["frames"] = gps->frames;
    j["gps"]["matched"] = gps->matched;
    j["gps"]["fixes_paired"] = gps->pairs;
    j["gps"]["inliers"] = gps->inliers;
    j["gps"]["rms_metres"] = gps->rms;
    j["gps"]["scale_gps"] = gps->scale_gps;
    j["gps"]["scale_gps_sigma"] = gps->scale_gps_sigma;
  }
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
bool Number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end && *end == '\0' && std::isfinite(value);
}

bool NameNumber(const std::string& name, double& value) {
  return Number(fs::path(name).stem().string(), value);
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

// name → time (seconds) from frames.tsv (a header with name and time columns), "NAME TIME" lines,
// or KITTI times.txt (one number a line: line k is the image whose name's number is k).
std::map<std::string, double> ReadTimes(const std::string& path,
                                        const std::vector<const ImageRecord*>& images) {
  std::ifstream in(path);
  if (!in) throw Error(path, 0, "cannot open");
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::vector<std::string> f;
    for (std::string w; ls >> w;) f.push_back(w);
    if (!f.empty() && f[0][0] != '#') rows.push_back(f);
  }
  std::map<std::string, double> out;
  if (rows.empty()) throw Error(path, 0, "no times");
  size_t name_col = 0, time_col = 1, first = 0;
  const auto& h = rows[0];
  auto col = [&](const char* k) { return std::find(h.begin(), h.end(), k) - h.begin(); };
  if (col("name") < static_cast<long>(h.size()) && col("time") < static_cast<long>(h.size())) {
    name_col = static_cast<size_t>(col("name"));
    time_col = static_cast<size_t>(col("time"));
    first = 1;
  } else if (h.size() == 1) {  // KITTI times.txt
    std::vector<double> t;
    for (size_t r = 0; r < rows.size(); ++r) {
      double v;
      if (rows[r].size() != 1 || !Number(rows[r][0], v))
        throw Error(path, static_cast<long>(r + 1), "expected one time in seconds a line");
      t.push_back(v);
    }
    for (const ImageRecord* im : images) {
      double k;
      if (NameNumber(im->name, k) && k == std::round(k) && k >= 0 &&
          k < static_cast<double>(t.size()))
        out[im->name] = t[static_cast<size_t>(k)];
    }
    return out;
  }
  for (size_t r = first; r < rows.size(); ++r) {
    double v;
    if (rows[r].size() <= std::max(name_col, time_col) || !Number(rows[r][time_col], v))
      throw Error(path, static_cast<long>(r + 1), "expected an image name and a time in seconds");
    out[rows[r][name_col]] = v;
  }
  return out;
}

Sim3 Compose(const Sim3& a, const Sim3& b) {  // a after b
  Sim3 c;
  c.scale = a.scale * b.scale;
  c.R = a.R * b.R;
  c.t = a.scale * (a.R * b.t) + a.t;
  return c;
}

// Places the upright model `rec` (model units) in UTM by the GPS log; returns the alignment.
GpsAlignment PlaceByGps(Reconstruction& rec, const GroundFit& fit, const GeorefOptions& o,
                        GeorefReport& rep) {
  const GpsLog log = ReadGpsLog(o.gps);
  rep.gps_bad_checksums = log.bad_checksums;
  const auto images = rec.ImagesByName();
  const std::map<std::string, double> times = ReadTimes(o.times, images);
  std::vector<Eigen::Vector3d> centres;
  std::vector<double> t;
  for (const ImageRecord* im : images) {
    auto it = times.find(im->name);
    if (it == times.end()) continue;
    centres.push_back(im->world_to_camera.Inverse().t);
    t.push_back(it->second);
  }
  if (centres.size() < 3)
    throw Error(o.times, 0,
                std::to_string(centres.size()) + " of the model's " +
                    std::to_string(images.size()) + " images have a time here: need 3");
  GpsAlignOptions g;
  g.offset = o.gps_offset;
  g.search = o.gps_search;
  g.max_gap = o.gps_max_gap;
  g.height_sigma = o.height_sigma;
  if (o.camera_height > 0) {
    if (!(fit.camera_height > 0))
      throw Error("", 0,
                  "no camera sees the road below it (too few sparse points on the ground): the "
                  "camera height cannot give the scale (leave --camera-height out: GPS alone)");
    g.height_scale = o.camera_height / fit.camera_height;
  }
  GpsAlignment a = AlignToGps(centres, t, log, o.gps, g);
  TransformModel(rec, a.T);
  return a;
}

}  // namespace

GeorefReport RunGeoref(const GeorefOptions& o) {
  o.Check();
  GeorefReport rep;
  std::vector<fs::path> inputs;
  for (const char* stem : {"cameras", "images", "points3D"})
    for (const char* ext : {".txt", ".bin"})
      inputs.push_back(fs::path(o.model) / (std::string(stem) + ext));
  if (!o.gps.empty()) inputs.insert(inputs.end(), {o.gps, o.times});
  GeorefOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, "georef", table, inputs, fs::path());
  std::vector<fs::path> outputs;
  for (const auto& f : ColmapModelFileNames(o.binary)) outputs.push_back(fs::path(o.outdir) / f);
  outputs.push_back(GeorefJson(o));
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(o.outdir);
  if (!stale) {
    rep.up_to_date = true;
  } else {
    Reconstruction rec = ReadColmapModel(o.model);
    const GroundFit fit = FitGround(rec);
    // With GPS, upright in model units first; the scale comes with the placement.
    Sim3 T = UprightTransform(rec, fit, o.gps.empty() ? o.camera_height : 0);
    TransformModel(rec, T);
    std::optional<GpsAlignment> gps;
    if (!o.gps.empty()) {
      gps = PlaceByGps(rec, fit, o, rep);
      T = Compose(gps->T, T);
      rep.gps = true;
      rep.gps_frames = gps->frames;
      rep.gps_matched = gps->matched;
      rep.gps_pairs = gps->pairs;
      rep.gps_inliers = gps->inliers;
      rep.gps_rms = gps->rms;
      rep.scale_gps = gps->scale_gps;
      rep.scale_gps_sigma = gps->scale_gps_sigma;
      rep.utm_zone = gps->zone.Name();
      rep.scale_source = gps->scale_source;
      rep.gps_offset = gps->offset;
    }
    CreateFolder(o.outdir);
    if (o.binary)
      WriteColmapBinary(rec, o.outdir);
    else
      WriteColmapText(rec, o.outdir);
    const nlohmann::json record = Record(fit, T, o.camera_height, gps ? &*gps : nullptr, o);
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
