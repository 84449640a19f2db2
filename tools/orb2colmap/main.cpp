// orb2colmap — thin main: option table, then RunOrb2Colmap().
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "orb2colmap.h"

int main(int argc, char** argv) {
  mvtm::Orb2ColmapOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "orb2colmap",
      "Convert ORB-SLAM2 keyframe or ground-truth poses (TUM or KITTI, camera-to-world) "
      "into a COLMAP model of every frame, interpolating between keyframes.");
  app.add_option("TRAJECTORY", o.trajectory,
                 "Poses: ORB-SLAM2 KeyFrameTrajectory/CameraTrajectory or TUM (t tx ty tz qx qy qz "
                 "qw), or KITTI 3x4 rows")
      ->required();
  app.add_option("OUTDIR", o.outdir, "Folder for cameras, images, points3D (.txt or .bin)")
      ->required();
  mvtm::AddChoiceOption(app, "--input-format", o.input_format, mvtm::kOrbInputFormats,
                        "Trajectory format");
  app.add_option("--trajectory-times", o.trajectory_times,
                 "KITTI: times.txt with the timestamp of each pose line (default: line index)");
  app.add_option("--frames", o.frames,
                 "Frame timestamps: KITTI times.txt, TUM rgb.txt, or 'timestamp name' lines "
                 "(default: the trajectory's own poses)");
  app.add_option("--images", o.images, "Folder of frame images; sorted file names name the frames");
  auto* cam = app.add_option("--camera", o.camera,
                             "Intrinsics as 'MODEL W H PARAMS...' (COLMAP model, e.g. 'PINHOLE "
                             "1241 376 718.856 718.856 607.19 185.22')");
  auto* orb = app.add_option("--orb-settings", o.orb_settings,
                             "Intrinsics from an ORB-SLAM2 settings YAML (Camera.fx ...)");
  auto* kc = app.add_option("--kitti-calib", o.kitti_calib, "Intrinsics from a KITTI calib.txt");
  app.add_option("--kitti-cam", o.kitti_cam, "Which projection matrix Pn of --kitti-calib")
      ->capture_default_str()
      ->check(CLI::Range(0, 3));
  app.add_option("--size", o.size,
                 "Image size WxH when the intrinsics source has none (else read from --images)");
  app.add_flag("--binary", o.binary, "Write cameras.bin, images.bin, points3D.bin");
  app.add_option("--database", o.database,
                 "Create or fill a COLMAP database.db: cameras, images with pose priors");
  mvtm::AddChoiceOption(app, "--outside", o.outside, mvtm::kOrbOutside,
                        "Frames outside the keyframe time span");
  app.add_flag("--force", o.force, "Rewrite the model even when it is newer than every input");
  mvtm::AddQuietOption(app, o.quiet);
  cam->excludes(orb)->excludes(kc);
  orb->excludes(kc);
  return mvtm::RunMain(app, "orb2colmap", argc, argv, [&] {
    auto r = mvtm::RunOrb2Colmap(o);
    if (r.up_to_date) {
      if (!o.quiet)
        std::cerr << "orb2colmap: " << o.outdir << " is up to date (use --force to rewrite)\n";
      return 0;
    }
    if (!o.quiet) {
      std::cerr << "orb2colmap: " << r.written << " frames written from " << r.keyframes
                << " poses";
      if (r.dropped) std::cerr << "; " << r.dropped << " outside the pose time span dropped";
      if (r.clamped) std::cerr << "; " << r.clamped << " outside the pose time span clamped";
      if (r.reordered) std::cerr << "; " << r.reordered << " poses were out of time order (sorted)";
      std::cerr << "\n";
    }
    return 0;
  });
}
