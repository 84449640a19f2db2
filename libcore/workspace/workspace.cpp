#include "workspace/workspace.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/version.h"
#include "io/colmap_model.h"

namespace mvtm {

namespace {
// "dir/A_0001.jpg" → "dir/A_0001" + ext
fs::path Derived(const fs::path& dir, const std::string& name, const char* ext) {
  fs::path p = dir / name;
  p.replace_extension(ext);
  return p;
}
}  // namespace

std::string PassOf(const std::string& image_name) {
  const std::string base = fs::path(image_name).filename().string();
  const size_t u = base.find('_');
  return u == std::string::npos ? std::string() : base.substr(0, u);
}

Workspace::Workspace(fs::path root) : root_(std::move(root)) {}

fs::path Workspace::SparseDir() const { return root_ / "sparse"; }
fs::path Workspace::ImagesDir() const { return root_ / "images"; }
fs::path Workspace::ImagePath(const std::string& name) const { return root_ / "images" / name; }
fs::path Workspace::TexturePath(const std::string& name) const { return TexturesDir() / name; }
fs::path Workspace::SourceImagePath(const std::string& name) const {
  fs::path t = TexturePath(name);
  return fs::exists(t) ? t : ImagePath(name);
}
fs::path Workspace::MeshPath() const {
  for (const char* n : {"mesh.ply", "meshed-poisson.ply", "meshed-delaunay.ply"})
    if (fs::exists(root_ / n)) return root_ / n;
  return root_ / "mesh.ply";
}
fs::path Workspace::LabelsDir() const { return root_ / "labels"; }
fs::path Workspace::LabelPath(const std::string& name) const {
  return Derived(LabelsDir(), name, ".png");
}
fs::path Workspace::MasksDir() const { return root_ / "masks"; }
fs::path Workspace::MaskPath(const std::string& name) const {
  return Derived(MasksDir(), name, ".png");
}
fs::path Workspace::DynamicDir() const { return root_ / "dynamic"; }
fs::path Workspace::DynamicPath(const std::string& name) const {
  return Derived(DynamicDir(), name, ".png");
}
fs::path Workspace::DepthDir() const { return root_ / "depth"; }
fs::path Workspace::DepthPath(const std::string& name) const {
  return Derived(DepthDir(), name, ".exr");
}
fs::path Workspace::StereoDir() const { return root_ / "stereo"; }
fs::path Workspace::StereoDepthPath(const std::string& name) const {
  return Derived(StereoDir(), name, ".exr");
}
fs::path Workspace::StereoConfidencePath(const std::string& name) const {
  return Derived(StereoDir(), name, ".conf.exr");
}
fs::path Workspace::TexturesDir() const { return root_ / "textures"; }
fs::path Workspace::TextureProvenancePath(const std::string& name) const {
  return Derived(TexturesDir() / "provenance", name, ".png");
}
fs::path Workspace::NewMeshPath() const { return root_ / "mesh.ply"; }
fs::path Workspace::DynmaskMeshPath() const { return root_ / "dynmask-mesh.ply"; }
std::vector<fs::path> Workspace::SparseModelFiles() const {
  std::vector<fs::path> files;
  for (const auto& f : ColmapModelFiles(SparseDir().string())) files.emplace_back(f);
  return files;
}
fs::path Workspace::TracksPath() const { return root_ / "tracks.tsv"; }
fs::path Workspace::PartnersPath() const { return root_ / "partners.tsv"; }
fs::path Workspace::ExposurePath() const { return root_ / "exposure.tsv"; }
std::vector<std::string> Workspace::Missing(const std::vector<WsItem>& needs) const {
  std::vector<std::string> out;
  auto model = [&] { return HasColmapModel(SparseDir().string()); };
  for (WsItem n : needs) {
    switch (n) {
      case WsItem::kSparse:
        if (!model()) out.push_back("sparse/ (COLMAP model: cameras, images, points3D)");
        break;
      case WsItem::kImages:
        if (!fs::is_directory(ImagesDir())) out.push_back("images/");
        break;
      case WsItem::kMesh:
        if (!fs::exists(MeshPath())) out.push_back("mesh.ply (or meshed-poisson.ply)");
        break;
      case WsItem::kLabels:
        if (!fs::is_directory(LabelsDir())) out.push_back("labels/");
        break;
      case WsItem::kMasks:
        if (!fs::is_directory(MasksDir())) out.push_back("masks/ (run segtrack)");
        break;
      case WsItem::kTracks:
        if (!fs::exists(TracksPath())) out.push_back("tracks.tsv (run segtrack)");
        break;
      case WsItem::kStereo:
        if (!fs::is_directory(StereoDir())) out.push_back("stereo/ (run densify)");
        break;
      case WsItem::kPartners:
        if (!fs::exists(PartnersPath())) out.push_back("partners.tsv (run pickview --partners)");
        break;
      case WsItem::kDepth:
        if (!fs::is_directory(root_ / "depth")) out.push_back("depth/ (run bakedepth)");
        break;
      case WsItem::kTextures:
        if (!fs::is_directory(root_ / "textures")) out.push_back("textures/ (run inpaint3d)");
        break;
    }
  }
  return out;
}

void Workspace::Require(const std::string& tool, const std::vector<WsItem>& needs) const {
  if (!fs::is_directory(root_)) throw Error(root_.string(), 0, "workspace folder does not exist");
  auto miss = Missing(needs);
  if (miss.empty()) return;
  std::string list;
  for (const auto& m : miss) list += (list.empty() ? "" : ", ") + m;
  throw Error(root_.string(), 0, "not ready for " + tool + ": missing " + list);
}

fs::path Workspace::MetricRecord(const std::string& except_tool) const {
  std::error_code ec;
  // georef's record: the model was made metric (camera height or GPS) before it was undistorted.
  const fs::path georef = root_ / "georef.json";
  if (fs::is_regular_file(georef, ec)) {
    std::ifstream in(georef);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (!j.is_discarded() && j.is_object() && j.value("unit", "") == "metre") return georef;
  }
  const fs::path dir = root_ / "provenance";
  if (!fs::is_directory(dir, ec)) return {};
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    const std::string stem = p.stem().string();
    if (!except_tool.empty() &&
        (stem == except_tool || stem.rfind(except_tool + "-shard-", 0) == 0))
      continue;
    std::ifstream in(p);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("options")) continue;
    const nlohmann::json& o = j["options"];
    if (o.is_object() && o.contains("metric") && o["metric"] == true) return p;
  }
  return {};
}

}  // namespace mvtm
