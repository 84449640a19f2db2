#include "calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "camera/camera.h"
#include "cli/work.h"
#include "image/folder.h"
#include "image/image.h"
#include "io/colmap_model.h"
#include "run/ledger.h"
#include "video/capture.h"

namespace mvtm {

namespace fs = std::filesystem;

namespace {

cv::Size ParsePattern(const std::string& s) {
  const size_t x = s.find('x');
  const std::string cols = x == std::string::npos ? "" : s.substr(0, x);
  const std::string rows = x == std::string::npos ? "" : s.substr(x + 1);
  char* e1 = nullptr;
  char* e2 = nullptr;
  const long c = std::strtol(cols.c_str(), &e1, 10);
  const long r = std::strtol(rows.c_str(), &e2, 10);
  if (x == std::string::npos || cols.empty() || rows.empty() || *e1 || *e2 || c < 3 || r < 3 ||
      c > 100 || r > 100)
    throw FieldError("pattern", "expected COLSxROWS inner corners, each 3..100, got '" + s + "'");
  return {static_cast<int>(c), static_cast<int>(r)};
}

}  // namespace

OptionTable DeclareOptions(CalibrateOptions& o) {
  OptionTable t("calibrate");
  t.Positional(
      "INPUT", &o.input,
      "Views of a chessboard: a folder of photos, or a video (any container FFmpeg reads)");
  t.Positional("OUTDIR", &o.outdir, "Folder for cameras.txt and calibration.json").Dir();
  t.Text("--pattern", &o.pattern, "The board's inner corners, COLSxROWS (a 10x7-square board: 9x6)")
      .Alternative("7x5")
      .Check([&o] { ParsePattern(o.pattern); });
  t.Real("--square", &o.square,
         "Side of a square, any unit (recorded; the intrinsics do not "
         "depend on it)")
      .Range(0, 1e6, true);
  t.Choice("--model", &o.model, kCalibModels, "COLMAP camera model to fit");
  t.Integer("--every", &o.every, "Video: use every Nth frame").Range(1, 100000);
  t.Real("--start", &o.start, "Video: first second used").Range(0, 1e7);
  t.Real("--end", &o.end, "Video: last second used (0: the end)").Range(0, 1e7);
  t.Integer("--max-views", &o.max_views, "Views used at most, spread over those found")
      .Range(3, 1000);
  t.Flag("--force", &o.force, "Rewrite the outputs even when up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void CalibrateOptions::Check() const {
  CheckDeclared(*this);
  if (!fs::exists(input)) throw UsageError("INPUT: '" + input + "' does not exist");
  if (end != 0 && end <= start) throw UsageError("--end must be after --start");
}

namespace {

// A view is an outlier when its RMS reprojection error is over 3× the median view's and over
// this many pixels (with sub-pixel corners every view is within a fraction of a pixel).
constexpr double kMinOutlierError = 0.5;

struct View {
  std::string name;
  std::vector<cv::Point2f> corners;
};

// Corners of the board in one grey image; false when the whole board is not found.
bool FindBoard(const cv::Mat& grey, cv::Size pattern, std::vector<cv::Point2f>& corners) {
  return cv::findChessboardCornersSB(grey, pattern, corners, cv::CALIB_CB_ACCURACY);
}

// An image of any depth (image/image.h: 8 or 16 bits, or float in [0, 1]) as 8-bit grey: the
// luma of RGB, else the first channel.
cv::Mat Grey8(const Image& img) {
  cv::Mat out(img.height, img.width, CV_8U);
  const double to8 = 255.0 / img.MaxValue();
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double v = img.channels >= 3 ? 0.299 * img.at(x, y, 0) + 0.587 * img.at(x, y, 1) +
                                               0.114 * img.at(x, y, 2)
                                         : img.at(x, y, 0);
      out.at<uchar>(y, x) = cv::saturate_cast<uchar>(v * to8);
    }
  return out;
}

std::vector<View> ReadViews(const CalibrateOptions& o, cv::Size pattern, cv::Size& size,
                            size_t& seen) {
  std::vector<View> views;
  auto take = [&](const cv::Mat& img, const std::string& name) {
    cv::Mat grey;
    if (img.channels() == 3)
      cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
    else if (img.channels() == 4)
      cv::cvtColor(img, grey, cv::COLOR_BGRA2GRAY);
    else
      grey = img;
    if (size.width == 0) size = grey.size();
    if (grey.size() != size)
      throw Error(name, 0,
                  "is " + std::to_string(grey.cols) + "x" + std::to_string(grey.rows) +
                      ", the first view " + std::to_string(size.width) + "x" +
                      std::to_string(size.height) + ": one camera, one size");
    ++seen;
    View v{name, {}};
    if (FindBoard(grey, pattern, v.corners)) views.push_back(std::move(v));
  };
  if (fs::is_directory(o.input)) {
    const std::vector<std::string> files = ListImageFiles(o.input);
    if (files.empty()) throw Error(o.input, 0, "no images in the folder");
    for (const std::string& f : files) {
      const std::string path = (fs::path(o.input) / f).string();
      take(Grey8(ReadImage(path)), f);
    }
    return views;
  }
  const std::unique_ptr<cv::VideoCapture> video = OpenVideo(o.input);
  cv::VideoCapture& cap = *video;
  const double fps = cap.get(cv::CAP_PROP_FPS) > 0 ? cap.get(cv::CAP_PROP_FPS) : 30;
  cv::Mat frame;
  long used = 0;  // frames within [start, end], counted for --every
  for (long i = 0; cap.read(frame); ++i) {
    // The decoder's timestamp (variable frame rates), else the index over the frame rate.
    const double ms = cap.get(cv::CAP_PROP_POS_MSEC);
    const double t = ms > 0 || i == 0 ? ms / 1000 : static_cast<double>(i) / fps;
    if (t < o.start) continue;
    if (o.end > 0 && t > o.end) break;
    if (used++ % o.every != 0) continue;
    take(frame, "frame " + std::to_string(i));
  }
  if (seen == 0) throw Error(o.input, 0, "no frame decoded in the time range");
  return views;
}

int Flags(CalibModel m) {
  // k3 and the rational terms are never fitted (COLMAP's models have none of them).
  int f = cv::CALIB_FIX_K3 | cv::CALIB_FIX_K4 | cv::CALIB_FIX_K5 | cv::CALIB_FIX_K6;
  switch (m) {
    case CalibModel::kPinhole:
      return f | cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_ZERO_TANGENT_DIST;
    case CalibModel::kSimpleRadial:
      return f | cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_FIX_K2 | cv::CALIB_ZERO_TANGENT_DIST;
    case CalibModel::kRadial:
      return f | cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_ZERO_TANGENT_DIST;
    case CalibModel::kOpenCV:
      return f;
  }
  return f;
}

Camera ToCamera(CalibModel m, cv::Size size, const cv::Mat& K, const cv::Mat& d) {
  Camera c;
  c.id = 1;
  c.width = static_cast<uint64_t>(size.width);
  c.height = static_cast<uint64_t>(size.height);
  // OpenCV puts the centre of the top-left pixel at (0, 0), COLMAP at (0.5, 0.5).
  const double fx = K.at<double>(0, 0), fy = K.at<double>(1, 1), cx = K.at<double>(0, 2) + 0.5,
               cy = K.at<double>(1, 2) + 0.5;
  auto dist = [&](int i) { return d.at<double>(i); };
  switch (m) {
    case CalibModel::kPinhole:
      c.model = CameraModel::kPinhole;
      c.params = {fx, fy, cx, cy};
      break;
    case CalibModel::kSimpleRadial:
      c.model = CameraModel::kSimpleRadial;
      c.params = {fx, cx, cy, dist(0)};
      break;
    case CalibModel::kRadial:
      c.model = CameraModel::kRadial;
      c.params = {fx, cx, cy, dist(0), dist(1)};
      break;
    case CalibModel::kOpenCV:
      c.model = CameraModel::kOpenCV;
      c.params = {fx, fy, cx, cy, dist(0), dist(1), dist(2), dist(3)};
      break;
  }
  return c;
}

std::string Spec(const Camera& c) {
  std::ostringstream s;
  s.precision(10);
  s << CameraModelName(c.model) << ' ' << c.width << ' ' << c.height;
  for (double p : c.params) s << ' ' << p;
  return s.str();
}

struct Fit {
  cv::Mat K, d;
  double rms = 0;
  std::vector<double> per_view;
};

Fit Calibrate(const std::vector<View>& views, cv::Size pattern, double square, cv::Size size,
              CalibModel m) {
  std::vector<cv::Point3f> board;
  for (int r = 0; r < pattern.height; ++r)
    for (int c = 0; c < pattern.width; ++c)
      board.emplace_back(static_cast<float>(c * square), static_cast<float>(r * square), 0.f);
  std::vector<std::vector<cv::Point3f>> obj(views.size(), board);
  std::vector<std::vector<cv::Point2f>> img;
  for (const View& v : views) img.push_back(v.corners);
  Fit f;
  f.K = cv::Mat::eye(3, 3, CV_64F);
  f.d = cv::Mat::zeros(5, 1, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_in, std_ex, errs;
  f.rms = cv::calibrateCamera(
      obj, img, size, f.K, f.d, rvecs, tvecs, std_in, std_ex, errs, Flags(m),
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  for (int i = 0; i < errs.rows; ++i) f.per_view.push_back(errs.at<double>(i));
  return f;
}

}  // namespace

CalibrateReport RunCalibrate(const CalibrateOptions& o) {
  o.Check();
  CalibrateReport rep;
  const cv::Size pattern = ParsePattern(o.pattern);
  std::vector<fs::path> inputs;
  if (fs::is_directory(o.input)) {
    for (const std::string& f : ListImageFiles(o.input)) inputs.push_back(fs::path(o.input) / f);
  } else {
    inputs.emplace_back(o.input);
  }
  CalibrateOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(o.outdir, "calibrate", table, inputs, fs::path());
  const fs::path json = fs::path(o.outdir) / "calibration.json";
  std::vector<fs::path> outputs{json};
  for (const auto& f : ColmapModelFileNames(false)) outputs.push_back(fs::path(o.outdir) / f);
  const bool stale = ledger.AnyStale(outputs, {}, o.force);
  rep.why = ledger.Summary();
  RemoveStaleTemporaries(o.outdir);
  if (!stale) {
    // The spec from the camera written before.
    const Reconstruction r = ReadColmapModel(o.outdir);
    rep.spec = Spec(r.cameras.begin()->second);
    rep.up_to_date = true;
    return rep;
  }
  cv::Size size(0, 0);
  std::vector<View> views = ReadViews(o, pattern, size, rep.views);
  rep.found = views.size();
  if (views.size() < 3)
    throw Error(o.input, 0,
                "the " + o.pattern + " board was found in " + std::to_string(views.size()) +
                    " of " + std::to_string(rep.views) +
                    " views: need 3 (check --pattern: inner corners, not squares)");
  if (views.size() > static_cast<size_t>(o.max_views)) {  // spread evenly
    std::vector<View> kept;
    for (int i = 0; i < o.max_views; ++i)
      kept.push_back(views[static_cast<size_t>(i) * views.size() / o.max_views]);
    views.swap(kept);
  }
  Fit fit = Calibrate(views, pattern, o.square, size, o.model);
  std::vector<double> sorted = fit.per_view;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::vector<View> good;
  for (size_t i = 0; i < views.size(); ++i)
    if (fit.per_view[i] <= std::max(3 * median, kMinOutlierError)) good.push_back(views[i]);
  if (good.size() < views.size() && good.size() >= 3) {
    rep.dropped = views.size() - good.size();
    views.swap(good);
    fit = Calibrate(views, pattern, o.square, size, o.model);
  }
  rep.used = views.size();
  rep.rms = fit.rms;
  const Camera cam = ToCamera(o.model, size, fit.K, fit.d);
  const std::string problem = CameraProblem(cam);
  if (!problem.empty()) throw Error(o.input, 0, "the fit gave an unusable camera: " + problem);
  rep.spec = Spec(cam);
  Reconstruction r;
  r.cameras[cam.id] = cam;
  CreateFolder(o.outdir);
  WriteColmapText(r, o.outdir);  // a model of the camera alone: images, points3D empty
  nlohmann::json j;
  j["camera"] = rep.spec;
  j["rms_pixels"] = fit.rms;
  j["pattern"] = o.pattern;
  j["square"] = o.square;
  j["views"] = rep.views;
  j["found"] = rep.found;
  j["used"] = rep.used;
  j["dropped"] = rep.dropped;
  for (size_t i = 0; i < views.size(); ++i)
    j["per_view"].push_back({{"view", views[i].name}, {"rms_pixels", fit.per_view[i]}});
  WriteTextAtomic(json, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
  for (const fs::path& p : outputs) ledger.Done(p);
  ledger.Write();
  return rep;
}

}  // namespace mvtm
