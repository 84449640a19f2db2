#include "drive/road_car.h"

#include <algorithm>
#include <map>

#include "base/error.h"
#include "base/text.h"
#include "drive/ground.h"

namespace mvtm {

RecordedDrive RoadRecordedDrive(const RoadLocator& where, const std::string& pass,
                                const std::string& start, std::vector<size_t>& homes) {
  std::vector<const ImageRecord*> images;
  std::map<const ImageRecord*, size_t> home_of;
  for (const RoadRecordedFrame& f : where.frames()) {
    images.push_back(f.image);
    home_of[f.image] = f.home;
  }
  // Name order, as on a workspace: a pass driven against the path of record is in its own order.
  RecordedDrive r = SelectRecordedDrive(images, pass, start, where.road().GraphPath().string(),
                                        "owned by a fragment of the road");
  homes.clear();
  for (const ImageRecord* im : r.images) homes.push_back(home_of.at(im));
  r.rec.cameras = where.model(homes[r.start]).cameras;  // the camera a COLMAP OUT is written with
  return r;
}

RoadGround::RoadGround(const RoadLocator& where, size_t home, bool keep_mesh)
    : where_(where), meshes_(where.road()), keep_mesh_(keep_mesh) {
  Enter(home);
}

const MeshRaycaster* RoadGround::Follow(const Eigen::Vector3d& centre, double t) {
  const size_t k = where_.Locate(centre, home_, "the car at t = " + FormatDouble(t) + " s");
  if (k != home_) Enter(k);
  return ray_.get();
}

const MeshRaycaster* RoadGround::JumpTo(size_t home) {
  if (home != home_) Enter(home);
  return ray_.get();
}

void RoadGround::Enter(size_t k) {
  const Road& road = where_.road();
  const std::vector<size_t> resident = road.Resident(k);
  auto listed = [](const std::vector<size_t>& v, size_t x) {
    return std::find(v.begin(), v.end(), x) != v.end();
  };
  std::vector<size_t> next;
  for (size_t n : resident)
    for (size_t m : road.Resident(n))
      if (!listed(resident, m) && !listed(next, m)) next.push_back(m);
  Mesh mesh = meshes_.Union(resident, next);
  if (mesh.faces.empty())
    throw Error(road.fragments()[k].dir.string(), 0,
                "no triangles in this fragment or its neighbours");
  ray_ = std::make_unique<MeshRaycaster>(mesh);  // (it copies the mesh)
  mesh_ = keep_mesh_ ? std::move(mesh) : Mesh();
  home_ = k;
  entered_.insert(k);
}

CarOnRoad SetUpRoadCar(const RoadLocator& where, const RoadGround& ground,
                       const RecordedDrive& drive, const std::vector<size_t>& homes,
                       const CarOptions& o, const std::string& tool) {
  const Road& road = where.road();
  CarOnRoad set;
  set.rec = drive;
  const Workspace ws(road.fragments()[ground.home()].dir);
  const Eigen::Vector3d up = RecordedUp(drive.w2c);
  const std::vector<size_t> resident = road.Resident(ground.home());
  std::vector<Rigid3d> near;
  for (size_t i = 0; i < drive.w2c.size(); ++i)
    if (std::find(resident.begin(), resident.end(), homes[i]) != resident.end())
      near.push_back(drive.w2c[i]);
  const std::vector<double> heights = CameraHeights(ground.ray(), near, up);
  set.height_cameras = heights.size();
  set.scale = ResolveScale(o.scale, o.metric, ws, heights, tool, set.scale_source);
  set.car = MakeCar(o.wheelbase, o.track, o.camera_offset, ws, heights, set.scale,
                    &set.height_from_workspace);
  set.frame = FrameAtCamera(drive.w2c[drive.start], up, set.scale);
  return set;
}

}  // namespace mvtm
