#include "sfmjoin.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/work.h"
#include "geometry/align.h"
#include "io/colmap_model.h"
#include "run/ledger.h"
#include "scene/upright.h"

namespace mvtm {

namespace fs = std::filesystem;

OptionTable DeclareOptions(SfmjoinOptions& o) {
  OptionTable t("sfmjoin");
  t.PositionalList("PATHS", &o.paths,
                   "MODEL... OUTDIR: COLMAP model folders of overlapping stretches of one drive, "
                   "in drive order (each sharing images with the ones before it), and the folder "
                   "for the joined model and join.tsv");
  t.Integer("--min-shared", &o.min_shared,
            "Fewest images a model must share with the models before it")
      .Range(2, 1e6);
  t.Real("--max-misfit", &o.max_misfit,
         "Largest RMS distance between a model's shared camera centres and the joined ones, "
         "after the fit, as a fraction of their extent (a broken stretch is an error)")
      .Range(0, 10, true);
  t.Flag("--rigid", &o.rigid,
         "The models are metric already (e.g. each made so by georef --camera-height): fit "
         "rotation and translation only");
  t.Flag("--binary", &o.binary, "Write cameras.bin, images.bin, points3D.bin");
  t.Flag("--force", &o.force, "Rewrite the model even when it is up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void SfmjoinOptions::Check() const {
  CheckDeclared(*this);
  if (paths.size() < 2)
    throw UsageError("expected MODEL... OUTDIR, got " + std::to_string(paths.size()) + " path");
  std::error_code ec;
  for (size_t i = 0; i + 1 < paths.size(); ++i) {
    if (fs::exists(paths.back()) && fs::equivalent(paths[i], paths.back(), ec))
      throw UsageError("OUTDIR must not be a MODEL (" + paths[i] + ")");
    for (size_t j = 0; j < i; ++j)
      if (fs::equivalent(paths[i], paths[j], ec)) throw UsageError(paths[i] + " is given twice");
  }
}

namespace {

struct Part {
  std::string dir;
  Reconstruction rec;
  std::vector<std::string> names;          // name order
  std::map<std::string, size_t> position;  // name → index in names
  std::map<uint32_t, std::string> name_of;
  std::set<std::string> outliers;  // shared images whose pose here disagreed with the join
};

Part ReadPart(const std::string& dir) {
  Part p;
  p.dir = dir;
  p.rec = ReadColmapModel(dir);
  for (const ImageRecord* im : p.rec.ImagesByName()) {
    if (p.position.count(im->name))
      throw Error(dir + ": image " + im->name + " is in the model twice");
    p.position[im->name] = p.names.size();
    p.names.push_back(im->name);
    p.name_of[im->id] = im->name;
  }
  if (p.names.empty()) throw Error(dir + ": the model has no registered image");
  return p;
}

// Places part k in the joined frame by the images it shares with the parts before it (`placed`:
// name → joined world-to-camera pose).
SfmjoinModelReport Place(Part& part, const std::map<std::string, Rigid3d>& placed,
                         const SfmjoinOptions& o) {
  SfmjoinModelReport r;
  r.model = part.dir;
  r.images = part.names.size();
  std::vector<Rigid3d> src, dst;
  for (const std::string& name : part.names) {
    auto it = placed.find(name);
    if (it == placed.end()) continue;
    src.push_back(part.rec.FindImage(name)->world_to_camera);
    dst.push_back(it->second);
  }
  r.shared = src.size();
  if (src.size() < o.min_shared)
    throw Error(part.dir + ": shares " + std::to_string(src.size()) +
                " images with the models before it: need " + std::to_string(o.min_shared) +
                " (overlap the stretches by more images, or list the models in drive order)");
  PoseAlignment a;
  try {
    a = AlignPoses(src, dst, !o.rigid);
  } catch (const Error& e) {
    throw Error(part.dir + ": " + e.what());
  }
  r.inliers = a.inliers;
  for (size_t i = 0, j = 0; i < part.names.size(); ++i)
    if (placed.count(part.names[i]) && !a.inlier[j++]) part.outliers.insert(part.names[i]);
  r.scale = a.T.scale;
  r.rotation_rms_deg = a.rotation_rms_deg;
  r.centre_rms = a.centre_rms;
  r.misfit = a.extent > 0 ? a.centre_rms / a.extent : 0;
  if (r.misfit > o.max_misfit)
    throw Error(part.dir + ": its shared cameras misfit the models before it by " +
                std::to_string(100 * r.misfit) + " % of their extent (over --max-misfit " +
                std::to_string(100 * o.max_misfit) + " %): a broken stretch?");
  TransformModel(part.rec, a.T);
  return r;
}

// The part each image is kept from: the one in which it lies farthest from the ends of the
// stretch (name order), the earlier on a tie; never one whose pose of it was an outlier of its
// placement.
std::map<std::string, size_t> Owners(const std::vector<Part>& parts) {
  std::map<std::string, std::pair<size_t, size_t>> best;  // name → (depth, part)
  for (size_t k = 0; k < parts.size(); ++k)
    for (const auto& [name, pos] : parts[k].position) {
      if (parts[k].outliers.count(name)) continue;
      const size_t depth = std::min(pos, parts[k].names.size() - 1 - pos);
      auto it = best.find(name);
      if (it == best.end() || depth > it->second.first) best[name] = {depth, k};
    }
  std::map<std::string, size_t> owner;
  for (const auto& [name, b] : best) owner[name] = b.second;
  return owner;
}

// Image ids: kept when every name has one id in every part and no id two names; else 1, 2, ...
// in name order.
std::map<std::string, uint32_t> ImageIds(const std::vector<Part>& parts,
                                         const std::map<std::string, size_t>& owner) {
  std::map<std::string, std::set<uint32_t>> ids;
  std::map<uint32_t, std::set<std::string>> names;
  for (const Part& p : parts)
    for (const auto& [id, name] : p.name_of) ids[name].insert(id), names[id].insert(name);
  bool keep = true;
  for (const auto& [name, s] : ids) keep = keep && s.size() == 1;
  for (const auto& [id, s] : names) keep = keep && s.size() == 1;
  std::map<std::string, uint32_t> out;
  uint32_t next = 1;
  for (const auto& [name, k] : owner) out[name] = keep ? *ids[name].begin() : next++;
  return out;
}

// Camera ids of the cameras the kept images use: a part's camera equal (model, size, parameters)
// to one already joined is that one; else it keeps its id when free, or takes the next.
std::map<std::pair<size_t, uint32_t>, uint32_t> JoinCameras(
    const std::vector<Part>& parts, const std::map<std::string, size_t>& owner,
    Reconstruction& out) {
  std::map<std::pair<size_t, uint32_t>, uint32_t> map;
  for (size_t k = 0; k < parts.size(); ++k) {
    std::set<uint32_t> used;
    for (const auto& [id, im] : parts[k].rec.images)
      if (owner.at(im.name) == k) used.insert(im.camera_id);
    for (uint32_t id : used) {
      const Camera& cam = parts[k].rec.cameras.at(id);
      uint32_t found = 0;
      for (const auto& [oid, oc] : out.cameras)
        if (oc.model == cam.model && oc.width == cam.width && oc.height == cam.height &&
            oc.params == cam.params)
          found = oid;
      if (!found) {
        found = out.cameras.count(id) ? out.cameras.rbegin()->first + 1 : id;
        out.cameras[found] = cam;
        out.cameras[found].id = found;
      }
      map[{k, id}] = found;
    }
  }
  return map;
}

Reconstruction Join(const std::vector<Part>& parts, std::vector<SfmjoinModelReport>& reports) {
  Reconstruction out;
  const auto owner = Owners(parts);
  const auto image_id = ImageIds(parts, owner);
  const auto camera_id = JoinCameras(parts, owner, out);
  uint64_t next_point = 1;
  for (size_t k = 0; k < parts.size(); ++k) {
    const Part& p = parts[k];
    auto owned = [&](uint32_t id) { return owner.at(p.name_of.at(id)) == k; };
    std::map<uint64_t, uint64_t> point_id;
    for (const auto& [id, pt] : p.rec.points3D) {
      Point3D q = pt;
      q.track.clear();
      for (const TrackElement& e : pt.track)
        if (owned(e.image_id))
          q.track.push_back({image_id.at(p.name_of.at(e.image_id)), e.point2D_idx});
      if (q.track.size() < 2) continue;
      q.id = next_point++;
      point_id[id] = q.id;
      out.points3D[q.id] = std::move(q);
    }
    for (const auto& [id, im] : p.rec.images) {
      if (!owned(id)) continue;
      ImageRecord r = im;
      r.id = image_id.at(im.name);
      r.camera_id = camera_id.at({k, im.camera_id});
      for (Point2D& x : r.points2D) {
        auto it = point_id.find(x.point3D_id);
        x.point3D_id = it == point_id.end() ? kInvalidPoint3DId : it->second;
      }
      out.images[r.id] = std::move(r);
      ++reports[k].kept_images;
    }
    reports[k].kept_points = point_id.size();
  }
  return out;
}

void WriteTable(const fs::path& path, const std::vector<SfmjoinModelReport>& models) {
  WriteTextAtomic(path, [&](std::ostream& out) {
    out << "model\timages\tshared\tinliers\tscale\trotation_rms_deg\tcentre_rms\tmisfit\t"
           "kept_images\tkept_points\n";
    char line[256];
    for (const auto& m : models) {
      std::snprintf(line, sizeof line, "\t%zu\t%zu\t%zu\t%.9g\t%.6g\t%.6g\t%.6g\t%zu\t%zu\n",
                    m.images, m.shared, m.inliers, m.scale, m.rotation_rms_deg, m.centre_rms,
                    m.misfit, m.kept_images, m.kept_points);
      out << m.model << line;
    }
  });
}

}  // namespace

SfmjoinReport RunSfmjoin(const SfmjoinOptions& o) {
  o.Check();
  SfmjoinReport rep;
  const fs::path outdir = o.paths.back();
  std::vector<fs::path> inputs;
  for (size_t i = 0; i + 1 < o.paths.size(); ++i)
    for (const std::string& f : ColmapModelFiles(o.paths[i])) inputs.emplace_back(f);
  SfmjoinOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(outdir, "sfmjoin", table, inputs, fs::path());
  std::vector<fs::path> outputs;
  for (const auto& f : ColmapModelFileNames(o.binary)) outputs.push_back(outdir / f);
  outputs.push_back(outdir / "join.tsv");
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(outdir);
  if (!stale) {
    rep.up_to_date = true;
    return rep;
  }
  std::vector<Part> parts;
  std::map<std::string, Rigid3d> placed;
  for (size_t i = 0; i + 1 < o.paths.size(); ++i) {
    parts.push_back(ReadPart(o.paths[i]));
    Part& p = parts.back();
    if (i == 0) {
      rep.models.push_back({p.dir, p.names.size(), 0, 0, 0, 0, 1, 0, 0, 0});
    } else {
      rep.models.push_back(Place(p, placed, o));
    }
    for (const std::string& name : p.names)
      placed.emplace(name, p.rec.FindImage(name)->world_to_camera);
  }
  const Reconstruction joined = Join(parts, rep.models);
  CreateFolder(outdir);
  if (o.binary)
    WriteColmapBinary(joined, outdir.string());
  else
    WriteColmapText(joined, outdir.string());
  WriteTable(outdir / "join.tsv", rep.models);
  for (const fs::path& p : outputs) ledger.Done(p);
  ledger.Write();
  rep.images = joined.images.size();
  rep.points = joined.points3D.size();
  rep.cameras = joined.cameras.size();
  return rep;
}

}  // namespace mvtm
