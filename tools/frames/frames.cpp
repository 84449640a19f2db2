#include "frames.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <set>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "cli/work.h"
#include "image/folder.h"
#include "image/image.h"
#include "image/mask.h"
#include "run/ledger.h"
#include "video/capture.h"

namespace mvtm {

namespace fs = std::filesystem;

namespace {

struct Crop {
  int w = 0, h = 0, x = 0, y = 0;
  bool empty() const { return w == 0; }
};

// "WxH+X+Y" (ImageMagick's geometry).
Crop ParseCrop(const std::string& s) {
  Crop c;
  char tail = 0;
  if (std::sscanf(s.c_str(), "%dx%d+%d+%d%c", &c.w, &c.h, &c.x, &c.y, &tail) != 4 || c.w <= 0 ||
      c.h <= 0 || c.x < 0 || c.y < 0)
    throw UsageError("--crop: '" + s + "' is not WxH+X+Y (e.g. 1280x600+0+0)");
  return c;
}

}  // namespace

OptionTable DeclareOptions(FramesOptions& o) {
  OptionTable t("frames");
  t.Positional("VIDEO", &o.video, "Video file (any container and codec FFmpeg reads)").File();
  t.Positional("OUTDIR", &o.outdir, "Folder for images/, frames.tsv, mask.png and colmap_mask.png")
      .Dir();
  t.Real("--spacing", &o.select.spacing,
         "Median image motion between kept frames, as a fraction of the image width")
      .Range(0, 1, true);
  t.Real("--blur-ratio", &o.select.blur_ratio,
         "A frame is blurred (dropped) when its sharpness (variance of the Laplacian) is below "
         "this times the median of the recent frames; 0 keeps every frame")
      .Range(0, 1, false, true);
  t.Integer("--blur-window", &o.select.blur_window, "Recent frames in that median").Range(1, 1000);
  t.Flag("--no-overlay", &o.select.no_overlay,
         "Do not look for burned-in overlays (static text and logos)");
  t.Text("--crop", &o.crop, "Keep only this part of each frame, WxH+X+Y (e.g. cut off the bonnet)")
      .Alternative("64x48+0+0")
      .Check([&o] {
        if (!o.crop.empty()) ParseCrop(o.crop);
      });
  t.Text("--mask", &o.mask,
         "PNG of the video's size, non-zero = not the scene (bonnet, logo): no motion is measured "
         "there and it goes into mask.png")
      .File();
  t.Flag("--force", &o.force, "Rewrite every output even when up to date").Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void FramesOptions::Check() const {
  CheckDeclared(*this);
  if (!fs::is_regular_file(video)) throw UsageError("VIDEO: '" + video + "' is not a file");
}

namespace {

Image ToImage(const cv::Mat& bgr) {
  Image img(bgr.cols, bgr.rows, 3);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* row = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = row[x][2 - c];
  }
  return img;
}

// masked = 255 (mvtm's masks), or with `keep` the other way round: COLMAP's camera mask, where
// black pixels give no features.
Image MaskImage(const cv::Mat& m, bool keep = false) {
  Image img(m.cols, m.rows, 1);
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x) img.at(x, y) = (m.at<uchar>(y, x) != 0) != keep ? 255.f : 0.f;
  return img;
}

// --mask at the video's size, as a cv::Mat (image/mask.h: any non-zero channel is masked).
cv::Mat ReadMaskMat(const std::string& path, int w, int h) {
  const Image m = ReadMask(path);
  RequireImageSize(m, path, static_cast<uint64_t>(w), static_cast<uint64_t>(h));
  cv::Mat out(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) out.at<uchar>(y, x) = m.at(x, y) > 0 ? 255 : 0;
  return out;
}

struct Kept {
  std::string name;
  long frame;
  double time, sharpness, motion;
};

}  // namespace

namespace {

// Images of an earlier selection that this one does not keep.
void RemoveUnkept(const fs::path& images, const std::set<std::string>& names, FramesReport& rep) {
  if (!fs::is_directory(images)) return;
  for (const auto& e : fs::directory_iterator(images)) {
    const std::string n = e.path().filename().string();
    if (e.is_regular_file() && n.size() == 10 && n.substr(6) == ".png" && !names.count(n)) {
      fs::remove(e.path());
      ++rep.removed;
    }
  }
}

// mask.png and colmap_mask.png: the overlay found and the user's mask; none when both are empty.
void WriteMasks(cv::Mat mask, const cv::Mat& user_mask, const fs::path& out, Ledger& ledger,
                FramesReport& rep) {
  const fs::path mask_png = out / "mask.png", colmap_mask_png = out / "colmap_mask.png";
  rep.overlay_pixels = mask.empty() ? 0 : static_cast<size_t>(cv::countNonZero(mask));
  if (!user_mask.empty()) mask = mask.empty() ? user_mask : (mask | user_mask);
  if (!mask.empty() && cv::countNonZero(mask) > 0) {
    WriteImage(mask_png.string(), MaskImage(mask), PngCompression::kFastFlat);
    WriteImage(colmap_mask_png.string(), MaskImage(mask, true), PngCompression::kFastFlat);
    ledger.Done(mask_png);
    ledger.Done(colmap_mask_png);
  } else {  // an earlier run's: this selection masks nothing
    fs::remove(mask_png);
    fs::remove(colmap_mask_png);
  }
}

void CheckSelection(const FramesOptions& o, const FramesReport& rep) {
  if (rep.decoded == 0)
    throw Error(o.video, 0,
                "no frame could be decoded (an empty or truncated file, or a codec FFmpeg cannot "
                "decode)");
  if (rep.kept < 2)
    throw Error(o.video, 0,
                "the video never moves: " + std::to_string(rep.decoded) + " frames decoded, " +
                    std::to_string(rep.kept) +
                    " kept (a road build needs frames from different places; --spacing " +
                    std::to_string(o.select.spacing) + ")");
}

FramesReport RunFramesInto(const FramesOptions& o) {
  FramesReport rep;
  const fs::path out(o.outdir), images = out / "images", tsv = out / "frames.tsv";
  FramesOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  std::vector<fs::path> inputs{o.video};
  if (!o.mask.empty()) inputs.emplace_back(o.mask);
  Ledger ledger(out, "frames", table, inputs, fs::path());
  RemoveStaleTemporaries(out);
  if (ledger.Stale(tsv, {}, o.force).empty()) {
    rep.up_to_date = true;
    return rep;
  }
  rep.why = ledger.Summary();
  const std::unique_ptr<cv::VideoCapture> video = OpenVideo(o.video);
  cv::VideoCapture& cap = *video;
  const double fps = cap.get(cv::CAP_PROP_FPS);
  const double announced = cap.get(cv::CAP_PROP_FRAME_COUNT);
  rep.expected = announced > 0 && std::isfinite(announced) ? static_cast<size_t>(announced) : 0;
  const Crop crop = o.crop.empty() ? Crop() : ParseCrop(o.crop);

  std::unique_ptr<FrameSelector> selector;
  cv::Mat user_mask;  // cropped
  std::vector<Kept> kept;
  std::set<std::string> names;
  Progress progress("frames", rep.expected, o.quiet);
  cv::Mat frame, grey;
  double last_time = -std::numeric_limits<double>::infinity();
  bool times_ok = true;
  for (long index = 0; cap.read(frame); ++index) {
    progress.Step();
    if (frame.empty()) break;
    ++rep.decoded;
    if (frame.channels() == 1) cv::cvtColor(frame, frame, cv::COLOR_GRAY2BGR);
    if (!selector) {
      if (!crop.empty() && (crop.x + crop.w > frame.cols || crop.y + crop.h > frame.rows))
        throw UsageError("--crop " + o.crop + " reaches outside the " + std::to_string(frame.cols) +
                         "x" + std::to_string(frame.rows) + " frames");
      if (!o.mask.empty()) {
        user_mask = ReadMaskMat(o.mask, frame.cols, frame.rows);
        if (!crop.empty()) user_mask = user_mask(cv::Rect(crop.x, crop.y, crop.w, crop.h)).clone();
      }
      selector = std::make_unique<FrameSelector>(o.select, user_mask);
    }
    if (!crop.empty()) frame = frame(cv::Rect(crop.x, crop.y, crop.w, crop.h));
    // The decoder's presentation time, else the frame index over the frame rate.
    double t = cap.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    if (!std::isfinite(t) || t <= last_time) times_ok = false;
    last_time = t;
    if (!times_ok) t = fps > 0 ? static_cast<double>(index) / fps : static_cast<double>(index);
    rep.duration = t;
    cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    const FrameDecision d = selector->Next(grey);
    rep.blurred += d.blurred;
    rep.still += !d.blurred && !d.keep;
    if (!d.keep) continue;
    char name[32];
    std::snprintf(name, sizeof name, "%06ld.png", index);
    kept.push_back({name, index, t, d.sharpness, std::isfinite(d.motion) ? d.motion : -1});
    names.insert(name);
    const fs::path path = images / name;
    if (ledger.Stale(path, {}, o.force).empty()) continue;
    WriteImage(path.string(), ToImage(frame), PngCompression::kFast);
    ledger.Done(path);
    ++rep.written;
  }
  rep.kept = kept.size();
  CheckSelection(o, rep);
  RemoveUnkept(images, names, rep);
  WriteMasks(selector->Overlay(), user_mask, out, ledger, rep);
  WriteTextAtomic(tsv, [&](std::ostream& os) {
    os << "name\tframe\ttime\tsharpness\tmotion\n";
    for (const Kept& k : kept)
      os << k.name << '\t' << k.frame << '\t' << k.time << '\t' << k.sharpness << '\t' << k.motion
         << '\n';
  });
  ledger.Done(tsv);
  ledger.Write();
  return rep;
}

}  // namespace

FramesReport RunFrames(const FramesOptions& o) {
  o.Check();
  // A video that cannot be used leaves no output folder behind when this run made it. In an
  // existing one, the ledger keeps frames.tsv stale until a run completes, so a rerun redoes it.
  const bool fresh = !fs::exists(o.outdir);
  try {
    return RunFramesInto(o);
  } catch (const Error&) {
    std::error_code ec;
    if (fresh) fs::remove_all(o.outdir, ec);
    throw;
  }
}

}  // namespace mvtm
