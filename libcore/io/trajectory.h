// mvtm — trajectory files: TUM, KITTI poses, KITTI calib, timestamps lists, NeRF transforms.
//
// Formats and conventions (all converted on entry; see geometry/rigid.h):
//  * TUM (also ORB-SLAM2 KeyFrameTrajectory.txt / CameraTrajectory.txt): one pose per line,
//    "timestamp tx ty tz qx qy qz qw", camera-to-world, '#' comments.
//    https://cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats
//  * KITTI odometry poses: 12 numbers per line, the row-major 3×4 camera-to-world [R|t] of cam0.
//    Line i is frame i; times come from times.txt (one number per line).
//  * KITTI calib.txt: lines "P0: 12 numbers" (rectified 3×4 projection matrices).
//  * A timestamps list: "timestamp [name]" per line (TUM rgb.txt: "timestamp rgb/NAME.png").
//  * NeRF transforms.json: camera-to-world 4×4 with OpenGL axes (x right, y up, z backward);
//    converted to camera axes (x right, y down, z forward) by negating the y and z columns.
// Every reader reports malformed input as "FILE:LINE: what" (field count, non-numeric,
// non-finite, zero-norm quaternion) and never crashes. Quaternions are normalised on read.
// The text readers take a stream as well as a path; `name` stands for FILE in messages ("-" for
// standard input). Stream readers read forward only: they work on pipes and std::cin.
// A COLMAP images.txt is parsed by io/colmap_model.h's reader (its rules and messages).
#pragma once

#include <istream>
#include <optional>
#include <string>
#include <vector>

#include "camera/camera.h"
#include "geometry/interpolate.h"

namespace mvtm {

enum class TrajectoryFormat { kAuto, kTum, kKitti, kColmap };

struct Trajectory {
  std::vector<StampedPose> poses;  // camera-to-world; time = timestamp, or frame index for KITTI
  std::vector<std::string> names;  // optional, parallel to poses (COLMAP images, NeRF frames)
};

// Detects TUM (8 fields), KITTI (12 fields) or a COLMAP images.txt (header comment or 10+ fields
// on alternating lines) from the first data line. Throws Error when none fits.
TrajectoryFormat DetectTrajectoryFormat(const std::string& path);
Trajectory ReadTum(const std::string& path);
Trajectory ReadTum(std::istream& in, const std::string& name);
// `times` (optional): KITTI times.txt giving each line's timestamp; else the line index.
Trajectory ReadKittiPoses(const std::string& path, const std::string& times_path = "");
Trajectory ReadKittiPoses(std::istream& in, const std::string& name);
// kAuto: the format is detected as by DetectTrajectoryFormat. The stream version keeps the
// lines read for detection and hands them to the reader, so it never seeks or reopens.
Trajectory ReadTrajectory(const std::string& path,
                          TrajectoryFormat format = TrajectoryFormat::kAuto);
Trajectory ReadTrajectory(std::istream& in, const std::string& name,
                          TrajectoryFormat format = TrajectoryFormat::kAuto);
// Pose i's name: its name in the file (COLMAP images, NeRF frames), else its index as six digits
// ("000012"): the name every tool gives a row of a trajectory (ptmrender's frames, pickview's
// queries, mkroad's truth at the poses).
std::string PoseName(const Trajectory& trajectory, size_t i);
void WriteTum(const std::string& path, const std::vector<StampedPose>& c2w);
// One TUM line without its newline: "timestamp tx ty tz qx qy qz qw" of a camera-to-world pose,
// numbers that read back exactly (WriteTum's rows; simulate streams them).
std::string TumRow(double time, const Rigid3d& c2w);
void WriteKittiPoses(const std::string& path, const std::vector<StampedPose>& c2w);

struct TimedName {
  double time = 0;
  std::string name;  // may be empty
  long line = 0;
};
// "timestamp [name]" per line; also reads KITTI times.txt (no names) and TUM rgb.txt.
std::vector<TimedName> ReadTimestamps(const std::string& path);
std::vector<TimedName> ReadTimestamps(std::istream& in, const std::string& name);

// KITTI calib.txt: the pinhole camera of projection matrix Pn (fx=P[0][0], fy=P[1][1],
// cx=P[0][2], cy=P[1][2]) with the given image size.
Camera ReadKittiCalib(const std::string& path, int cam_index, uint64_t width, uint64_t height);
// KITTI's rectified cameras share one orientation and differ by a translation: Pn = K [I | tn],
// so a point x0 in camera 0's coordinates is x0 + tn in camera n's. Returns tn = K⁻¹ Pn[:, 3]
// (metres; camera 1, 0.54 m right of camera 0, has tn ≈ (−0.54, 0, 0)).
Eigen::Vector3d ReadKittiCameraOffset(const std::string& path, int cam_index);

// ORB-SLAM2 settings YAML (Camera.fx/fy/cx/cy/k1/k2/p1/p2[/k3], Camera.width/height), read with
// cv::FileStorage. PINHOLE when all distortion terms are zero, else OPENCV (k3 must be zero;
// FULL_OPENCV when it is not). width/height override the file's when non-zero.
Camera ReadOrbSettings(const std::string& path, uint64_t width = 0, uint64_t height = 0);

// NeRF transforms.json: camera (PINHOLE, or OPENCV with k1 k2 p1 p2) and camera-to-world poses
// with names (file_path). Throws Error naming the JSON path of a bad field.
struct NerfScene {
  Camera camera;
  Trajectory frames;
};
NerfScene ReadNerfTransforms(const std::string& path);

}  // namespace mvtm
