#include "video/frame_select.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "base/stats.h"

namespace mvtm {

namespace {

constexpr int kWorkWidth = 640;
constexpr int kTileCols = 8, kTileRows = 4;
constexpr int kMaxCorners = 500;
constexpr size_t kMinTracked = 15;
constexpr double kMinTrackedShare = 0.2;
constexpr int kStillLevels = 6;
constexpr double kStillShare = 0.97;
constexpr double kEdgeMagnitude = 40;
constexpr double kEdgeShare = 0.8;
constexpr size_t kMinPairs = 8;

// The frame at most kWorkWidth wide (area averaging), or itself.
cv::Mat Working(const cv::Mat& grey) {
  if (grey.cols <= kWorkWidth) return grey;
  cv::Mat small;
  const double f = static_cast<double>(kWorkWidth) / grey.cols;
  cv::resize(grey, small, cv::Size(), f, f, cv::INTER_AREA);
  return small;
}

}  // namespace

double Sharpness(const cv::Mat& grey) {
  cv::Mat lap;
  cv::Laplacian(Working(grey), lap, CV_64F);
  // The variance of the Laplacian per tile, and its upper quartile over the tiles: textured
  // tiles decide (sky and flat road do not dilute it), and a small sharp overlay burned in after
  // the blur (a clock) cannot make a blurred frame look sharp.
  std::vector<double> tiles;
  for (int ty = 0; ty < kTileRows; ++ty)
    for (int tx = 0; tx < kTileCols; ++tx) {
      const int x0 = tx * lap.cols / kTileCols, x1 = (tx + 1) * lap.cols / kTileCols;
      const int y0 = ty * lap.rows / kTileRows, y1 = (ty + 1) * lap.rows / kTileRows;
      if (x1 <= x0 || y1 <= y0) continue;
      cv::Scalar mean, dev;
      cv::meanStdDev(lap(cv::Rect(x0, y0, x1 - x0, y1 - y0)), mean, dev);
      tiles.push_back(dev[0] * dev[0]);
    }
  if (tiles.empty()) return 0;
  const size_t q = tiles.size() * 3 / 4;
  std::nth_element(tiles.begin(), tiles.begin() + q, tiles.end());
  return tiles[q];
}

FrameSelector::FrameSelector(const FrameSelectOptions& options, cv::Mat mask)
    : o_(options), mask_(std::move(mask)) {}

double FrameSelector::StepMotion(const cv::Mat& small) const {
  if (prev_pts_.size() < kMinTracked) return std::numeric_limits<double>::infinity();
  std::vector<cv::Point2f> fwd, back;
  std::vector<uchar> ok_f, ok_b;
  std::vector<float> err;
  const cv::Size win(21, 21);
  cv::calcOpticalFlowPyrLK(prev_small_, small, prev_pts_, fwd, ok_f, err, win, 3);
  cv::calcOpticalFlowPyrLK(small, prev_small_, fwd, back, ok_b, err, win, 3);
  std::vector<double> d;
  for (size_t i = 0; i < prev_pts_.size(); ++i) {
    if (!ok_f[i] || !ok_b[i]) continue;
    const cv::Point2f e = back[i] - prev_pts_[i];
    if (e.x * e.x + e.y * e.y > 1.0f) continue;
    const cv::Point2f m = fwd[i] - prev_pts_[i];
    d.push_back(std::sqrt(static_cast<double>(m.x * m.x + m.y * m.y)));
  }
  if (d.size() < kMinTracked ||
      static_cast<double>(d.size()) < kMinTrackedShare * static_cast<double>(prev_pts_.size()))
    return std::numeric_limits<double>::infinity();
  return Median(d) / small.cols;
}

void FrameSelector::Corners(const cv::Mat& small) {
  // Corners away from the masked pixels (the user's mask and the overlay found so far).
  cv::Mat avoid;
  if (!mask_.empty()) cv::resize(mask_, avoid, small.size(), 0, 0, cv::INTER_NEAREST);
  if (overlay_dirty_) {
    overlay_ = Overlay();
    overlay_dirty_ = false;
  }
  if (!overlay_.empty()) {
    cv::Mat o;
    cv::resize(overlay_, o, small.size(), 0, 0, cv::INTER_NEAREST);
    avoid = avoid.empty() ? o : (avoid | o);
  }
  cv::Mat allowed;
  if (!avoid.empty()) allowed = avoid == 0;
  prev_pts_.clear();
  cv::goodFeaturesToTrack(small, prev_pts_, kMaxCorners, 0.01, std::max(4, small.cols / 80),
                          allowed);
  prev_small_ = small;
}

void FrameSelector::Keep(const cv::Mat& grey) {
  if (!o_.no_overlay) {
    if (unchanged_.empty()) {
      unchanged_ = cv::Mat::zeros(grey.size(), CV_32S);
      edged_ = cv::Mat::zeros(grey.size(), CV_32S);
    }
    if (have_key_) {
      cv::Mat diff;
      cv::absdiff(grey, key_grey_, diff);
      cv::Mat still = diff <= kStillLevels;  // 255 where unchanged
      cv::add(unchanged_, 1, unchanged_, still, CV_32S);
      ++pairs_;
    }
    cv::Mat gx, gy, mag;
    cv::Sobel(grey, gx, CV_32F, 1, 0);
    cv::Sobel(grey, gy, CV_32F, 0, 1);
    cv::magnitude(gx, gy, mag);
    cv::Mat edge = mag >= kEdgeMagnitude;
    cv::add(edged_, 1, edged_, edge, CV_32S);
  }
  ++kept_;
  overlay_dirty_ = true;
  have_key_ = true;
  key_grey_ = grey.clone();
}

FrameDecision FrameSelector::Next(const cv::Mat& grey) {
  FrameDecision d;
  const cv::Mat small = Working(grey);
  d.sharpness = Sharpness(small);
  const double recent_median = Median(recent_);
  d.blurred = !recent_.empty() && d.sharpness < o_.blur_ratio * recent_median;
  if (recent_.size() < static_cast<size_t>(o_.blur_window)) {
    recent_.push_back(d.sharpness);
  } else {
    recent_[recent_next_] = d.sharpness;
    recent_next_ = (recent_next_ + 1) % recent_.size();
  }
  // Travelled image motion: the per-step medians summed since the last kept frame (a step
  // between consecutive frames tracks well even when the view changes fast).
  if (!have_key_ || prev_small_.empty())
    travelled_ = std::numeric_limits<double>::infinity();
  else
    travelled_ += StepMotion(small);
  d.motion = travelled_;
  d.keep = !d.blurred && d.motion >= o_.spacing;
  if (d.keep) {
    Keep(grey);
    travelled_ = 0;
  }
  Corners(small.clone());
  return d;
}

cv::Mat FrameSelector::Overlay() const {
  if (o_.no_overlay || pairs_ < kMinPairs) return cv::Mat();
  const cv::Mat still = unchanged_ >= std::ceil(kStillShare * static_cast<double>(pairs_));
  const cv::Mat edged = edged_ >= std::ceil(kEdgeShare * static_cast<double>(kept_));
  cv::Mat overlay = still & edged;
  if (cv::countNonZero(overlay) == 0) return cv::Mat();
  const cv::Mat k = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(15, 15));
  cv::morphologyEx(overlay, overlay, cv::MORPH_CLOSE, k);
  cv::dilate(overlay, overlay, k);
  return overlay;
}

}  // namespace mvtm
