#include "track/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <tuple>

#include "base/error.h"

namespace mvtm {

namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Rounds half up, the same on every platform (std::lround rounds half away from zero).
int RoundHalfUp(double v) { return static_cast<int>(std::floor(v + 0.5)); }

// Gaussian-weighted local linear fit of (t_j, y_j) evaluated at t_j for j = i, using the samples
// with |t_j - t_i| <= 3 sigma. Reproduces y = a + b t exactly.
struct Smoother {
  double sigma;
  void Apply(const std::vector<double>& t, std::vector<double>& y) const {
    if (sigma <= 0 || t.size() < 2) return;
    const std::vector<double> in = y;
    const double reach = 3 * sigma, k = -0.5 / (sigma * sigma);
    size_t lo = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      while (t[i] - t[lo] > reach) ++lo;
      double s0 = 0, s1 = 0, s2 = 0, q0 = 0, q1 = 0;
      for (size_t j = lo; j < t.size() && t[j] - t[i] <= reach; ++j) {
        const double d = t[j] - t[i], w = std::exp(k * d * d);
        s0 += w, s1 += w * d, s2 += w * d * d, q0 += w * in[j], q1 += w * d * in[j];
      }
      const double det = s0 * s2 - s1 * s1;
      // A lone sample in its window (det = 0) keeps its own value.
      y[i] = det > 1e-12 * s0 * s2 ? (s2 * q0 - s1 * q1) / det : q0 / s0;
    }
  }
};

}  // namespace

void TrackOptions::Check() const {
  if (!(max_jump > 0) || !std::isfinite(max_jump))
    throw FieldError("max_jump", "must be > 0 pixels, got " + Num(max_jump));
  if (max_missed < 1)
    throw FieldError("max_missed", "must be >= 1 frame, got " + std::to_string(max_missed));
  if (max_gap < 0)
    throw FieldError("max_gap", "must be >= 0 frames, got " + std::to_string(max_gap));
  if (!(smooth >= 0) || !std::isfinite(smooth))
    throw FieldError("smooth", "must be >= 0 frames, got " + Num(smooth));
  if (min_life < 1)
    throw FieldError("min_life", "must be >= 1 frame, got " + std::to_string(min_life));
  if (!(min_ratio >= 0 && min_ratio <= 1))
    throw FieldError("min_ratio", "must be in 0..1, got " + Num(min_ratio));
  if (dilate < 0 || dilate > 1000)
    throw FieldError("dilate", "must be in 0..1000 pixels, got " + std::to_string(dilate));
}

std::pair<size_t, size_t> TrackResult::FrameRows(int frame) const {
  if (frame < 0 || static_cast<size_t>(frame) + 1 >= frame_begin_.size()) return {0, 0};
  return {frame_begin_[static_cast<size_t>(frame)], frame_begin_[static_cast<size_t>(frame) + 1]};
}

void TrackResult::RenderMask(int frame, int dilate, std::vector<uint8_t>& out) const {
  out.assign(static_cast<size_t>(width) * height, 0);
  auto [b, e] = FrameRows(frame);
  for (size_t i = b; i < e; ++i) {
    const TrackRow& r = rows[i];
    if (r.state == RowState::kRejected) continue;
    PaintBlob(blobs[r.blob], r.draw_x, r.draw_y, 255, out.data(), width, height);
  }
  if (dilate > 0 && b < e) {
    cv::Mat m(height, width, CV_8U, out.data());
    // The disk: offsets (dx, dy) with dx^2 + dy^2 <= dilate^2.
    cv::Mat k(2 * dilate + 1, 2 * dilate + 1, CV_8U);
    for (int dy = -dilate; dy <= dilate; ++dy)
      for (int dx = -dilate; dx <= dilate; ++dx)
        k.at<uint8_t>(dy + dilate, dx + dilate) = dx * dx + dy * dy <= dilate * dilate;
    cv::dilate(m, m, k);
  }
}

bool TrackResult::HasInterpolated(int frame) const {
  const auto [b, e] = FrameRows(frame);
  return std::any_of(rows.begin() + ptrdiff_t(b), rows.begin() + ptrdiff_t(e),
                     [](const TrackRow& r) { return r.state == RowState::kInterpolated; });
}

size_t RejectUnsupportedGaps(TrackResult& res, int frame, const float* evidence, double min_mean) {
  if (!res.HasInterpolated(frame)) return 0;
  const auto [b, e] = res.FrameRows(frame);
  std::vector<uint8_t> detected(size_t(res.width) * size_t(res.height), 0);
  for (size_t i = b; i < e; ++i)
    if (res.rows[i].state == RowState::kDetected)
      PaintBlob(res.blobs[res.rows[i].blob], res.rows[i].draw_x, res.rows[i].draw_y, 1,
                detected.data(), res.width, res.height);
  size_t dropped = 0;
  for (size_t i = b; i < e; ++i) {
    TrackRow& r = res.rows[i];
    if (r.state != RowState::kInterpolated) continue;
    const Blob& blob = res.blobs[r.blob];
    double sum = 0, n = 0;
    for (int y = 0; y < blob.h; ++y)
      for (int x = 0; x < blob.w; ++x) {
        const int px = r.draw_x + x, py = r.draw_y + y;
        if (!blob.mask[size_t(y) * size_t(blob.w) + size_t(x)] || px < 0 || py < 0 ||
            px >= res.width || py >= res.height)
          continue;
        const size_t q = size_t(py) * size_t(res.width) + size_t(px);
        if (!detected[q]) sum += double(evidence[q]), n += 1;
      }
    if (n > 0 && sum < min_mean * n) {
      r.state = RowState::kRejected;
      ++dropped;
    }
  }
  res.summary.interpolated -= dropped;
  res.summary.unsupported_gaps += dropped;
  return dropped;
}

Tracker::Tracker(int width, int height, const TrackOptions& options)
    : width_(width), height_(height), o_(options) {
  o_.Check();
}

void Tracker::AddFrame(const uint8_t* vehicle) { AddBlobs(finder_.Find(vehicle, width_, height_)); }

void Tracker::AddBlobs(std::vector<Blob> blobs) {
  const int t = frames_++;
  // Tracks that have now missed max_missed frames in a row end.
  live_.erase(
      std::remove_if(live_.begin(), live_.end(),
                     [&](size_t k) { return t - tracks_[k].dets.back().frame > o_.max_missed; }),
      live_.end());
  // Candidate pairs within the gate, by distance to the constant-velocity prediction.
  std::vector<std::tuple<double, int, size_t, size_t>>
      pairs;  // distance, track id, blob, live index
  for (size_t li = 0; li < live_.size(); ++li) {
    const Track& tr = tracks_[live_[li]];
    const Blob& last = blobs_[tr.dets.back().blob];
    double px = last.cx, py = last.cy;
    if (tr.dets.size() >= 2) {
      const Det& a = tr.dets[tr.dets.size() - 2];
      const Det& b = tr.dets.back();
      const Blob& prev = blobs_[a.blob];
      const double s = static_cast<double>(t - b.frame) / (b.frame - a.frame);
      px += (last.cx - prev.cx) * s;
      py += (last.cy - prev.cy) * s;
    }
    for (size_t bi = 0; bi < blobs.size(); ++bi) {
      const double d = std::hypot(blobs[bi].cx - px, blobs[bi].cy - py);
      if (d <= o_.max_jump) pairs.emplace_back(d, tr.id, bi, li);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> track_used(live_.size(), 0), blob_used(blobs.size(), 0);
  const size_t base = blobs_.size();
  for (const auto& [d, id, bi, li] : pairs) {
    if (track_used[li] || blob_used[bi]) continue;
    track_used[li] = blob_used[bi] = 1;
    tracks_[live_[li]].dets.push_back({t, base + bi});
  }
  for (size_t bi = 0; bi < blobs.size(); ++bi) {
    if (blob_used[bi]) continue;
    tracks_.push_back({static_cast<int>(tracks_.size()) + 1, {{t, base + bi}}});
    live_.push_back(tracks_.size() - 1);
  }
  for (Blob& b : blobs) blobs_.push_back(std::move(b));
}

namespace {

// `src`'s pixels scaled to nw x nh (nearest neighbour); cx, cy: their centroid relative to the
// box (the source's relative centroid when no pixel survives).
Blob ScaledBlob(const Blob& src, int nw, int nh) {
  Blob s;
  s.w = nw, s.h = nh;
  s.mask.resize(static_cast<size_t>(nw) * nh);
  const cv::Mat in(src.h, src.w, CV_8U, const_cast<uint8_t*>(src.mask.data()));
  cv::Mat out(nh, nw, CV_8U, s.mask.data());
  cv::resize(in, out, out.size(), 0, 0, cv::INTER_NEAREST);
  double sx = 0, sy = 0;
  for (int yy = 0; yy < nh; ++yy)
    for (int xx = 0; xx < nw; ++xx)
      if (s.mask[static_cast<size_t>(yy) * nw + xx]) sx += xx, sy += yy, ++s.area;
  s.cx = src.cx - src.x, s.cy = src.cy - src.y;
  if (s.area > 0) s.cx = sx / s.area, s.cy = sy / s.area;
  return s;
}

// Sets r's box, centroid and area to the pixels of `d` drawn at (r.draw_x, r.draw_y) that fall
// inside a width x height image; none: an empty box at the drawing position, area 0.
void ClipDrawn(const Blob& d, int width, int height, TrackRow& r) {
  int x0 = width, y0 = height, x1 = -1, y1 = -1, area = 0;
  double sx = 0, sy = 0;
  for (int yy = std::max(0, -r.draw_y); yy < std::min(d.h, height - r.draw_y); ++yy)
    for (int xx = std::max(0, -r.draw_x); xx < std::min(d.w, width - r.draw_x); ++xx)
      if (d.mask[static_cast<size_t>(yy) * d.w + xx]) {
        const int X = r.draw_x + xx, Y = r.draw_y + yy;
        x0 = std::min(x0, X), x1 = std::max(x1, X), y0 = std::min(y0, Y), y1 = std::max(y1, Y);
        sx += X, sy += Y, ++area;
      }
  if (area > 0) {
    r.x = x0, r.y = y0, r.w = x1 - x0 + 1, r.h = y1 - y0 + 1;
    r.cx = sx / area, r.cy = sy / area, r.area = area;
  } else {
    r.x = r.draw_x, r.y = r.draw_y, r.w = r.h = 0, r.cx = r.scx, r.cy = r.scy, r.area = 0;
  }
}

}  // namespace

Tracker::Smoothed Tracker::Smooth(const Track& tr, const std::vector<Blob>& blobs) const {
  const size_t m = tr.dets.size();
  std::vector<double> f(m);
  Smoothed s{std::vector<double>(m), std::vector<double>(m), std::vector<double>(m),
             std::vector<double>(m)};
  for (size_t i = 0; i < m; ++i) {
    const Blob& b = blobs[tr.dets[i].blob];
    f[i] = tr.dets[i].frame, s.cx[i] = b.cx, s.cy[i] = b.cy, s.w[i] = b.w, s.h[i] = b.h;
  }
  const Smoother smoother{o_.smooth};
  for (auto* v : {&s.cx, &s.cy, &s.w, &s.h}) smoother.Apply(f, *v);
  return s;
}

std::vector<uint8_t> Tracker::Rejected(const Track& tr) const {
  std::vector<uint8_t> rejected(tr.dets.size(), 0);
  for (size_t b = 0; b < tr.dets.size();) {
    size_t e = b + 1;  // the stretch [b, e): no gap inside longer than max_gap
    while (e < tr.dets.size() && tr.dets[e].frame - tr.dets[e - 1].frame - 1 <= o_.max_gap) ++e;
    const int span = tr.dets[e - 1].frame - tr.dets[b].frame + 1;
    const bool r = span < o_.min_life || static_cast<double>(e - b) < o_.min_ratio * span;
    std::fill(rejected.begin() + long(b), rejected.begin() + long(e), r);
    b = e;
  }
  return rejected;
}

void Tracker::AddDetectedRows(const Track& tr, const Smoothed& s,
                              const std::vector<uint8_t>& rejected, TrackResult& res) const {
  for (size_t i = 0; i < tr.dets.size(); ++i) {
    const Blob& b = res.blobs[tr.dets[i].blob];
    TrackRow r;
    r.frame = tr.dets[i].frame;
    r.track = tr.id;
    r.state = rejected[i] ? RowState::kRejected : RowState::kDetected;
    r.x = b.x, r.y = b.y, r.w = b.w, r.h = b.h, r.cx = b.cx, r.cy = b.cy, r.area = b.area;
    r.scx = s.cx[i], r.scy = s.cy[i], r.sw = s.w[i], r.sh = s.h[i];
    r.blob = tr.dets[i].blob;
    r.draw_x = b.x, r.draw_y = b.y;
    res.rows.push_back(r);
    rejected[i] ? ++res.summary.rejected_blobs : ++res.summary.detected;
  }
}

void Tracker::FillGaps(const Track& tr, const Smoothed& s, const std::vector<uint8_t>& rejected,
                       TrackResult& res) const {
  for (size_t i = 0; i + 1 < tr.dets.size(); ++i) {
    const int f0 = tr.dets[i].frame, f1 = tr.dets[i + 1].frame, gap = f1 - f0 - 1;
    if (gap == 0) continue;
    if (gap > o_.max_gap) {  // between two stretches; counted when one of them is kept
      if (!rejected[i] || !rejected[i + 1]) ++res.summary.unfilled_gaps;
      continue;
    }
    if (rejected[i]) continue;  // inside a rejected stretch
    const size_t src_index = tr.dets[i].blob;
    for (int t = f0 + 1; t < f1; ++t) {
      const double a = static_cast<double>(t - f0) / (f1 - f0);
      TrackRow r;
      r.frame = t;
      r.track = tr.id;
      r.state = RowState::kInterpolated;
      r.scx = (1 - a) * s.cx[i] + a * s.cx[i + 1];
      r.scy = (1 - a) * s.cy[i] + a * s.cy[i + 1];
      r.sw = (1 - a) * s.w[i] + a * s.w[i + 1];
      r.sh = (1 - a) * s.h[i] + a * s.h[i + 1];
      // The last detected blob, scaled by the smoothed size ratio (nearest neighbour).
      const Blob& src = res.blobs[src_index];
      const int nw = std::max(1, RoundHalfUp(src.w * (r.sw / s.w[i])));
      const int nh = std::max(1, RoundHalfUp(src.h * (r.sh / s.h[i])));
      size_t bi = src_index;
      double rcx = src.cx - src.x, rcy = src.cy - src.y;  // centroid relative to the box
      if (nw != src.w || nh != src.h) {
        Blob scaled = ScaledBlob(src, nw, nh);
        rcx = scaled.cx, rcy = scaled.cy;
        res.blobs.push_back(std::move(scaled));
        bi = res.blobs.size() - 1;
      }
      r.blob = bi;
      r.draw_x = RoundHalfUp(r.scx - rcx);
      r.draw_y = RoundHalfUp(r.scy - rcy);
      ClipDrawn(res.blobs[bi], width_, height_, r);
      res.rows.push_back(r);
      ++res.summary.interpolated;
    }
  }
}

void Tracker::IndexFrames(TrackResult& res) const {
  std::sort(res.rows.begin(), res.rows.end(), [](const TrackRow& a, const TrackRow& b) {
    return std::tie(a.frame, a.track) < std::tie(b.frame, b.track);
  });
  res.frame_begin_.assign(static_cast<size_t>(frames_) + 1, res.rows.size());
  for (size_t i = res.rows.size(); i-- > 0;)
    res.frame_begin_[static_cast<size_t>(res.rows[i].frame)] = i;
  for (int fr = frames_ - 1; fr >= 0; --fr)  // frames without rows start where the next begins
    res.frame_begin_[static_cast<size_t>(fr)] = std::min(
        res.frame_begin_[static_cast<size_t>(fr)], res.frame_begin_[static_cast<size_t>(fr) + 1]);
}

TrackResult Tracker::Finish() {
  TrackResult res;
  res.width = width_;
  res.height = height_;
  res.blobs = std::move(blobs_);
  TrackSummary& sum = res.summary;
  sum.frames = frames_;
  sum.tracks = static_cast<int>(tracks_.size());
  for (const Track& tr : tracks_) {
    const Smoothed s = Smooth(tr, res.blobs);
    const std::vector<uint8_t> rejected = Rejected(tr);
    std::count(rejected.begin(), rejected.end(), 0) > 0 ? ++sum.kept : ++sum.rejected;
    AddDetectedRows(tr, s, rejected, res);
    FillGaps(tr, s, rejected, res);
  }
  IndexFrames(res);

  tracks_.clear();
  live_.clear();
  blobs_.clear();
  frames_ = 0;
  return res;
}

}  // namespace mvtm
