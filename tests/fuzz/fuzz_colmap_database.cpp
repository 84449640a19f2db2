// mvtm — libFuzzer harness: COLMAP database.db (SQLite) through io/colmap_database.h: the input is
// the database file; the harness lists its images, then adds a camera and upserts an image the way
// orb2colmap does.
// Accepts only mvtm::Error; see fuzz_util.h.
#include "base/error.h"
#include "camera/camera.h"
#include "fuzz_util.h"
#include "io/colmap_database.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mvtm::fuzz::TempDir dir;
  const std::string path = dir.Add("database.db", data, size);
  try {
    mvtm::ColmapDatabase db(path);
    const auto images = db.Images();
    mvtm::Camera cam = mvtm::ParseCameraSpec("PINHOLE 64 32 50 50 32 16");
    db.Begin();
    const uint32_t cam_id = db.AddCamera(cam);
    db.UpdateCamera(cam_id, cam);
    db.UpsertImage("fuzz.png", static_cast<uint32_t>(images.size() + 1), cam_id, mvtm::Rigid3d());
    if (!images.empty()) db.UpsertImage(images.begin()->first, 1, cam_id, mvtm::Rigid3d());
    db.Commit();
  } catch (const mvtm::Error&) {
  }
  return 0;
}
