// mvtm — COLMAP's SQLite database (database.db), the subset orb2colmap fills.
//
// Schema: COLMAP 3.8 src/base/database.cc (tables cameras, images, keypoints, descriptors,
// matches, two_view_geometries). Camera params are a blob of doubles; image pose priors
// (prior_qw..prior_tz) are world-to-camera like images.txt.
// Opening an existing database keeps its contents: images already present (by name) keep their
// image_id, which is what `colmap point_triangulator` needs the model's ids to match.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "camera/camera.h"
#include "geometry/rigid.h"

struct sqlite3;

namespace mvtm {

class ColmapDatabase {
 public:
  // Opens or creates `path` (creating COLMAP's tables when absent). Throws Error.
  explicit ColmapDatabase(const std::string& path);
  ~ColmapDatabase();
  ColmapDatabase(const ColmapDatabase&) = delete;
  ColmapDatabase& operator=(const ColmapDatabase&) = delete;

  // name → (image_id, camera_id) of the images already in the database.
  std::map<std::string, std::pair<uint32_t, uint32_t>> Images() const;
  // Inserts a camera and returns its id.
  uint32_t AddCamera(const Camera& camera);
  // Overwrites the model, size and parameters of an existing camera.
  void UpdateCamera(uint32_t camera_id, const Camera& camera);
  // Inserts an image with a pose prior (image_id chosen by the caller) or, when `name` exists,
  // updates its camera and prior. No prior (std::nullopt) stores NULLs, as COLMAP does for an
  // image without one (structure from motion finds the pose). Returns the image_id in the
  // database.
  uint32_t UpsertImage(const std::string& name, uint32_t wanted_id, uint32_t camera_id,
                       const std::optional<Rigid3d>& prior_world_to_camera);

  void Begin();
  void Commit();

 private:
  void Exec(const std::string& sql) const;
  std::string path_;
  sqlite3* db_ = nullptr;
  std::map<std::string, std::pair<uint32_t, uint32_t>> cache_;  // name → ids, loaded on first use
  bool cache_loaded_ = false;
};

}  // namespace mvtm
