// mvtm — a car on a road of fragments (workspace/road.h): the road's recorded drive, the car set
// on it as on a workspace (car_setup.h), and the ground under it, streamed by the road graph.
// drive and simulate drive the same car over a road the same way.
//
// The ground is the own triangles of the fragment the car is in and of its graph neighbours
// (RoadMeshes). When the car's camera comes nearest a recorded image owned by another fragment
// (RoadLocator, walking the graph), that fragment's ground replaces it; the fragments two steps
// away are read ahead on a second thread, the others dropped.
// Thread safety: none (one car, one thread).
#pragma once

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "drive/car_setup.h"
#include "raycast/mesh_raycaster.h"
#include "workspace/road.h"
#include "workspace/road_locator.h"
#include "workspace/road_meshes.h"

namespace mvtm {

// The road's recorded drive: its recorded frames whose names start with `pass`, in name order,
// from `start`; `homes` gets the fragment owning each. The images point into `where`'s models;
// rec.cameras are the start fragment's. Throws as SelectRecordedDrive.
RecordedDrive RoadRecordedDrive(const RoadLocator& where, const std::string& pass,
                                const std::string& start, std::vector<size_t>& homes);

class RoadGround {
 public:
  // `keep_mesh`: also keep the triangles (mesh()) beside the raycaster's copy.
  RoadGround(const RoadLocator& where, size_t home, bool keep_mesh = false);
  const MeshRaycaster& ray() const { return *ray_; }
  // The triangles under ray(): the fragment's own and its neighbours' (RoadMeshes::Union);
  // empty unless kept.
  const Mesh& mesh() const { return mesh_; }
  size_t home() const { return home_; }
  size_t entered() const { return entered_.size(); }  // distinct fragments the car was in
  // The ground after the camera reached `centre` at time t: the fragment it is in now (an Error
  // naming the time when it left the road or the graph).
  const MeshRaycaster* Follow(const Eigen::Vector3d& centre, double t);
  // The car put down in fragment `home` (a reset to a recorded image): no graph walk.
  const MeshRaycaster* JumpTo(size_t home);

 private:
  void Enter(size_t k);

  const RoadLocator& where_;
  RoadMeshes meshes_;
  bool keep_mesh_;
  Mesh mesh_;
  std::unique_ptr<MeshRaycaster> ray_;
  size_t home_ = 0;
  std::set<size_t> entered_;
};

// The car set on a road as SetUpCar sets it on a workspace: up from all of the recorded
// drive's cameras, the height from those over the start fragment's ground (its own triangles
// and its neighbours'), the scale from the start fragment's workspace (for `tool`), the road
// frame at the start image. `homes` as RoadRecordedDrive's.
CarOnRoad SetUpRoadCar(const RoadLocator& where, const RoadGround& ground,
                       const RecordedDrive& drive, const std::vector<size_t>& homes,
                       const CarOptions& o, const std::string& tool);

}  // namespace mvtm
