// mvtm — a car on the mesh: the road plane a planar path lives in, the ground under the wheels
// (ray casts, raycast/mesh_raycaster.h) and the camera pose that results (drive).
//
// Conventions:
//  * The road frame: a level plane through `origin` (a world point, double) with unit normal
//    `up`; planar x along `x_axis`, y along `y_axis` = up × x_axis (left), heights along up. The
//    planar model works in metres; `scale` (model units per metre) maps metres to the model's
//    unit, so a model scaled by s with scale × s gives the same path scaled by s.
//  * Up is the recorded cameras' mean up axis (−y, the cameras of a dashcam are level to within
//    a few degrees), RecordedUp().
//  * The car: rear axle centre at the planar pose, wheels at ±track/2 across the rear axle and
//    the front axle (wheelbase ahead). Each wheel's ground is the first surface a ray cast
//    straight down (−up) meets, starting `kClearance` (2 m) above the ground that wheel had at the
//    previous placement (the first placement: from the height of the frame's origin, i.e. the
//    start camera), and at most 20 m below that start. The ground plane under the car is the
//    least-squares plane through the four contacts: its slope along the car gives the pitch,
//    across it the roll, and its height under the rear axle centre the car's height (for a
//    rectangle of contacts, the mean of the two rear contacts).
//  * The camera sits at `camera_offset` (metres forward, left, up) from that ground point in
//    the car's frame (forward, left, up of the ground plane), looking forward: camera z =
//    forward, y = down (−up of the car), x = right, as a level recorded dashcam.
//  * No surface under a wheel is an Error naming the time and the wheel ("leaves the mesh").
// Thread safety: GroundPlacer is stateful (the previous ground heights); one per path. The state
// only chooses where each ray starts, so a pose placed after different previous poses (another
// output rate) agrees to rounding, not to the bit.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "drive/bicycle.h"
#include "geometry/rigid.h"
#include "raycast/mesh_raycaster.h"

namespace mvtm {

struct RoadFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d y_axis = Eigen::Vector3d::UnitY();
  double scale = 1;  // model units per metre

  // Planar metres (x, y) and a height h (metres along up) → world point.
  Eigen::Vector3d ToWorld(double x, double y, double h) const;
  // World point → planar metres, and its height in metres along up.
  Eigen::Vector2d ToPlane(const Eigen::Vector3d& p) const;
  double Height(const Eigen::Vector3d& p) const;
  // Heading (radians from x_axis, counter-clockwise about up) of a world direction projected to
  // the plane. Throws Error when the direction is (nearly) along up.
  double Heading(const Eigen::Vector3d& direction) const;
  // World direction of a planar heading.
  Eigen::Vector3d Direction(double heading) const;
};

// The normalised mean of the cameras' up axes (−y of world-to-camera poses). Throws Error when
// there are none or they cancel.
Eigen::Vector3d RecordedUp(const std::vector<Rigid3d>& world_to_camera);

// The road frame at a recorded camera: origin its centre, x its viewing direction made level.
RoadFrame FrameAtCamera(const Rigid3d& world_to_camera, const Eigen::Vector3d& up, double scale);

// The planar pose (metres) of a recorded camera's foot point and heading in `frame`.
PlanarPose PlanarCamera(const RoadFrame& frame, const Rigid3d& world_to_camera);

// Height of each camera above the first surface straight below it (−up), in model units;
// cameras above no surface (within 1e6 model units) are left out.
std::vector<double> CameraHeights(const MeshRaycaster& mesh,
                                  const std::vector<Rigid3d>& world_to_camera,
                                  const Eigen::Vector3d& up);

struct CarGeometry {
  double wheelbase = 2.7;                                       // metres, rear to front axle
  double track = 1.6;                                           // metres, left to right wheel
  Eigen::Vector3d camera_offset = Eigen::Vector3d(0, 0, 1.65);  // metres forward, left, up
};

// The rear axle pose that puts the camera's foot point (the ground point below the camera) at
// `camera_foot` with the car heading its way: back by the camera offset's forward and left parts.
PlanarPose RearAxleUnder(const PlanarPose& camera_foot, const CarGeometry& car);

struct Placement {
  Rigid3d camera_to_world;
  double pitch = 0, roll = 0;                             // radians: nose up, left side up
  Eigen::Vector3d rear_ground = Eigen::Vector3d::Zero();  // ground point under the rear axle
};

class GroundPlacer {
 public:
  GroundPlacer(const MeshRaycaster& mesh, const RoadFrame& frame, const CarGeometry& car);
  // The camera pose of the car at `rear_axle`; `time` only names the moment in errors.
  Placement Place(const PlanarPose& rear_axle, double time);
  // Starts the next placement's rays as if the previous ground under every wheel were at
  // `height` metres along up (a car put down elsewhere on the road: simulate's resets), instead
  // of from the frame's origin.
  void StartFromGround(double height);
  // Places the next cars on `mesh` (a road's ground as the car moves between fragments: the
  // previous ground heights are kept). `mesh` must outlive its use.
  void UseMesh(const MeshRaycaster& mesh) { mesh_ = &mesh; }

  static constexpr double kClearance = 2.0;  // metres above the previous ground
  static constexpr double kMaxDrop = 20.0;   // metres below the ray's start

 private:
  const MeshRaycaster* mesh_;
  RoadFrame frame_;
  CarGeometry car_;
  bool first_ = true;
  double last_[4] = {0, 0, 0, 0};  // previous ground heights (metres) per wheel
};

}  // namespace mvtm
