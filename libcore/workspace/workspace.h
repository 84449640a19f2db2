// mvtm — the workspace: one road fragment on disk. The only code that knows folder names.
//
// Layout (man mvtm-workspace(5)):
//   sparse/               COLMAP model (cameras, images, points3D; .txt or .bin) — poses of record
//   images/NAME           undistorted source images, named as in images.txt
//   mesh.ply              (or meshed-poisson.ply, meshed-delaunay.ply) — first found wins
//   labels/NAME.png       semantic labels (segtrack input)
//   masks/NAME.png        8-bit masks, 255 = remove (segtrack or dynmask output)
//   dynamic/NAME.png      8-bit probability of "not static", 255 = surely not (dynmask)
//   dynmask-mesh.ply      the mesh as dynmask's first run found it, vehicles and all (dynmask)
//   tracks.tsv            segtrack's (or dynmask's) tracks
//   partners.tsv          pickview's view selection
//   exposure.tsv          gain and offset per image (exposure)
//   depth/NAME.exr        float32 linear camera-space depth, +inf = no surface (bakedepth)
//   stereo/NAME.exr       float32 linear depth from multi-view stereo, +inf = untrusted (densify)
//   stereo/NAME.conf.exr  its confidence, 0..1
//   textures/NAME         images with vehicles removed (inpaint3d); preferred over images/ by
//                         the programs that project them (never by those that build the mesh)
//   textures/provenance/NAME.png  where each inpainted pixel came from (inpaint3d)
//   provenance/TOOL.json  the record of what made a tool's outputs here (run/ledger.h)
// NAME keeps any sub-folders of the image name; derived files replace the extension (".png",
// ".exr") after the full name's stem, e.g. "A_0001.jpg" → "masks/A_0001.png".
// A COLMAP dense workspace (image_undistorter output + meshed-poisson.ply) is a valid workspace.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/file_stamp.h"

namespace mvtm {

namespace fs = std::filesystem;

enum class WsItem {
  kSparse,
  kImages,
  kMesh,
  kLabels,
  kMasks,
  kTracks,
  kPartners,
  kDepth,
  kTextures,
  kStereo
};

// The pass (drive) an image belongs to: its file name's prefix before the first '_'
// (mkroad: A_0000.png is pass "A"); "" when the name has none. Images of one drive of a road
// share it (pickview --partners pairs passes; dynmask compares a photo with its own pass).
std::string PassOf(const std::string& image_name);

class Workspace {
 public:
  explicit Workspace(fs::path root);

  const fs::path& root() const { return root_; }
  fs::path SparseDir() const;
  fs::path ImagesDir() const;
  fs::path ImagePath(const std::string& name) const;
  // textures/NAME when it exists, else images/NAME.
  fs::path SourceImagePath(const std::string& name) const;
  fs::path TexturePath(const std::string& name) const;
  fs::path MeshPath() const;  // the first existing of mesh.ply, meshed-poisson.ply,
                              // meshed-delaunay.ply; else mesh.ply
  fs::path LabelPath(const std::string& name) const;
  fs::path LabelsDir() const;
  fs::path MaskPath(const std::string& name) const;
  fs::path MasksDir() const;
  // dynamic/NAME.png: 8-bit probability that a pixel is not the static scene (dynmask).
  fs::path DynamicPath(const std::string& name) const;
  fs::path DynamicDir() const;
  fs::path DepthPath(const std::string& name) const;
  fs::path DepthDir() const;
  // stereo/NAME.exr and stereo/NAME.conf.exr: dense depth from the photos and its confidence
  // (densify).
  fs::path StereoDir() const;
  fs::path StereoDepthPath(const std::string& name) const;
  fs::path StereoConfidencePath(const std::string& name) const;
  fs::path TexturesDir() const;
  // textures/provenance/STEM.png: where each pixel of textures/NAME came from (inpaint3d).
  fs::path TextureProvenancePath(const std::string& name) const;
  // Where a tool that builds the workspace's mesh writes it (mesh.ply).
  fs::path NewMeshPath() const;
  // dynmask-mesh.ply: the mesh dynmask checks the photos against, kept (hard-linked) as its
  // first run found it, since roadmesh rebuilds mesh.ply without the masked pixels afterwards.
  fs::path DynmaskMeshPath() const;
  // The sparse model's files that exist (text and binary): the inputs every derived output
  // (depth maps, frames, partners, the mesh) depends on.
  std::vector<fs::path> SparseModelFiles() const;
  fs::path TracksPath() const;
  fs::path PartnersPath() const;
  // exposure.tsv: gain and offset per image (exposure); ptmrender brings projectors to one
  // exposure.
  fs::path ExposurePath() const;
  // The record that says the model is metric — georef.json with "unit": "metre" (georef made the
  // model metric from the camera height or GPS), else a tool's last run with the option
  // "metric": true (roadmesh --metric) — as the record's path; empty when none does.
  // A record that cannot be read or parsed says nothing; `except_tool`'s own records
  // (TOOL.json, TOOL-shard-I.json) are passed over (drive's "metric" is its own --metric: its
  // record must not become an input of itself).
  fs::path MetricRecord(const std::string& except_tool = "") const;

  // What `tool` needs that is missing, one human-readable item each (empty: ready).
  std::vector<std::string> Missing(const std::vector<WsItem>& needs) const;
  // Throws Error("WS: not ready for TOOL: missing a, b") when anything is missing.
  void Require(const std::string& tool, const std::vector<WsItem>& needs) const;

 private:
  fs::path root_;
};

}  // namespace mvtm
