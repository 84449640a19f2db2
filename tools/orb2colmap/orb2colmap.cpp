#include "orb2colmap.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "image/folder.h"
#include "image/image.h"
#include "io/colmap_database.h"
#include "io/colmap_model.h"
#include "run/ledger.h"

namespace mvtm {

namespace fs = std::filesystem;

OptionTable DeclareOptions(Orb2ColmapOptions& o) {
  OptionTable t("orb2colmap");
  t.Positional("TRAJECTORY", &o.trajectory,
               "Poses: ORB-SLAM2 KeyFrameTrajectory/CameraTrajectory or TUM (t tx ty tz qx qy qz "
               "qw), or KITTI 3x4 rows; poses with names: a COLMAP model (its folder, or its "
               "images.txt/.bin) or a NeRF/nerfstudio transforms.json, whose camera is used when "
               "no intrinsics are given; '-' for none: the camera and the --images go into the "
               "--database without pose priors, for structure from motion")
      .File();
  t.Positional("OUTDIR", &o.outdir, "Folder for cameras, images, points3D (.txt or .bin)").Dir();
  t.Choice("--input-format", &o.input_format, kOrbInputFormats, "Trajectory format");
  t.Text("--trajectory-times", &o.trajectory_times,
         "KITTI: times.txt with the timestamp of each pose line (default: line index)")
      .File();
  t.Text("--frames", &o.frames,
         "Frame timestamps: KITTI times.txt, TUM rgb.txt, or 'timestamp name' lines (default: "
         "the trajectory's own poses)")
      .File();
  t.Text("--images", &o.images, "Folder of frame images; sorted file names name the frames").Dir();
  t.Text("--camera", &o.camera,
         "Intrinsics as 'MODEL W H PARAMS...' (COLMAP model, e.g. 'PINHOLE 1241 376 718.856 "
         "718.856 607.19 185.22')")
      .Excludes("--orb-settings")
      .Excludes("--kitti-calib");
  t.Text("--orb-settings", &o.orb_settings,
         "Intrinsics from an ORB-SLAM2 settings YAML (Camera.fx ...)")
      .File()
      .Excludes("--kitti-calib");
  t.Text("--kitti-calib", &o.kitti_calib, "Intrinsics from a KITTI calib.txt").File();
  t.Integer("--kitti-cam", &o.kitti_cam, "Which projection matrix Pn of --kitti-calib").Range(0, 3);
  t.Integer("--kitti-poses-cam", &o.kitti_poses_cam,
            "Which camera Pn of --kitti-calib a TUM or KITTI TRAJECTORY's poses are of; they are "
            "moved to --kitti-cam's by the offset between the two (-1: 0 for a KITTI-format "
            "TRAJECTORY, KITTI's ground truth being the left grey camera's, else --kitti-cam)")
      .Range(-1, 3);
  t.Text("--size", &o.size,
         "Image size WxH when the intrinsics source has none (else read from --images)")
      .Alternative("40x12")
      .Check([&o] {
        if (!o.size.empty()) ParseImageSize(o.size);
      });
  t.Flag("--binary", &o.binary, "Write cameras.bin, images.bin, points3D.bin");
  t.Text("--database", &o.database,
         "Create or fill a COLMAP database.db: cameras, images with pose priors")
      .File();
  t.Choice("--outside", &o.outside, kOrbOutside, "Frames outside the keyframe time span");
  t.Flag("--force", &o.force, "Rewrite the model (and database) even when they are up to date")
      .Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

bool HasNamedPoses(const std::string& trajectory) {
  const fs::path p(trajectory);
  const std::string name = p.filename().string();
  return fs::is_directory(p) || p.extension() == ".json" || name == "images.txt" ||
         name == "images.bin";
}

void Orb2ColmapOptions::Check() const {
  CheckDeclared(*this);
  int sources = !camera.empty() + !orb_settings.empty() + !kitti_calib.empty();
  if (sources > 1 || (sources == 0 && !HasNamedPoses(trajectory)))
    throw UsageError("give exactly one of --camera, --orb-settings, --kitti-calib");
  if (HasNamedPoses(trajectory) &&
      (!frames.empty() || !trajectory_times.empty() || input_format != OrbInputFormat::kAuto))
    throw UsageError(
        "a COLMAP model or transforms.json names its images: no --frames, --trajectory-times or "
        "--input-format");
  if (kitti_poses_cam >= 0 &&
      (kitti_calib.empty() || HasNamedPoses(trajectory) || trajectory == kNoTrajectory))
    throw UsageError("--kitti-poses-cam: needs --kitti-calib and a TUM or KITTI TRAJECTORY");
  if (!images.empty() && !fs::is_directory(images))
    throw UsageError("--images: '" + images + "' is not a folder");
  if (trajectory == kNoTrajectory) {
    if (images.empty() || database.empty())
      throw UsageError("TRAJECTORY '-' (no poses) needs --images and --database");
    if (!frames.empty() || !trajectory_times.empty())
      throw UsageError("TRAJECTORY '-' (no poses) takes no --frames or --trajectory-times");
  }
}

namespace {

// The camera of --kitti-calib whose poses a TUM or KITTI TRAJECTORY holds: --kitti-poses-cam,
// or by default 0 for a KITTI-format trajectory (the KITTI benchmark's poses are the left grey
// camera's) and --kitti-cam's for a TUM one (a SLAM run on those images).
int KittiPosesCamera(const Orb2ColmapOptions& o, TrajectoryFormat fmt) {
  if (o.kitti_poses_cam >= 0) return o.kitti_poses_cam;
  return fmt == TrajectoryFormat::kKitti ? 0 : o.kitti_cam;
}

Camera ResolveCamera(const Orb2ColmapOptions& o, const std::vector<std::string>& image_files) {
  uint64_t w = 0, h = 0;
  if (!o.size.empty()) {
    const ImageSize size = ParseImageSize(o.size);
    w = size.width;
    h = size.height;
  } else if (!image_files.empty()) {
    auto spec = ReadImageSpec((fs::path(o.images) / image_files.front()).string());
    w = static_cast<uint64_t>(spec.width);
    h = static_cast<uint64_t>(spec.height);
  }
  Camera c;
  if (!o.camera.empty()) {
    c = ParseCameraSpec(o.camera);
  } else if (!o.orb_settings.empty()) {
    c = ReadOrbSettings(o.orb_settings, w, h);
  } else {
    if (!w) throw UsageError("--kitti-calib has no image size: give --size WxH or --images");
    c = ReadKittiCalib(o.kitti_calib, o.kitti_cam, w, h);
  }
  c.id = 1;
  return c;
}

std::string Basename(const std::string& p) { return fs::path(p).filename().string(); }

// Every file the model depends on: the trajectory and the other files named by options, and the
// image files of --images (their sorted names name the frames; the first gives the size).
std::vector<fs::path> Inputs(const Orb2ColmapOptions& o,
                             const std::vector<std::string>& image_files) {
  std::vector<fs::path> inputs;
  for (const std::string& in :
       {o.trajectory, o.trajectory_times, o.frames, o.orb_settings, o.kitti_calib})
    if (!in.empty() && in != kNoTrajectory) inputs.emplace_back(in);
  for (const std::string& f : image_files) inputs.push_back(fs::path(o.images) / f);
  return inputs;
}

// The files written: the three model files, and the database with --database.
std::vector<fs::path> Outputs(const Orb2ColmapOptions& o) {
  std::vector<fs::path> out;
  for (const auto& f : ColmapModelFileNames(o.binary)) out.push_back(fs::path(o.outdir) / f);
  if (!o.database.empty()) out.emplace_back(o.database);
  return out;
}

// The poses of --input-format (TUM or KITTI; a COLMAP model is refused), camera-to-world.
Trajectory ReadInputTrajectory(const Orb2ColmapOptions& o, TrajectoryFormat* fmt) {
  *fmt = o.input_format == OrbInputFormat::kTum     ? TrajectoryFormat::kTum
         : o.input_format == OrbInputFormat::kKitti ? TrajectoryFormat::kKitti
                                                    : DetectTrajectoryFormat(o.trajectory);
  if (*fmt == TrajectoryFormat::kKitti) return ReadKittiPoses(o.trajectory, o.trajectory_times);
  if (*fmt == TrajectoryFormat::kTum) return ReadTum(o.trajectory);
  throw Error(o.trajectory, 0,
              "a COLMAP images.txt is read as a model when named images.txt (or its folder)");
}

// Names the frames that have none: after the images (one each, in order), else after the
// frame index (KITTI) or the timestamp. Named frames keep their base name.
void NameFrames(const Orb2ColmapOptions& o, const std::vector<std::string>& image_files,
                TrajectoryFormat fmt, std::vector<TimedName>& frames) {
  bool named =
      std::all_of(frames.begin(), frames.end(), [](const TimedName& f) { return !f.name.empty(); });
  if (named) {
    for (auto& f : frames) f.name = Basename(f.name);
  } else if (!image_files.empty()) {
    if (image_files.size() != frames.size())
      throw Error(o.images, 0,
                  std::to_string(image_files.size()) + " images for " +
                      std::to_string(frames.size()) + " frame timestamps" +
                      (o.frames.empty() ? "" : " in " + o.frames));
    for (size_t i = 0; i < frames.size(); ++i) frames[i].name = image_files[i];
  } else {
    char buf[64];
    for (size_t i = 0; i < frames.size(); ++i) {
      if (fmt == TrajectoryFormat::kKitti)
        std::snprintf(buf, sizeof buf, "%06zu.png", i);
      else
        std::snprintf(buf, sizeof buf, "%.6f.png", frames[i].time);
      frames[i].name = buf;
    }
  }
  std::map<std::string, long> seen;
  for (const auto& f : frames) {
    auto [it, fresh] = seen.emplace(f.name, f.line);
    if (!fresh)
      throw Error(o.frames.empty() ? o.trajectory : o.frames, f.line,
                  "frame name '" + f.name + "' repeats line " + std::to_string(it->second));
  }
}

// The frames to write: --frames' timestamps, else every keyframe, named by NameFrames.
std::vector<TimedName> ReadFrames(const Orb2ColmapOptions& o, const std::vector<StampedPose>& keys,
                                  const std::vector<std::string>& image_files,
                                  TrajectoryFormat fmt) {
  std::vector<TimedName> frames;
  if (!o.frames.empty()) {
    frames = ReadTimestamps(o.frames);
  } else {
    // Every pose is a frame, in time order; exact duplicates were merged by SortKeyframes.
    for (const auto& k : keys) frames.push_back({k.time, "", k.line});
  }
  NameFrames(o, image_files, fmt, frames);
  return frames;
}

// Poses that name their images (a COLMAP model, a NeRF transforms.json), and the camera they
// come with (none when a model has several).
struct NamedPoses {
  std::optional<Camera> camera;
  std::vector<TimedName> frames;  // time = order, name = the image's base name
  std::vector<Rigid3d> w2c;
};

NamedPoses ReadNamedPoses(const Orb2ColmapOptions& o, const std::vector<std::string>& image_files) {
  NamedPoses out;
  const fs::path p(o.trajectory);
  if (p.extension() == ".json") {
    const NerfScene scene = ReadNerfTransforms(o.trajectory);
    out.camera = scene.camera;
    // NeRF file paths often drop the extension ("./train/r_0"): match an --images file by stem.
    std::map<std::string, std::string> by_stem;
    for (const std::string& f : image_files) by_stem.emplace(fs::path(f).stem().string(), f);
    for (size_t i = 0; i < scene.frames.poses.size(); ++i) {
      std::string name = Basename(scene.frames.names[i]);
      if (fs::path(name).extension().empty() && by_stem.count(name)) name = by_stem[name];
      out.frames.push_back({static_cast<double>(i), name, 0});
      Rigid3d w2c = scene.frames.poses[i].pose.Inverse();
      w2c.q.normalize();
      out.w2c.push_back(w2c);
    }
  } else {
    const fs::path dir = fs::is_directory(p) ? p : p.parent_path();
    const Reconstruction model = ReadColmapModel(dir.empty() ? "." : dir.string());
    if (model.cameras.size() == 1)
      out.camera = model.cameras.begin()->second;
    else if (o.camera.empty() && o.orb_settings.empty() && o.kitti_calib.empty())
      throw UsageError(o.trajectory + ": the model has " + std::to_string(model.cameras.size()) +
                       " cameras: give one with --camera, --orb-settings or --kitti-calib");
    size_t i = 0;
    for (const ImageRecord* im : model.ImagesByName()) {
      out.frames.push_back({static_cast<double>(i++), im->name, 0});
      out.w2c.push_back(im->world_to_camera);
    }
  }
  if (out.frames.empty()) throw Error(o.trajectory, 0, "no posed image");
  std::map<std::string, size_t> seen;
  for (size_t i = 0; i < out.frames.size(); ++i)
    if (!seen.emplace(out.frames[i].name, i).second)
      throw Error(o.trajectory, 0, "image name '" + out.frames[i].name + "' repeats");
  return out;
}

struct Posed {
  const TimedName* frame;
  std::optional<Rigid3d> w2c;  // none: TRAJECTORY '-'
};

// Interpolates each frame's pose (world-to-camera); frames outside the keyframes' time span are
// dropped or clamped as --outside says. Throws when no frame is left.
std::vector<Posed> PoseFrames(const Orb2ColmapOptions& o, const std::vector<StampedPose>& keys,
                              const std::vector<TimedName>& frames, Orb2ColmapReport& rep) {
  const Outside outside = o.outside;
  std::vector<Posed> posed;
  for (const auto& f : frames) {
    bool inside = f.time >= keys.front().time && f.time <= keys.back().time;
    auto c2w = InterpolateCameraToWorld(keys, f.time, outside);
    if (!c2w) {
      ++rep.dropped;
      continue;
    }
    if (!inside) ++rep.clamped;
    Rigid3d w2c = c2w->Inverse();
    w2c.q.normalize();
    posed.push_back({&f, w2c});
  }
  if (posed.empty())
    throw Error(o.trajectory, 0, "no frame lies inside the pose time span (use --outside clamp?)");
  return posed;
}

// KITTI's rectified cameras differ by a translation only (ReadKittiCameraOffset): a pose of
// camera M becomes camera N's by adding tN − tM to its world-to-camera translation.
void MoveToKittiCamera(const Orb2ColmapOptions& o, TrajectoryFormat fmt, std::vector<Posed>& posed,
                       Orb2ColmapReport& rep) {
  rep.from_cam = KittiPosesCamera(o, fmt);
  rep.to_cam = o.kitti_cam;
  if (rep.from_cam == rep.to_cam) return;
  rep.offset = ReadKittiCameraOffset(o.kitti_calib, rep.to_cam) -
               ReadKittiCameraOffset(o.kitti_calib, rep.from_cam);
  for (Posed& p : posed) p.w2c->t += rep.offset;
}

// The model of the posed frames, images numbered from 1; with --database, the camera and the
// images (with their pose priors) go into the database too, and the model takes its ids.
Reconstruction BuildModel(const Orb2ColmapOptions& o, Camera cam, const std::vector<Posed>& posed) {
  std::unique_ptr<ColmapDatabase> db;
  std::map<std::string, std::pair<uint32_t, uint32_t>> db_images;
  uint32_t next_id = 1;
  if (!o.database.empty()) {
    db = std::make_unique<ColmapDatabase>(o.database);
    db_images = db->Images();
    for (const auto& [n, ids] : db_images) next_id = std::max(next_id, ids.first + 1);
    uint32_t cam_id = 0;
    for (const auto& p : posed) {
      auto it = db_images.find(p.frame->name);
      if (it != db_images.end()) {
        cam_id = it->second.second;
        break;
      }
    }
    db->Begin();
    if (cam_id)
      db->UpdateCamera(cam_id, cam);
    else
      cam_id = db->AddCamera(cam);
    cam.id = cam_id;
  }
  Reconstruction model;
  model.cameras[cam.id] = cam;
  uint32_t fallback_id = 1;
  for (const auto& p : posed) {
    ImageRecord im;
    im.camera_id = cam.id;
    im.name = p.frame->name;
    if (db) {
      auto it = db_images.find(im.name);
      uint32_t want = it != db_images.end() ? it->second.first : next_id++;
      im.id = db->UpsertImage(im.name, want, cam.id, p.w2c);
    } else {
      im.id = fallback_id++;
    }
    // Without poses the images are in the database only: the model holds the camera.
    if (!p.w2c) continue;
    im.world_to_camera = *p.w2c;
    model.images[im.id] = std::move(im);
  }
  if (db) db->Commit();
  return model;
}

}  // namespace

Orb2ColmapReport RunOrb2Colmap(const Orb2ColmapOptions& o) {
  o.Check();
  Orb2ColmapReport rep;
  const std::vector<std::string> image_files =
      o.images.empty() ? std::vector<std::string>() : ListImageFiles(o.images);
  Orb2ColmapOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, "orb2colmap", table, Inputs(o, image_files), fs::path());
  // The model files and the database are made together (the model takes the database's image
  // ids): one stale output remakes them all. A database another program changed since (COLMAP's
  // feature extraction) is stale too ("no record"), as it always was rewritten before.
  const std::vector<fs::path> outputs = Outputs(o);
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(o.outdir);  // a killed run's leftovers, even when all is up to date
  if (!stale) {
    rep.up_to_date = true;
    return rep;
  }
  std::vector<TimedName> frames;
  std::vector<Posed> posed;
  std::optional<NamedPoses> named;
  if (o.trajectory == kNoTrajectory) {
    if (image_files.empty()) throw Error(o.images, 0, "no images in the folder");
    for (size_t i = 0; i < image_files.size(); ++i)
      frames.push_back({static_cast<double>(i), image_files[i], 0});
    for (const TimedName& f : frames) posed.push_back({&f, std::nullopt});
  } else if (HasNamedPoses(o.trajectory)) {
    named = ReadNamedPoses(o, image_files);
    frames = named->frames;
    rep.keyframes = frames.size();
    for (size_t i = 0; i < frames.size(); ++i) posed.push_back({&frames[i], named->w2c[i]});
  } else {
    TrajectoryFormat fmt;
    std::vector<StampedPose> keys = ReadInputTrajectory(o, &fmt).poses;
    rep.reordered = SortKeyframes(keys, o.trajectory);
    rep.keyframes = keys.size();
    frames = ReadFrames(o, keys, image_files, fmt);
    // Poses first, so that nothing is written (model or database) when the input is unusable.
    posed = PoseFrames(o, keys, frames, rep);
    if (!o.kitti_calib.empty()) MoveToKittiCamera(o, fmt, posed, rep);
  }
  rep.frames = frames.size();
  Camera cam;
  if (named && o.camera.empty() && o.orb_settings.empty() && o.kitti_calib.empty()) {
    cam = *named->camera;
    cam.id = 1;
  } else {
    cam = ResolveCamera(o, image_files);
  }
  const Reconstruction model = BuildModel(o, cam, posed);
  if (o.binary)
    WriteColmapBinary(model, o.outdir);
  else
    WriteColmapText(model, o.outdir);
  for (const fs::path& p : outputs) ledger.Done(p);
  ledger.Write();
  rep.written = posed.size();
  return rep;
}

}  // namespace mvtm
