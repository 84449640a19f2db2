#include "orb2colmap.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "image/folder.h"
#include "image/image.h"
#include "io/colmap_database.h"
#include "io/colmap_model.h"

namespace mvtm {

namespace fs = std::filesystem;

void Orb2ColmapOptions::Check() const {
  int sources = !camera.empty() + !orb_settings.empty() + !kitti_calib.empty();
  if (sources != 1)
    throw UsageError("give exactly one of --camera, --orb-settings, --kitti-calib");
  CheckChoice(outside, kOrbOutside, "--outside");
  CheckChoice(input_format, kOrbInputFormats, "--input-format");
  if (kitti_cam < 0 || kitti_cam > 3) throw UsageError("--kitti-cam: must be 0..3");
  if (!images.empty() && !fs::is_directory(images))
    throw UsageError("--images: '" + images + "' is not a folder");
}

namespace {

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

}  // namespace

Orb2ColmapReport RunOrb2Colmap(const Orb2ColmapOptions& o) {
  o.Check();
  Orb2ColmapReport rep;
  if (!o.force && o.database.empty()) {
    const char* ext = o.binary ? ".bin" : ".txt";
    std::vector<fs::path> inputs;
    for (const std::string& in : {o.trajectory, o.trajectory_times, o.frames, o.orb_settings, o.kitti_calib, o.images})
      if (!in.empty()) inputs.emplace_back(in);
    bool fresh = true;
    for (const char* f : {"cameras", "images", "points3D"})
      fresh = fresh && IsUpToDate(fs::path(o.outdir) / (std::string(f) + ext), inputs);
    if (fresh) {
      rep.up_to_date = true;
      return rep;
    }
  }

  Trajectory traj;
  TrajectoryFormat fmt = o.input_format == "tum"     ? TrajectoryFormat::kTum
                         : o.input_format == "kitti" ? TrajectoryFormat::kKitti
                                                     : DetectTrajectoryFormat(o.trajectory);
  if (fmt == TrajectoryFormat::kKitti) traj = ReadKittiPoses(o.trajectory, o.trajectory_times);
  else if (fmt == TrajectoryFormat::kTum) traj = ReadTum(o.trajectory);
  else throw Error(o.trajectory, 0, "a COLMAP model is already a COLMAP model: nothing to convert");
  std::vector<StampedPose> keys = traj.poses;
  rep.reordered = SortKeyframes(keys, o.trajectory);
  rep.keyframes = keys.size();

  // Frames: timestamps and names.
  std::vector<std::string> image_files;
  if (!o.images.empty()) image_files = ListImageFiles(o.images);
  std::vector<TimedName> frames;
  if (!o.frames.empty()) {
    frames = ReadTimestamps(o.frames);
  } else {
    // Every pose is a frame, in time order; exact duplicates were merged by SortKeyframes.
    for (const auto& k : keys) frames.push_back({k.time, "", k.line});
  }
  bool named = std::all_of(frames.begin(), frames.end(), [](const TimedName& f) { return !f.name.empty(); });
  if (!named) {
    if (!image_files.empty()) {
      if (image_files.size() != frames.size())
        throw Error(o.images, 0,
                    std::to_string(image_files.size()) + " images for " + std::to_string(frames.size()) +
                        " frame timestamps" + (o.frames.empty() ? "" : " in " + o.frames));
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
  } else {
    for (auto& f : frames) f.name = Basename(f.name);
  }
  {
    std::map<std::string, long> seen;
    for (const auto& f : frames) {
      auto [it, fresh] = seen.emplace(f.name, f.line);
      if (!fresh)
        throw Error(o.frames.empty() ? o.trajectory : o.frames, f.line,
                    "frame name '" + f.name + "' repeats line " + std::to_string(it->second));
    }
  }
  rep.frames = frames.size();

  Camera cam = ResolveCamera(o, image_files);
  Reconstruction model;
  Outside outside = o.outside == "clamp" ? Outside::kClamp : Outside::kDrop;

  // Poses first, so that nothing is written (model or database) when the input is unusable.
  struct Posed {
    const TimedName* frame;
    Rigid3d w2c;
  };
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
    if (cam_id) db->UpdateCamera(cam_id, cam);
    else cam_id = db->AddCamera(cam);
    cam.id = cam_id;
  }
  model.cameras[cam.id] = cam;

  uint32_t fallback_id = 1;
  for (const auto& p : posed) {
    ImageRecord im;
    im.camera_id = cam.id;
    im.name = p.frame->name;
    im.world_to_camera = p.w2c;
    if (db) {
      auto it = db_images.find(im.name);
      uint32_t want = it != db_images.end() ? it->second.first : next_id++;
      im.id = db->UpsertImage(im.name, want, cam.id, im.world_to_camera);
    } else {
      im.id = fallback_id++;
    }
    model.images[im.id] = std::move(im);
  }
  if (db) db->Commit();
  if (o.binary) WriteColmapBinary(model, o.outdir);
  else WriteColmapText(model, o.outdir);
  rep.written = model.images.size();
  return rep;
}

}  // namespace mvtm
