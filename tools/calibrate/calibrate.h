// calibrate — a camera's intrinsics from views of a chessboard (OpenCV's calib3d): a folder of
// photos or a video segment → a COLMAP camera for the road build (orb2colmap --camera, or
// examples/road-build.sh's CALIB).
//
// Views: every image of the folder (sorted by name), or every --every'th frame of the video
// between --start and --end seconds. Corners: cv::findChessboardCornersSB (the sector-based
// detector, sub-pixel by itself), which finds the board or nothing: a view without the whole
// board is left out and counted. The views used are the first --max-views in order, spread over
// the found ones evenly when there are more.
// Fit: cv::calibrateCamera on the board's inner corners (--pattern COLSxROWS, --square the side
// in any unit: the intrinsics do not depend on it) for the COLMAP model asked for:
//   PINHOLE        fx fy cx cy, no distortion
//   SIMPLE_RADIAL  f cx cy k (fx = fy, one radial term)
//   RADIAL         f cx cy k1 k2
//   OPENCV         fx fy cx cy k1 k2 p1 p2 (the default)
// then views whose RMS reprojection error is over 3× the median view's (and over 0.5 px) are
// dropped and the fit redone once (a misdetected board, a blurred frame). The principal point
// is moved by half a pixel into COLMAP's convention (the top-left pixel's centre at (0.5, 0.5);
// OpenCV's is at (0, 0)).
// Outputs (OUTDIR/): a COLMAP model of the camera alone (cameras.txt with camera 1; images.txt
// and points3D.txt empty) and calibration.json (the camera,
// the RMS reprojection error in pixels, per-view errors and names, views found / used / dropped,
// the pattern); the camera spec line ("OPENCV W H fx fy cx cy k1 k2 p1 p2", what --camera takes)
// on standard output. Both are up to date by run/ledger.h as every tool's outputs.
#pragma once

#include <string>
#include <vector>

#include "run/option_table.h"

namespace mvtm {

enum class CalibModel { kPinhole, kSimpleRadial, kRadial, kOpenCV };
inline const std::vector<std::pair<CalibModel, std::string>> kCalibModels = {
    {CalibModel::kPinhole, "PINHOLE"},
    {CalibModel::kSimpleRadial, "SIMPLE_RADIAL"},
    {CalibModel::kRadial, "RADIAL"},
    {CalibModel::kOpenCV, "OPENCV"}};

struct CalibrateOptions {
  std::string input;            // folder of photos, or a video
  std::string outdir;           // cameras.txt, calibration.json
  std::string pattern = "9x6";  // inner corners, columns x rows
  double square = 1;            // the side of a square (any unit)
  CalibModel model = CalibModel::kOpenCV;
  int every = 10;      // video: every Nth frame
  double start = 0;    // video: seconds
  double end = 0;      // video: seconds (0: the end)
  int max_views = 40;  // views used at most
  bool force = false;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(CalibrateOptions& o);

struct CalibrateReport {
  bool up_to_date = false;
  std::string why;
  size_t views = 0, found = 0, used = 0, dropped = 0;
  double rms = 0;    // pixels
  std::string spec;  // "MODEL W H PARAMS..."
};

CalibrateReport RunCalibrate(const CalibrateOptions& options);

}  // namespace mvtm
