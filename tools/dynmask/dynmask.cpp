#include "dynmask.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/stats.h"
#include "cli/progress.h"
#include "image/image.h"
#include "index/view_selection.h"
#include "io/colmap_model.h"
#include "io/mesh_io.h"
#include "io/tracks.h"
#include "raycast/mesh_raycaster.h"
#include "run/ledger.h"
#include "stereo/neighbours.h"
#include "track/labels.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace fs = std::filesystem;

namespace {

// A folder option that is given must name a folder (a misspelt one would silently add nothing).
void RequireFolder(const char* flag, const std::string& dir) {
  if (!dir.empty() && !fs::is_directory(dir))
    throw UsageError(std::string(flag) + ": no such folder: " + dir);
}

// The options that turn probability maps into blobs (the blob tests of the maps use them too).
void DeclareMaskOptions(OptionTable& t, DynmaskOptions& o) {
  t.Real("--probability", &o.mask.probability, "Probability at or above which a pixel is masked")
      .Range(0, 1, true, true)
      .Alternative("0.7");
  t.Integer("--open", &o.mask.open, "Opening radius (working pixels): removes specks").Range(0, 50);
  t.Real("--close", &o.mask.close, "Closing radius in image widths (joins a vehicle's parts)")
      .Range(0, 0.2);
  t.Real("--min-area", &o.mask.min_area, "Blobs below this share of the image are dropped")
      .Range(0, 1, false, true);
}

// The options that only the masks depend on, not the probability maps: tracking, gap filling,
// masks OR-ed in, labels confirmed.
void DeclareTrackingOptions(OptionTable& t, DynmaskOptions& o) {
  t.Real("--max-jump", &o.track.max_jump,
         "Tracking: largest distance from a track's predicted centroid to its blob (pixels; "
         "0: a quarter of the image width)")
      .AtLeast(0);
  DeclareTrackOptions(t, o.track);
  t.Real("--gap-support", &o.gap_support,
         "Tracking: a frame's gap filled by interpolation is kept only when its pixels outside "
         "that frame's detected blobs have a mean probability of at least P (0: every gap "
         "filled, as segtrack fills them)")
      .Range(0, 1)
      .Alternative("0");
  t.Text("--also", &o.also, "Folder of masks (NAME.png) OR-ed into every output mask")
      .Dir()
      .Check([&o] { RequireFolder("--also", o.also); });
  t.Text("--labels", &o.labels,
         "Folder of label images (NAME.png, class ids): the masks are the blobs of --classes "
         "that the geometry confirms move, whole")
      .Dir()
      .Check([&o] { RequireFolder("--labels", o.labels); });
  t.Text("--classes", &o.classes, "With --labels: the class ids to confirm, comma-separated")
      .Alternative("8")
      .Check([&o] { LabelDecoder::ParseClasses(o.classes); });
  t.Real("--confirm", &o.confirm,
         "With --labels: mean probability over a label blob at which it is confirmed")
      .Range(0, 1)
      .Alternative("0.5");
}

// The tests on what the evidence finds: blobs on the ground, standing up, pixels unexplained.
void DeclareStandingOptions(OptionTable& t, DynmaskOptions& o) {
  t.Real("--grounded", &o.grounded,
         "Keep only blobs that stand on the ground: a foot within F x the camera's height of "
         "the road under it (0: keep every blob)")
      .Range(0, 10)
      .Alternative("0");
  t.Real("--min-height", &o.min_height,
         "Keep only blobs that rise H x the camera's height above the ground at their foot: "
         "vehicles, cyclists, pedestrians; not wet patches or shadows in the road (0: off)")
      .Range(0, 10)
      .Alternative("0");
  t.Real("--seen-tolerance", &o.seen_tolerance,
         "Pixels where densify's depth of the photo is the static depth within T (relative) "
         "are static: the photo saw the static surface there (0: off)")
      .Range(0, 1, false, true)
      .Alternative("0");
  t.Real("--occludes", &o.occludes,
         "Keep only blobs that hide something: at least S of their upper pixels have a static "
         "depth beyond their foot's (by --occlusion-gap) or none; not doors, shop fronts or "
         "stretches of a facade the mesh has wrong (0: off)")
      .Range(0, 1)
      .Alternative("0");
  t.Real("--occlusion-gap", &o.occlusion_gap,
         "With --occludes: how far beyond the foot (relative to its depth) a static surface "
         "counts as behind the blob")
      .Range(0, 10, true, false)
      .Alternative("0.5");
  t.Real("--complete", &o.complete,
         "Complete each blob with GrabCut seeded by it (its colours against its surroundings'), "
         "growing by at most G x its area, never into pixels the photo's own depth explains "
         "(within --seen-tolerance, else 0.05): a cyclist's body against the far background, a "
         "car's panels of the road's colour (0: off; needs densify's maps and the mesh)")
      .Range(0, 100)
      .Alternative("0");
  t.Real("--driven", &o.driven.half_width,
         "Surfaces standing where a drive's car passed are not static: pixels the photo's own "
         "depth and the mesh put in one place (see --driven-agree) within W x the camera's "
         "height of a drive's path, across it and beside it (not beyond its first or last "
         "photo), between --driven-above and --driven-below x the camera's height above the "
         "road: a car parked in a lane another drive took, a vehicle waiting ahead (0: off; "
         "needs densify's maps and the mesh)")
      .Range(0, 10)
      .Alternative("0");
  t.Real("--driven-above", &o.driven.above,
         "With --driven: the lowest surface counted, x the camera's height above the road (not "
         "kerbs, speed bumps)")
      .Range(0, 10)
      .Alternative("0.3");
  t.Real("--driven-below", &o.driven.below,
         "With --driven: the highest surface counted, x the camera's height above the road (a "
         "car's roof; not branches or signs over the road)")
      .Range(0, 10, true, false)
      .Alternative("2");
  t.Real("--driven-agree", &o.driven.agree,
         "With --driven: a pixel counts where densify's depth of the photo is the mesh's within "
         "this (relative): a surface several photos saw in one place, not one photo's stereo "
         "mistake")
      .Range(0, 1, true, true)
      .Alternative("0.2");
  t.Flag("--no-driven-grow", &o.no_driven_grow,
         "With --driven: mark only the pixels densify's depth puts in the space, not the rest "
         "of their surface in the mesh (by default the mesh's surface in the space joined to a "
         "marked blob is marked too: a dark body or a window densify found no depth for)");
  t.Real("--max-fill", &o.max_fill,
         "In a blob more than S of whose pixels see a corridor wall that roadmesh --dense put "
         "behind a hole of the fused facades (a guessed depth), those pixels are cleared (1: off)")
      .Range(0, 1)
      .Alternative("1");
}

// The evidence's options (libcore/dynamic's DynamicOptions).
void DeclareEvidenceOptions(OptionTable& t, DynmaskOptions& o) {
  t.Real("--threshold", &o.evidence.threshold,
         "Photometric residual (luma 0..1) at which a pixel is 50 % not static")
      .Above(0)
      .Alternative("0.08");
  t.Flag("--no-colour", &o.no_colour,
         "Photometric residual of the luma only (by default of each colour channel, each with its "
         "own exposure gain: a blue car on a grey road of its brightness)");
  t.Real("--colour-threshold", &o.evidence.colour_threshold,
         "With colour: a channel's photometric residual (0..1) at which a pixel is 50 % not static")
      .Above(0)
      .Alternative("0.05");
  t.Flag("--no-flow", &o.no_flow, "Photometric evidence only (no optical flow against the warp)");
  t.Real("--flow-threshold", &o.evidence.flow_threshold,
         "Residual flow (working pixels) at which a pixel is 50 % not static")
      .Above(0)
      .Alternative("4");
  t.Real("--flow-relative", &o.evidence.flow_relative,
         "... or this share of the pixel's rigid motion between the photos, when larger (0: off)")
      .Range(0, 10, false, true)
      .Alternative("0.1");
  t.Real("--quantile", &o.evidence.quantile,
         "Quantile of the residuals over the neighbours (0: the smallest; 0.5: the median)")
      .Range(0, 1)
      .Alternative("0.25");
  t.Real("--depth-tolerance", &o.evidence.depth_tolerance,
         "Relative depth difference that hides a point in a neighbour")
      .Range(0, 1, true, true);
  t.Integer("--slack", &o.evidence.slack, "Misalignment forgiven, working pixels").Range(0, 5);
  t.Integer("--window", &o.evidence.window, "Box averaging the photometric residual (odd)")
      .Range(1, 31)
      .Alternative("7")
      .Check([&o] {
        if (o.evidence.window % 2 == 0) throw UsageError("--window: must be odd, 1..31");
      });
  t.Real("--segments", &o.evidence.segments,
         "Regions evidence spreads over: Felzenszwalb's k (larger: larger regions; 0: off)")
      .AtLeast(0)
      .Alternative("0");
  t.Real("--texture", &o.evidence.texture,
         "Luma gradient per pixel at which a pixel's own evidence counts fully")
      .Above(0);
  t.Real("--partners-veto", &o.evidence.partners_veto,
         "Where the partners (other drives) saw the pixel's static point as the photo does "
         "(residual under F x --threshold), the motion its own neighbours show there is light "
         "that changes with the viewpoint (a reflection in a window or on a wet road): its flow "
         "residual is dropped (0: off)")
      .Range(0, 10);
  t.Real("--ahead-veto", &o.evidence.ahead_veto,
         "Photos with partners also get --ahead photos of their own drive farther along (with "
         "none farther along, such as a drive's last photo: the --ahead photos just behind it, "
         "which veto only where their own pixel disagrees too: a lead car keeping its place): "
         "where one saw the pixel's static point as the photo does (residual under F x "
         "--threshold), the partners' evidence there is the other drive's own traffic and is "
         "dropped (0: off)")
      .Range(0, 10)
      .Alternative("0");
  t.Real("--region-depth", &o.evidence.region_depth,
         "A pixel without static depth (sky, or beyond the reconstruction) takes its region's "
         "probability when more than this share of the region has depth: a vehicle's top "
         "against the sky (1: never)")
      .Range(0, 1)
      .Alternative("1");
}

}  // namespace

OptionTable DeclareOptions(DynmaskOptions& o) {
  OptionTable t("dynmask");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/, images/, mesh.ply or stereo/)")
      .Dir();
  t.Integer("--max-width", &o.max_width,
            "Working resolution: images wider than W pixels are scaled down to W (64..16384)")
      .Range(64, 16384)
      .Alternative("1241");
  t.Integer("--neighbours", &o.neighbours, "Photos of the same drive each photo is checked against")
      .Range(1, 16)
      .Alternative("2");
  t.Integer("--partners", &o.partners,
            "Photos of the other drives of the road each photo is also checked against: a "
            "vehicle parked in one drive only (0: its own drive only)")
      .Range(0, 16)
      .Alternative("0");
  t.Integer("--partners-ahead", &o.partners_ahead,
            "Photos of the other drives farther along the road, at N depths up to the photo's "
            "far surfaces: they see the far road in front of a vehicle driving ahead of their "
            "camera; compared at the pixels beyond them only (0: none)")
      .Range(0, 8)
      .Alternative("0");
  t.Integer("--ahead", &o.ahead,
            "Photos of the same drive farther along the road, at N depths up to the photo's far "
            "surfaces: they see the road in front of a vehicle driving ahead at the camera's "
            "speed; compared at the pixels at least 1.5 times their depth only; a cue for photos "
            "without partners of another drive, a veto of the partners' evidence for the others "
            "(see --ahead-veto; with none farther along: the N photos just behind, at every "
            "pixel) (0: none)")
      .Range(0, 8)
      .Alternative("0");
  t.Real("--ahead-min-share", &o.ahead_min_share,
         "A photo of the same drive farther along stands for a depth (k of N+1 parts of the "
         "photo's far surfaces); the nearest to it is left out when nearer than F x that depth "
         "(towards the drive's end: nearer photos see less of the road a vehicle covers)")
      .Range(0, 1)
      .Alternative("0.5");
  t.Real("--min-baseline", &o.min_baseline,
         "Nearest neighbour allowed, in median camera spacings (larger: more parallax)")
      .Range(0, 10)
      .Alternative("1.5");
  DeclareStandingOptions(t, o);
  t.Integer("--passes", &o.passes,
            "2: a second pass leaves out the neighbours' and partners' pixels inside their own "
            "first pass's blobs (the road a vehicle covers there); 1: one pass")
      .Range(1, 2);
  t.Choice("--depth", &o.depth,
           {{DepthSource::kAuto, "auto"},
            {DepthSource::kMesh, "mesh"},
            {DepthSource::kStereo, "stereo"}},
           "Static depth: the mesh ray-cast, densify's maps, or auto (the mesh, else the maps)");
  t.Text("--mesh", &o.mesh,
         "The mesh to ray-cast (default: dynmask-mesh.ply, the workspace's mesh as dynmask's "
         "first run found it, vehicles and all: roadmesh rebuilds mesh.ply without the masked "
         "pixels afterwards)")
      .File()
      .Check([&o] {
        if (!o.mesh.empty() && !fs::is_regular_file(o.mesh))
          throw UsageError("--mesh: no such file: " + o.mesh);
      });
  DeclareEvidenceOptions(t, o);
  DeclareMaskOptions(t, o);
  DeclareTrackingOptions(t, o);
  DeclareWorkOptions(t, o, "images", "in name order",
                     "Recompute probability maps and masks even when they are up to date");
  return t;
}

void DynmaskOptions::Check() const {
  CheckDeclared(*this);
  if (driven.half_width > 0 && !(driven.below > driven.above))
    throw UsageError("--driven-below: must be above --driven-above");
  if (!mesh.empty() && depth == DepthSource::kStereo)
    throw UsageError("--mesh: a mesh is not read with --depth stereo");
  evidence.Check();
  mask.Check();
  TrackOptions t = track;
  if (t.max_jump == 0) t.max_jump = 1;  // resolved per drive from the image width
  t.Check();
}

namespace {

using Clock = std::chrono::steady_clock;

// The model, its images by name, their drives (PassOf: the file name before the first '_') and
// working cameras.
struct Scene {
  Reconstruction rec;
  std::vector<const ImageRecord*> images;
  std::vector<Camera> full, work;
  std::map<std::string, std::vector<size_t>> drives;  // PassOf → its images, in name order
  Eigen::Vector3d up = Eigen::Vector3d::Zero();       // the drive's up (unit, world)
  std::vector<DrivenPath> paths;                      // DrivenPaths: where the drives' cars went
};

Scene LoadScene(const Workspace& ws, int max_width) {
  Scene s;
  s.rec = ReadColmapModel(ws.SparseDir().string());
  s.images = s.rec.ImagesByName();
  for (const ImageRecord* im : s.images) {
    const Camera& c = s.rec.cameras.at(im->camera_id);
    c.RequireUndistorted();
    s.full.push_back(c);
    const double f = std::min(1.0, double(max_width) / double(c.width));
    s.work.push_back(f == 1.0
                         ? c
                         : c.Scaled(std::max<uint64_t>(8, uint64_t(std::lround(c.width * f))),
                                    std::max<uint64_t>(8, uint64_t(std::lround(c.height * f)))));
    s.up += im->world_to_camera.Up();
    s.drives[PassOf(im->name)].push_back(s.full.size() - 1);
  }
  if (s.up.norm() > 0) s.up.normalize();
  return s;
}

// Neighbours of every image among the images of its own drive (stereo/neighbours.h's choice:
// nearest centres on both sides, enough baseline, similar viewing direction).
std::vector<std::vector<size_t>> ChooseNeighbours(const Scene& s, int count, double min_base) {
  std::vector<std::vector<size_t>> out(s.images.size());
  NeighbourOptions no;
  no.count = count;
  no.min_baseline = min_base;
  for (const auto& [name, idx] : s.drives) {
    std::vector<Rigid3d> w2c;
    std::vector<Camera> cams;
    for (size_t i : idx) w2c.push_back(s.images[i]->world_to_camera), cams.push_back(s.work[i]);
    if (idx.size() < 2) continue;
    const StereoNeighbourFinder finder(w2c, cams, no);
    for (size_t k = 0; k < idx.size(); ++k)
      for (size_t j : finder.Select(k, {})) out[idx[k]].push_back(idx[j]);
  }
  return out;
}

// Median distance between consecutive camera centres of each drive.
std::map<std::string, double> DriveSpacings(const Scene& s) {
  std::map<std::string, double> out;
  for (const auto& [name, idx] : s.drives) {
    std::vector<Rigid3d> w2c;
    for (size_t i : idx) w2c.push_back(s.images[i]->world_to_camera);
    out[name] = MedianSpacing(w2c);
  }
  return out;
}

// The camera centres and viewing directions of the other drives' photos, made once per drive.
struct OtherDrives {
  std::vector<size_t> images;           // indices into s.images
  std::vector<Eigen::Vector3d> centre;  // their camera centres
  std::vector<Eigen::Vector3d> way;     // their viewing directions

  void Add(const Scene& s, size_t j) {
    const Rigid3d& w2c = s.images[j]->world_to_camera;
    images.push_back(j), centre.push_back(w2c.Centre()), way.push_back(w2c.ViewDirection());
  }
};

// Partners farther along the road (`count` of them): for k = 1..count, the photo of another
// drive looking within 45 degrees of the image's way whose centre lies nearest to the depth
// k / (count + 1) of its far surfaces (the 90th percentile of the depths of the model's points
// it observes) in front of it, with that depth: it is compared at the image's pixels beyond it
// only (nearer ones are behind it). A vehicle driving ahead of the other drive's camera, at its
// speed, hides a cone of the far road in the nearest partners of every photo (and its own
// drive's photos cannot see it move); a photo of that drive taken nearer to that far road, at
// one of several distances, sees it in front of the vehicle. A pick nearer than `min_share` of
// the depth it stands for is left out (the drive ends before it); a photo picked for two depths
// is taken once.
std::vector<std::pair<size_t, double>> PartnersAhead(const Scene& s, size_t i,
                                                     const OtherDrives& others, int count,
                                                     double min_share = 0) {
  std::vector<std::pair<size_t, double>> out;
  if (count <= 0) return out;
  const ImageRecord& im = *s.images[i];
  std::vector<double> z;
  for (const Point2D& p : im.points2D) {
    const auto it = s.rec.points3D.find(p.point3D_id);
    if (it == s.rec.points3D.end()) continue;
    const double d = (im.world_to_camera * it->second.xyz).z();
    if (d > 0 && std::isfinite(d)) z.push_back(d);
  }
  if (z.size() < 8) return out;
  std::sort(z.begin(), z.end());
  const double p90 = z[size_t(0.9 * double(z.size() - 1))];
  // The candidates' depths in front of the image, once: (depth, index into s.images).
  const Eigen::Vector3d v = im.world_to_camera.ViewDirection();
  std::vector<std::pair<double, size_t>> ahead;
  for (size_t j = 0; j < others.images.size(); ++j) {
    const double zj = (im.world_to_camera * others.centre[j]).z();
    if (others.way[j].dot(v) >= std::sqrt(0.5) && zj > 0) ahead.emplace_back(zj, others.images[j]);
  }
  if (ahead.empty()) return out;
  for (int k = 1; k <= count; ++k) {
    const double want = p90 * k / (count + 1);
    const auto& [zj, j] =
        *std::min_element(ahead.begin(), ahead.end(), [&](const auto& a, const auto& b) {
          return std::abs(a.first - want) < std::abs(b.first - want);
        });
    if (zj < min_share * want) continue;
    if (std::none_of(out.begin(), out.end(), [&](const auto& o) { return o.first == j; }))
      out.emplace_back(j, zj);
  }
  return out;
}

// Each image's partners and, for each, the static depth it compares from (0: all pixels; a
// partner farther along the road: the pixels beyond its own centre's depth).
struct Partners {
  std::vector<std::vector<size_t>> images;
  std::vector<std::vector<double>> beyond;  // parallel to images
};

// Partners of every image among the images of the other drives: the nearest centres looking the
// same way (index/view_selection.h, the projector rule: within 45°, one just behind preferred),
// no farther than 3 camera spacings (beyond, a photo of another place), then the `ahead`
// partners farther along the road (PartnersAhead), each once. The spacing is the larger of the
// image's own drive's median and the median over the road's drives, so a drive of one photo, or
// one that mostly stood still, still has partners. `count` 0: none at all.
Partners ChoosePartners(const Scene& s, int count, int ahead) {
  Partners p{std::vector<std::vector<size_t>>(s.images.size()),
             std::vector<std::vector<double>>(s.images.size())};
  auto& out = p.images;
  if (count <= 0 || s.drives.size() < 2) return p;
  ViewSelectionOptions vo;
  vo.k = size_t(count);
  const std::map<std::string, double> spacing = DriveSpacings(s);
  std::vector<double> moving;
  for (const auto& [name, d] : spacing)
    if (d > 0) moving.push_back(d);
  const double road = moving.empty() ? 0 : Median(moving);
  for (const auto& [name, idx] : s.drives) {
    std::vector<Rigid3d> others;
    OtherDrives od;
    for (const auto& [other, jdx] : s.drives)
      if (other != name)
        for (size_t j : jdx) others.push_back(s.images[j]->world_to_camera), od.Add(s, j);
    const double reach = 3 * std::max(spacing.at(name), road);
    for (size_t i : idx) {
      for (const Candidate& c : SelectViews(s.images[i]->world_to_camera, others, vo))
        if (c.distance <= reach) out[i].push_back(od.images[c.index]);
      p.beyond[i].assign(out[i].size(), 0.0);
      for (const auto& [j, z] : PartnersAhead(s, i, od, ahead))
        if (std::find(out[i].begin(), out[i].end(), j) == out[i].end())
          out[i].push_back(j), p.beyond[i].push_back(z);
    }
  }
  return p;
}

// A photo of the drive farther along is compared at the pixels whose static depth is at least
// this many times its own centre's: nearer ones it sees from too close, where a small error of
// the static depth moves them far in it (KITTI 01 from its photos: a band along the far road's
// edge masked with 1; CamVid 0016E5's cyclists found as well with 1.5, half as well with 2).
constexpr double kAheadReach = 1.5;

// Photos of each image's own drive farther along the road (PartnersAhead over the drive's own
// photos), each at least `min_share` as far as the depth it stands for (nearer picks only
// towards the drive's end: CamVid 0016E5's last 18 photos had none at 0.5, and showed almost no
// evidence; 0.1 took the drive's last photos for them): a vehicle driving ahead of the
// camera at its speed keeps its place in the photos (its neighbours cannot see it move), but a
// photo taken metres farther along sees the road it covered. Only for images without partners
// of another drive (a road of one drive, or a stretch only one drive took): another drive's
// photos are the better witnesses (this drive's own traffic is not in them), and its own photos
// farther along carry that traffic onto the far road (mkroad, four seeds: IoU 0.01-0.04 lower).
// With `all` (--ahead-veto) images with partners get them too, as a veto of the partners'
// evidence (the other drive's own traffic); an image with none farther along (its drive's last
// photo) gets the `count` photos just behind it for that veto: without one, the other drive's
// traffic there was masked (mkroad seed 13, 120 m, 6 vehicles: drive B's last two photos 1.4 and
// 3.1 % of the frame -> 0; the 80 m street's four seeds: IoU -0.002..+0.0006). A vehicle driving
// ahead at the camera's speed agrees with the photos behind and loses its partners' evidence in
// that last photo only.
Partners ChooseAhead(const Scene& s, int count, double min_share, const Partners& partners,
                     bool all) {
  Partners p{std::vector<std::vector<size_t>>(s.images.size()),
             std::vector<std::vector<double>>(s.images.size())};
  if (count <= 0) return p;
  for (const auto& [name, idx] : s.drives) {
    OtherDrives own;
    for (size_t j : idx) own.Add(s, j);
    for (size_t k = 0; k < idx.size(); ++k) {
      const size_t i = idx[k];
      if (!partners.images[i].empty() && !all) continue;
      for (const auto& [j, z] : PartnersAhead(s, i, own, count, min_share))
        if (j != i) p.images[i].push_back(j), p.beyond[i].push_back(kAheadReach * z);
      // None picked farther along (the drive's end; also a road turning away, or an image
      // with few model points): the `count` photos just behind veto instead, at every pixel
      // (they see all the photo sees but what passed them).
      if (all && !partners.images[i].empty() && p.images[i].empty())
        for (size_t b = 1; b <= size_t(count) && b <= k; ++b)
          p.images[i].push_back(idx[k - b]), p.beyond[i].push_back(0);
    }
  }
  return p;
}

// The mesh the photos are checked against: --mesh; else dynmask-mesh.ply, which the first run
// keeps of the workspace's mesh (DepthProvider), so that a rerun after roadmesh rebuilt mesh.ply
// without the masked pixels still ray-casts the scene as recorded, the vehicles' surfaces that
// --driven grows over included. Empty when there is none; `keep` says the mesh is to be kept.
fs::path StaticMesh(const DynmaskOptions& o, const Workspace& ws, bool& keep) {
  keep = false;
  if (!o.mesh.empty()) return o.mesh;
  const fs::path kept = ws.DynmaskMeshPath(), mesh = ws.MeshPath();
  if (fs::exists(kept)) return kept;
  if (o.depth == DepthSource::kStereo || !fs::exists(mesh)) return {};
  keep = true;
  return mesh;
}

// Links `mesh` (its file, when a symbolic link) to a temporary beside dynmask-mesh.ply, a copy
// where links fail; the caller commits it once the mesh has been read.
void LinkKeptMesh(const fs::path& mesh, const AtomicFile& af) {
  std::error_code ec;
  const fs::path file = fs::canonical(mesh);  // a link to a symbolic link would follow it
  LinkOrCopy(file, af.temp_path(), ec);
  if (ec)
    throw Error(af.final_path().string(), 0, "cannot keep " + mesh.string() + ": " + ec.message());
}

// Static depth of one image at its working size.
class DepthProvider {
 public:
  // mark_walls: Depth() marks the pixels whose ray meets a corridor wall (for --max-fill).
  DepthProvider(const DynmaskOptions& o, const Workspace& ws, bool mark_walls)
      : ws_(ws), mark_walls_(mark_walls) {
    bool keep = false;
    mesh_ = StaticMesh(o, ws, keep);
    const bool stereo = fs::is_directory(ws.StereoDir());
    use_mesh_ = o.depth == DepthSource::kMesh || (o.depth == DepthSource::kAuto && !mesh_.empty());
    if (use_mesh_) {
      if (mesh_.empty()) ws.Require("dynmask", {WsItem::kMesh});
      // The mesh is kept only once it has been read (errors name mesh.ply, the link's file): a
      // broken mesh.ply is not kept.
      std::optional<AtomicFile> kept;
      if (keep) {
        kept.emplace(ws.DynmaskMeshPath());
        LinkKeptMesh(mesh_, *kept);
      }
      Mesh m = ReadMesh(mesh_.string());
      if (kept) {
        kept->Commit();
        mesh_ = ws.DynmaskMeshPath();
      }
      // The corridor walls behind the fused facades' holes are a backdrop at a guessed depth.
      if (m.has_face_kinds()) {
        walls_ = size_t(std::count(m.face_kinds.begin(), m.face_kinds.end(), kFaceFillWall));
        kinds_ = std::move(m.face_kinds);
      }
      caster_ = std::make_unique<MeshRaycaster>(m);
      return;
    }
    if (o.depth == DepthSource::kAuto && !stereo)
      throw Error(ws.root().string() +
                  ": no static depth: neither a mesh (run roadmesh) nor stereo/ (run densify)");
    ws.Require("dynmask", {WsItem::kStereo});
  }
  std::string Name() const {
    if (!use_mesh_) return "stereo/ (densify)";
    const std::string file =
        mesh_ == ws_.DynmaskMeshPath() ? mesh_.filename().string() : mesh_.string();
    if (walls_ == 0) return file + " (ray-cast)";
    return file + " (ray-cast; " + std::to_string(walls_) + " of its faces corridor walls)";
  }
  bool UsesMesh() const { return use_mesh_; }
  // How far below `c` (along -up, unit) the mesh is; NaN without a mesh or a surface there.
  double Below(const Eigen::Vector3d& c, const Eigen::Vector3d& up) const {
    const auto hit = caster_ ? caster_->Closest(c, -up) : std::nullopt;
    return hit ? hit->t : std::numeric_limits<double>::quiet_NaN();
  }
  fs::path Input(const std::string& name) const {
    return use_mesh_ ? mesh_ : ws_.StereoDepthPath(name);
  }
  // `guessed` (when given): CV_8U, 255 where the ray meets a corridor wall, else 0; empty when
  // the static depth says nothing of guesses (densify's maps, a mesh without face kinds).
  cv::Mat Depth(const Camera& cam, const Rigid3d& w2c, const std::string& name,
                cv::Mat* guessed = nullptr) const;

 private:
  const Workspace& ws_;
  fs::path mesh_;
  bool mark_walls_ = false;
  bool use_mesh_ = false;
  std::vector<uint8_t> kinds_;  // the mesh's face kinds (empty: the mesh says nothing)
  size_t walls_ = 0;            // its faces of kind kFaceFillWall
  std::unique_ptr<MeshRaycaster> caster_;
};

// Where each drive's car went (--driven): its camera centres in name order, those within a tenth
// of the drive's spacing of the last one kept left out (a car standing still, pose jitter), broken
// where two consecutive ones lie more than 5 spacings apart (a drive registered in two pieces,
// photos missing: the car's way between them is not known); the spacing is the median step
// between consecutive centres, steps under a hundredth of the mean left out (a car that stood
// still half the time). The camera's height above the road: the median over the drive's photos
// of how far below its centre the mesh is (a drive whose centres have nothing below: none).
std::vector<DrivenPath> DrivenPaths(const Scene& s, const DepthProvider& d) {
  std::vector<DrivenPath> out;
  for (const auto& [name, idx] : s.drives) {
    std::vector<Eigen::Vector3d> c;
    std::vector<double> steps, below;
    for (size_t i : idx) {
      c.push_back(s.images[i]->world_to_camera.Centre());
      if (c.size() > 1) steps.push_back((c.back() - c[c.size() - 2]).norm());
      const double h = d.Below(c.back(), s.up);
      if (std::isfinite(h)) below.push_back(h);
    }
    if (below.empty() || steps.empty()) continue;
    const double mean = std::accumulate(steps.begin(), steps.end(), 0.0) / double(steps.size());
    steps.erase(
        std::remove_if(steps.begin(), steps.end(), [&](double v) { return v < 0.01 * mean; }),
        steps.end());
    if (steps.empty()) continue;
    const double spacing = Median(steps), height = Median(below);
    DrivenPath piece{{c.front()}, height};
    for (size_t k = 1; k < c.size(); ++k) {
      const double step = (c[k] - piece.centres.back()).norm();
      if (step < 0.1 * spacing) continue;
      if (step > 5 * spacing) {
        out.push_back(piece);
        piece.centres.clear();
      }
      piece.centres.push_back(c[k]);
    }
    out.push_back(piece);
  }
  return out;
}

// densify's depth map of an image (what its photo saw) at the working size; empty when densify
// made none.
cv::Mat StereoDepth(const Workspace& ws, const Camera& cam, const std::string& name) {
  const fs::path p = ws.StereoDepthPath(name);
  if (!fs::exists(p)) return {};
  const Image d = ReadImage(p.string());
  if (d.channels != 1) throw Error(p.string() + ": depth must have one channel");
  cv::Mat m(d.height, d.width, CV_32F, const_cast<float*>(d.data.data())), z;
  cv::resize(m, z, {int(cam.width), int(cam.height)}, 0, 0, cv::INTER_NEAREST);
  return z;
}

cv::Mat DepthProvider::Depth(const Camera& cam, const Rigid3d& w2c, const std::string& name,
                             cv::Mat* guessed) const {
  const int w = int(cam.width), h = int(cam.height);
  cv::Mat z(h, w, CV_32F, std::numeric_limits<float>::infinity());
  cv::Mat g;
  if (guessed) *guessed = cv::Mat();
  if (guessed && mark_walls_ && use_mesh_ && walls_ > 0) g = *guessed = cv::Mat::zeros(h, w, CV_8U);
  if (!use_mesh_) {
    cv::Mat m = StereoDepth(ws_, cam, name);
    return m.empty() ? z : m;  // densify made no map for it: no evidence
  }
  const Eigen::Matrix3d Rt = w2c.R().transpose();
  const Eigen::Vector3d c = w2c.Centre();
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < w; ++x) {
        const Eigen::Vector3d dir = Rt * Eigen::Vector3d((x + 0.5 - cam.cx()) / cam.fx(),
                                                         (y + 0.5 - cam.cy()) / cam.fy(), 1);
        if (auto hit = caster_->Closest(c, dir)) {
          z.at<float>(y, x) = float(hit->t);  // t = z
          if (!g.empty() && kinds_[hit->triangle] == kFaceFillWall) g.at<uint8_t>(y, x) = 255;
        }
      }
  });
  return z;
}

// Luma 0..1 and 8-bit RGB at the working size.
void LoadPhoto(const fs::path& path, const Camera& full, const Camera& work, cv::Mat& luma,
               cv::Mat& rgb) {
  const Image colour = ReadImage(path.string());
  RequireImageSize(colour, path.string(), full.width, full.height);
  const Image g = ToGrey(colour);
  const cv::Size size(int(work.width), int(work.height));
  cv::Mat(g.height, g.width, CV_32F, const_cast<float*>(g.data.data()))
      .convertTo(luma, CV_32F, 1.0 / g.MaxValue());
  if (luma.size() != size) cv::resize(luma, luma, size, 0, 0, cv::INTER_AREA);
  const int c = colour.channels;
  cv::Mat rgbf(colour.height, colour.width, CV_32FC3);
  for (int y = 0; y < colour.height; ++y)
    for (int x = 0; x < colour.width; ++x)
      for (int k = 0; k < 3; ++k) rgbf.at<cv::Vec3f>(y, x)[k] = colour.at(x, y, c >= 3 ? k : 0);
  rgbf.convertTo(rgb, CV_8UC3, 255.0 / colour.MaxValue());
  if (rgb.size() != size) cv::resize(rgb, rgb, size, 0, 0, cv::INTER_AREA);
}

// The views one run needs, loaded once each (an image is the neighbour or partner of several),
// their first-pass probabilities, computed once each, and their densify depth maps.
class ViewCache {
 public:
  ViewCache(const Workspace& ws, const Scene& s, const DepthProvider& d,
            const std::vector<std::vector<size_t>>& nbs, const DynamicOptions& ev,
            const MaskOptions& mask)
      : ws_(ws), s_(s), d_(d), nbs_(nbs), ev_(ev), mask_options_(mask) {}
  const DynamicView& Get(size_t i) {
    auto it = views_.find(i);
    if (it != views_.end()) return Used(it->second);
    const std::string& name = s_.images[i]->name;
    DynamicView v;
    v.camera = s_.work[i];
    v.world_to_camera = s_.images[i]->world_to_camera;
    v.depth = d_.Depth(s_.work[i], s_.images[i]->world_to_camera, name, &v.guessed);
    LoadPhoto(ws_.ImagePath(name), s_.full[i], s_.work[i], v.grey, v.colour);
    return Used(views_.emplace(i, Entry<DynamicView>{std::move(v), 0}).first->second);
  }
  // Image j's probability against its own neighbours (the first pass).
  const cv::Mat& FirstPass(size_t j) {
    auto it = first_.find(j);
    if (it != first_.end()) return Used(it->second);
    std::vector<const DynamicView*> views;
    for (size_t k : nbs_[j]) views.push_back(&Get(k));
    cv::Mat p = EstimateDynamic(Get(j), views, ev_).probability;
    return Used(first_.emplace(j, Entry<cv::Mat>{p, 0}).first->second);
  }
  // Where image j's first pass finds something moving, as a whole blob: its first-pass mask
  // (MaskFromProbability: the opening, closing and filled holes of the masks) dilated by the
  // reach of a residual (window / 2 + slack pixels), 1 inside, 0 outside. A vehicle's body,
  // which its outline's evidence does not cover, is left out of the evidence against other
  // photos too.
  const cv::Mat& FirstMask(size_t j) {
    auto it = mask_.find(j);
    if (it != mask_.end()) return Used(it->second);
    cv::Mat m = MaskFromProbability(FirstPass(j), mask_options_), f;
    const int r = ev_.window / 2 + ev_.slack;
    cv::dilate(m, m, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
    m.convertTo(f, CV_32F, 1.0 / 255);
    return Used(mask_.emplace(j, Entry<cv::Mat>{f, 0}).first->second);
  }
  // Image j's densify depth map at the working size (empty without one).
  const cv::Mat& Seen(size_t j) {
    auto it = seen_.find(j);
    if (it != seen_.end()) return Used(it->second);
    cv::Mat z = StereoDepth(ws_, s_.work[j], s_.images[j]->name);
    return Used(seen_.emplace(j, Entry<cv::Mat>{z, 0}).first->second);
  }
  // The next image: forgets what the last 8 images did not use (neighbours and partners of
  // images near in name order are near; one needed again is simply made again).
  void Next() {
    ++tick_;
    Forget(views_), Forget(first_), Forget(mask_), Forget(seen_);
  }

 private:
  template <class T>
  struct Entry {
    T value;
    size_t used;
  };
  template <class T>
  const T& Used(Entry<T>& e) {
    e.used = tick_;
    return e.value;
  }
  template <class Map>
  void Forget(Map& m) {
    for (auto it = m.begin(); it != m.end();)
      it = it->second.used + 8 < tick_ ? m.erase(it) : std::next(it);
  }
  const Workspace& ws_;
  const Scene& s_;
  const DepthProvider& d_;
  const std::vector<std::vector<size_t>>& nbs_;
  const DynamicOptions& ev_;
  const MaskOptions& mask_options_;
  size_t tick_ = 0;
  std::map<size_t, Entry<DynamicView>> views_;
  std::map<size_t, Entry<cv::Mat>> first_, mask_, seen_;
};

// Writes one probability map (8-bit, 255 = surely not static) atomically.
void WriteProbability(const fs::path& path, const cv::Mat& p) {
  Image out(p.cols, p.rows, 1, 8);
  for (int y = 0; y < p.rows; ++y)
    for (int x = 0; x < p.cols; ++x)
      out.data[size_t(y) * size_t(p.cols) + size_t(x)] =
          std::round(std::clamp(p.at<float>(y, x), 0.f, 1.f) * 255.f);
  WriteImage(path.string(), out, PngCompression::kFast);
}

}  // namespace

}  // namespace mvtm

namespace mvtm {

namespace {

struct Job {
  size_t i = 0;
  std::vector<fs::path> in;  // the files its map is made from beyond the model
};

// Each image's neighbours of its own drive and partners of the other drives.
struct Pairing {
  std::vector<std::vector<size_t>> neighbours;
  Partners partner;
  Partners ahead;  // own drive, farther along
};

// Whether image i's photos farther along veto its partners' evidence (--ahead-veto), rather than
// being a cue: then they are compared with what they saw (their densify maps), as partners are.
bool AheadVetoes(const DynmaskOptions& o, const Pairing& pair, size_t i) {
  return o.evidence.ahead_veto > 0 && !pair.partner.images[i].empty();
}

// The selected images whose probability map is stale.
std::vector<Job> StaleMaps(const DynmaskOptions& o, const Workspace& ws, const Scene& s,
                           const Pairing& pair, const DepthProvider& d, Ledger& ledger,
                           DynmaskReport& rep) {
  std::vector<Job> todo;
  const auto& nbs = pair.neighbours;
  for (size_t i : o.Select().Apply(s.images.size())) {
    Job job{i, {}};
    const auto view = [&](size_t j) {
      job.in.push_back(ws.ImagePath(s.images[j]->name));
      job.in.push_back(d.Input(s.images[j]->name));
      if (o.passes == 2)  // the first pass of a neighbour or partner reads its own neighbours
        for (size_t k : nbs[j]) {
          job.in.push_back(ws.ImagePath(s.images[k]->name));
          job.in.push_back(d.Input(s.images[k]->name));
        }
    };
    job.in.push_back(ws.ImagePath(s.images[i]->name));
    job.in.push_back(d.Input(s.images[i]->name));
    // --seen-tolerance, --complete and --driven read the photo's own map.
    const fs::path own = ws.StereoDepthPath(s.images[i]->name);
    if ((o.seen_tolerance > 0 || o.complete > 0 || o.driven.half_width > 0) && d.UsesMesh() &&
        fs::exists(own))
      job.in.push_back(own);
    const auto seen = [&](size_t j) {  // a partner's or a vetoing photo's densify map
      const fs::path p = ws.StereoDepthPath(s.images[j]->name);
      if (fs::exists(p)) job.in.push_back(p);
    };
    for (size_t j : nbs[i]) view(j);
    for (size_t j : pair.ahead.images[i]) {
      view(j);
      if (AheadVetoes(o, pair, i)) seen(j);
    }
    for (size_t j : pair.partner.images[i]) {
      view(j);
      seen(j);
    }
    std::sort(job.in.begin(), job.in.end());
    job.in.erase(std::unique(job.in.begin(), job.in.end()), job.in.end());
    if (ledger.Stale(ws.DynamicPath(s.images[i]->name), job.in, o.force).empty())
      ++rep.skipped;
    else
      todo.push_back(std::move(job));
  }
  return todo;
}

// The tests on the blobs of image i's probability (standing, unexplained: KeepStandingUnexplained)
// and their completion (--complete), with the photo's own densify map when the mesh is the static
// depth.
void JudgeBlobs(const DynmaskOptions& o, const Scene& s, const DepthProvider& d, ViewCache& cache,
                size_t i, cv::Mat& probability, DynmaskReport& rep) {
  const bool tests = o.min_height > 0 || o.seen_tolerance > 0 || o.occludes > 0 || o.max_fill < 1;
  // Completion needs what the photo saw: explained pixels are its sure background.
  const bool complete = o.complete > 0 && d.UsesMesh();
  const bool driven = o.driven.half_width > 0 && d.UsesMesh();
  if (!tests && !complete && !driven) return;
  DynamicView t = cache.Get(i);
  // The photo's own map against the mesh's depth; with densify's maps as the static depth they
  // are one map and explain nothing, and a vehicle parked in this drive is in that "static"
  // depth, hiding nothing behind it: the occlusion test needs the mesh too.
  if (d.UsesMesh()) t.seen = cache.Seen(i);
  if (tests) {
    const BlobTestCounts c =
        KeepStandingUnexplained(t, s.up, o.mask,
                                {o.min_height, o.seen_tolerance, d.UsesMesh() ? o.occludes : 0,
                                 o.occlusion_gap, o.max_fill},
                                probability);
    rep.lying += size_t(c.lying), rep.surface += size_t(c.surface);
    rep.guessed += size_t(c.guessed);
    rep.explained += c.explained;
  }
  // After the tests: a parked vehicle is in the mesh when no drive's masks left it out (its
  // pixels explained, its blob on the static surface), yet it stood where a car drove.
  if (driven) {
    DrivenSpace ds = o.driven;
    ds.open = o.mask.open, ds.min_area = o.mask.min_area, ds.grow = !o.no_driven_grow;
    rep.driven += MarkDriven(t, s.paths, s.up, ds, probability);
  }
  if (complete) {
    BlobCompletion bc;
    bc.max_grow = o.complete;
    if (o.seen_tolerance > 0) bc.tolerance = o.seen_tolerance;
    rep.completed += size_t(CompleteBlobs(t, o.mask, bc, probability));
  }
}

void ComputeMaps(const DynmaskOptions& o, const Workspace& ws, const Scene& s, const Pairing& pair,
                 const DepthProvider& d, const std::vector<Job>& todo, Ledger& ledger,
                 DynmaskReport& rep) {
  CreateFolder(ws.DynamicDir());
  DynamicOptions ev = o.evidence;
  ev.flow = !o.no_flow;
  ev.colour = !o.no_colour;
  ViewCache cache(ws, s, d, pair.neighbours, ev, o.mask);
  Progress bar("dynmask", todo.size(), o.quiet);
  const auto t0 = Clock::now();
  // The views of `images` (Mat headers: no pixel copies), with their first-pass mask on two
  // passes, and with what they saw (densify's maps) as partners.
  const auto views_of = [&](const std::vector<size_t>& images, bool partners) {
    std::vector<DynamicView> v;
    for (size_t j : images) {
      v.push_back(cache.Get(j));
      if (o.passes == 2) v.back().dynamic = cache.FirstMask(j);
      if (partners) v.back().seen = cache.Seen(j);
    }
    return v;
  };
  // ... the views of `p`'s photos of image i, each with its `beyond`.
  const auto views_beyond = [&](const Partners& p, size_t i, bool seen) {
    std::vector<DynamicView> v = views_of(p.images[i], seen);
    for (size_t k = 0; k < v.size(); ++k) v[k].beyond = p.beyond[i][k];
    return v;
  };
  const auto pointers = [](const std::vector<DynamicView>& v) {
    std::vector<const DynamicView*> p;
    for (const DynamicView& x : v) p.push_back(&x);
    return p;
  };
  for (const Job& job : todo) {
    cache.Next();
    const std::vector<DynamicView> nv = views_of(pair.neighbours[job.i], false);
    const std::vector<DynamicView> pv = views_beyond(pair.partner, job.i, true);
    // As a veto of the partners' evidence, the photos farther along with what they saw: a
    // vehicle parked in this drive hides the road its pixels warp to from them.
    const bool veto = AheadVetoes(o, pair, job.i);
    const std::vector<DynamicView> av = views_beyond(pair.ahead, job.i, veto);
    DynamicEvidence e =
        EstimateDynamic(cache.Get(job.i), pointers(nv), ev, pointers(pv), pointers(av));
    if (e.neighbours + e.partners + e.ahead == 0) ++rep.no_neighbours;
    if (e.partners > 0) ++rep.with_partners;
    if (e.ahead > 0) ++(veto ? rep.with_veto : rep.with_ahead);
    const std::vector<double>& beyond = pair.ahead.beyond[job.i];
    if (veto && e.ahead > 0 &&
        std::all_of(beyond.begin(), beyond.end(), [](double b) { return b == 0; }))
      ++rep.with_behind;
    if (o.grounded > 0)
      rep.floating += size_t(
          KeepGrounded(cache.Get(job.i), s.up, o.mask.probability, o.grounded, e.probability));
    JudgeBlobs(o, s, d, cache, job.i, e.probability, rep);
    const fs::path out = ws.DynamicPath(s.images[job.i]->name);
    CreateFolder(out.parent_path());
    WriteProbability(out, e.probability);
    ledger.Done(out, job.in);
    ++rep.written;
    bar.Step();
  }
  if (rep.written)
    rep.ms_per_image =
        std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / double(rep.written);
}

fs::path LabelFile(const DynmaskOptions& o, const std::string& name) {
  return fs::path(o.labels) / fs::path(name).replace_extension(".png");
}

// With --labels: the mask is the blobs of the label image's classes whose mean probability (the
// map upsampled, bilinear) reaches --confirm, whole; the labels say what a vehicle is, the
// geometry whether it moves. A frame without a label image keeps the geometry's mask.
void ConfirmLabels(const DynmaskOptions& o, const LabelDecoder& decoder, const std::string& name,
                   const cv::Mat& prob, cv::Mat& mask) {
  const fs::path p = LabelFile(o, name);
  if (!fs::exists(p)) return;
  const Image label = ReadImage(p.string());
  RequireImageSize(label, p.string(), uint64_t(mask.cols), uint64_t(mask.rows));
  std::vector<uint8_t> vehicle;
  decoder.Decode(label, p.string(), vehicle);
  cv::Mat v(mask.rows, mask.cols, CV_8U, vehicle.data()), labels, up;
  cv::resize(prob, up, mask.size(), 0, 0, cv::INTER_LINEAR);
  const int n = cv::connectedComponents(v, labels, 8, CV_32S);
  std::vector<double> sum(size_t(n), 0), count(size_t(n), 0);
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const size_t b = size_t(labels.at<int>(y, x));
      sum[b] += up.at<float>(y, x), count[b] += 1;
    }
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const size_t b = size_t(labels.at<int>(y, x));
      mask.at<uint8_t>(y, x) = b > 0 && sum[b] >= o.confirm * count[b] ? 255 : 0;
    }
}

// Image i's probability map (CV_32F, 0..1) at the working size.
cv::Mat ReadProbability(const Workspace& ws, const Scene& s, size_t i) {
  const fs::path p = ws.DynamicPath(s.images[i]->name);
  const Image im = ReadImage(p.string());
  RequireImageSize(im, p.string(), s.work[i].width, s.work[i].height);
  cv::Mat prob(im.height, im.width, CV_32F);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      prob.at<float>(y, x) =
          float(im.data[(size_t(y) * size_t(im.width) + size_t(x)) * size_t(im.channels)] /
                im.MaxValue());
  return prob;
}

// One image's mask from its probability map, at the image's full size.
cv::Mat MaskOf(const DynmaskOptions& o, const LabelDecoder& decoder, const Workspace& ws,
               const Scene& s, size_t i) {
  const MaskOptions& mo = o.mask;
  const cv::Mat prob = ReadProbability(ws, s, i);
  cv::Mat m = MaskFromProbability(prob, mo), full;
  const cv::Size size(int(s.full[i].width), int(s.full[i].height));
  cv::resize(m, full, size, 0, 0, cv::INTER_NEAREST);
  if (!o.labels.empty()) ConfirmLabels(o, decoder, s.images[i]->name, prob, full);
  return full;
}

// ORs the mask DIR/STEM.png (any non-zero channel) into `out` (w×h bytes).
void OrAlso(const std::string& dir, const std::string& name, const Camera& cam,
            std::vector<uint8_t>& out) {
  const fs::path p = fs::path(dir) / (fs::path(name).replace_extension(".png"));
  if (!fs::exists(p)) return;
  const Image m = ReadImage(p.string());
  RequireImageSize(m, p.string(), cam.width, cam.height);
  for (size_t k = 0; k < out.size(); ++k)
    for (int c = 0; c < m.channels; ++c)
      if (m.data[k * size_t(m.channels) + size_t(c)] != 0) out[k] = 255;
}

// What every mask and tracks.tsv are made from: every probability map (tracking couples the
// frames) and the --also masks that exist.
std::vector<fs::path> MaskInputs(const DynmaskOptions& o, const Workspace& ws, const Scene& s) {
  std::vector<fs::path> maps;
  for (const ImageRecord* im : s.images) maps.push_back(ws.DynamicPath(im->name));
  if (!o.also.empty())
    for (const ImageRecord* im : s.images) {
      const fs::path p = fs::path(o.also) / fs::path(im->name).replace_extension(".png");
      if (fs::exists(p)) maps.push_back(p);
    }
  if (!o.labels.empty())
    for (const ImageRecord* im : s.images)
      if (fs::exists(LabelFile(o, im->name))) maps.push_back(LabelFile(o, im->name));
  return maps;
}

// Tracks each drive's blobs and writes every mask and tracks.tsv.
void WriteMasks(const DynmaskOptions& o, const Workspace& ws, const Scene& s, Ledger& ledger,
                DynmaskReport& rep) {
  const std::vector<fs::path> inputs = MaskInputs(o, ws, s);
  const LabelDecoder decoder = LabelDecoder::ClassIds(LabelDecoder::ParseClasses(o.classes));
  CreateFolder(ws.MasksDir());
  std::vector<TracksTsvRow> rows;
  Progress bar("dynmask masks", s.images.size(), o.quiet);
  double share = 0;
  int id_base = 0;
  for (const auto& [pass, idx] : s.drives) {
    const Camera& c0 = s.full[idx[0]];
    TrackOptions to = o.track;
    if (to.max_jump == 0) to.max_jump = 0.25 * double(c0.width);
    Tracker tracker(int(c0.width), int(c0.height), to);
    for (size_t i : idx) {
      if (s.full[i].width != c0.width || s.full[i].height != c0.height)
        throw Error(ws.ImagePath(s.images[i]->name).string() +
                    ": every image of a drive must have one size to be tracked");
      tracker.AddFrame(MaskOf(o, decoder, ws, s, i).data);
    }
    TrackResult res = tracker.Finish();
    if (o.gap_support > 0)
      for (size_t k = 0; k < idx.size(); ++k) {
        if (!res.HasInterpolated(int(k))) continue;  // the map is read only where a gap is filled
        cv::Mat p;
        cv::resize(ReadProbability(ws, s, idx[k]), p, cv::Size(res.width, res.height), 0, 0,
                   cv::INTER_LINEAR);
        RejectUnsupportedGaps(res, int(k), p.ptr<float>(), o.gap_support);
      }
    std::vector<uint8_t> mask;
    Image out(res.width, res.height, 1, 8);
    for (size_t k = 0; k < idx.size(); ++k) {
      res.RenderMask(int(k), o.track.dilate, mask);
      if (!o.also.empty()) OrAlso(o.also, s.images[idx[k]]->name, c0, mask);
      std::copy(mask.begin(), mask.end(), out.data.begin());
      share += double(std::count(mask.begin(), mask.end(), 255)) / double(mask.size());
      const fs::path path = ws.MaskPath(s.images[idx[k]]->name);
      CreateFolder(path.parent_path());
      WriteImage(path.string(), out, PngCompression::kFast);
      ledger.Done(path, inputs);
      ++rep.masks_written;
      bar.Step();
    }
    for (TrackRow r : res.rows) {
      const std::string& name = s.images[idx[size_t(r.frame)]]->name;
      r.track += id_base;
      rows.push_back({name, r});
    }
    id_base += res.summary.tracks;
    const TrackSummary& t = res.summary;
    rep.summary.frames += t.frames, rep.summary.tracks += t.tracks, rep.summary.kept += t.kept;
    rep.summary.rejected += t.rejected, rep.summary.detected += t.detected;
    rep.summary.interpolated += t.interpolated, rep.summary.rejected_blobs += t.rejected_blobs;
    rep.summary.unfilled_gaps += t.unfilled_gaps;
    rep.summary.unsupported_gaps += t.unsupported_gaps;
  }
  WriteTracksTsv(ws.TracksPath().string(), rows);
  ledger.Done(ws.TracksPath(), inputs);
  rep.masked = true;
  rep.masked_share = share / double(s.images.size());
}

// The masks (and tracks.tsv) are stale when any is.
bool MasksStale(const DynmaskOptions& o, const Workspace& ws, const Scene& s, Ledger& ledger) {
  std::vector<fs::path> outputs{ws.TracksPath()};
  for (const ImageRecord* im : s.images) outputs.push_back(ws.MaskPath(im->name));
  return ledger.AnyStale(outputs, MaskInputs(o, ws, s), o.force);
}

// The provenance keys of the options only the masks depend on: a change of them alone leaves
// the probability maps up to date.
std::set<std::string> MaskOnlyKeys() {
  DynmaskOptions o;
  OptionTable t("dynmask");
  DeclareTrackingOptions(t, o);
  std::set<std::string> keys;
  const nlohmann::json changing = t.OutputJson();
  for (const auto& [key, value] : changing.items()) keys.insert(key);
  return keys;
}

}  // namespace

DynmaskReport RunDynmask(const DynmaskOptions& o) {
  o.Check();
  const Workspace ws(o.workspace);
  ws.Require("dynmask", {WsItem::kSparse, WsItem::kImages});
  const DepthProvider depth(o, ws, o.max_fill < 1);
  Scene s = LoadScene(ws, o.max_width);
  if (o.driven.half_width > 0 && depth.UsesMesh()) s.paths = DrivenPaths(s, depth);
  Pairing pair{ChooseNeighbours(s, o.neighbours, o.min_baseline),
               ChoosePartners(s, o.partners, o.partners_ahead),
               {}};
  pair.ahead = ChooseAhead(s, o.ahead, o.ahead_min_share, pair.partner, o.evidence.ahead_veto > 0);
  DynmaskReport rep;
  rep.images = s.images.size();
  rep.depth_source = depth.Name();
  DynmaskOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(ws.root(), o.ProvenanceName("dynmask"), table, ws.SparseModelFiles(), ws.root());
  ledger.Independent(ws.DynamicDir(), MaskOnlyKeys());
  const std::vector<Job> todo = StaleMaps(o, ws, s, pair, depth, ledger, rep);
  RemoveStaleTemporaries(ws.DynamicDir());
  RemoveStaleTemporaries(ws.MasksDir());
  if (!todo.empty()) ComputeMaps(o, ws, s, pair, depth, todo, ledger, rep);
  const bool whole = o.frames.empty() && o.shard.empty();
  if (whole && MasksStale(o, ws, s, ledger)) WriteMasks(o, ws, s, ledger, rep);
  rep.why = ledger.Summary();
  ledger.Write();
  return rep;
}

}  // namespace mvtm
