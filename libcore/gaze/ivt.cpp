#include "gaze/ivt.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "base/stats.h"

namespace mvtm {

Eigen::Vector3d ScreenGeometry::Direction(double x, double y) const {
  const Eigen::Vector3d p((x - 0.5 * width_px) * width_mm / width_px,
                          (y - 0.5 * height_px) * height_mm / height_px, distance_mm);
  return p.normalized();
}

double ScreenGeometry::AngleDeg(double x1, double y1, double x2, double y2) const {
  if (width_mm <= 0) return std::hypot(x2 - x1, y2 - y1) / px_per_degree;
  const Eigen::Vector3d a = Direction(x1, y1), b = Direction(x2, y2);
  // atan2 of |a×b| and a·b: accurate for the tiny angles between neighbouring samples.
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

namespace {

void FillGaps(std::vector<GazeSample>& s, double max_gap, IvtResult& r) {
  if (max_gap <= 0) return;
  size_t i = 0;
  while (i < s.size()) {
    if (s[i].valid) {
      ++i;
      continue;
    }
    size_t q = i;
    while (q < s.size() && !s[q].valid) ++q;
    if (i > 0 && q < s.size() && s[q].time - s[i - 1].time <= max_gap) {
      const GazeSample &a = s[i - 1], &b = s[q];
      for (size_t j = i; j < q; ++j) {
        const double w = (s[j].time - a.time) / (b.time - a.time);
        s[j].x = a.x + w * (b.x - a.x);
        s[j].y = a.y + w * (b.y - a.y);
        s[j].valid = true;
      }
      ++r.gaps_filled;
      r.samples_filled += q - i;
    }
    i = q;
  }
}

void MedianFilter(std::vector<GazeSample>& s, int window) {
  if (window <= 1) return;
  const std::vector<GazeSample> in = s;
  const long h = window / 2, n = static_cast<long>(s.size());
  std::vector<double> xs, ys;
  for (long i = 0; i < n; ++i) {
    if (!in[i].valid) continue;
    xs.clear();
    ys.clear();
    for (long j = std::max(0L, i - h); j <= std::min(n - 1, i + h); ++j)
      if (in[j].valid) {
        xs.push_back(in[j].x);
        ys.push_back(in[j].y);
      }
    s[i].x = MiddleMedian(xs);
    s[i].y = MiddleMedian(ys);
  }
}

void Velocities(IvtResult& r, const ScreenGeometry& screen, double window) {
  const auto& s = r.filtered;
  const long n = static_cast<long>(s.size());
  std::vector<double> dt;
  for (long i = 1; i < n; ++i) dt.push_back(s[i].time - s[i - 1].time);
  // The half window in samples; beyond the trace's length it changes nothing, and the bound keeps
  // i ± k from overflowing for absurd windows or sample rates (in double before any cast).
  const double half = window / (2 * Median(dt));
  const long k = !(half < double(n)) ? std::max(1L, n) : std::max(1L, std::lround(half));
  r.velocity_half_window = static_cast<int>(k);
  r.velocity.assign(s.size(), std::numeric_limits<double>::quiet_NaN());
  for (long i = 0; i < n; ++i) {
    const GazeSample &a = s[std::max(0L, i - k)], &b = s[std::min(n - 1, i + k)];
    if (!s[i].valid || !a.valid || !b.valid) continue;
    r.velocity[i] = screen.AngleDeg(a.x, a.y, b.x, b.y) / (b.time - a.time);
  }
}

// Fixations as maximal runs of fixation samples, with their sums for the mean.
struct Run {
  Fixation f;
  double sx = 0, sy = 0;
};

std::vector<Run> Runs(const IvtResult& r) {
  std::vector<Run> runs;
  for (size_t i = 0; i < r.classes.size(); ++i) {
    if (r.classes[i] != SampleClass::kFixation) continue;
    if (runs.empty() || runs.back().f.last + 1 != i) {
      runs.emplace_back();
      runs.back().f.first = i;
      runs.back().f.start = r.filtered[i].time;
    }
    Run& u = runs.back();
    u.f.last = i;
    u.f.end = r.filtered[i].time;
    ++u.f.samples;
    u.sx += r.filtered[i].x;
    u.sy += r.filtered[i].y;
    u.f.x = u.sx / u.f.samples;
    u.f.y = u.sy / u.f.samples;
  }
  return runs;
}

std::vector<Run> Merge(std::vector<Run> runs, const ScreenGeometry& screen, const IvtOptions& o,
                       IvtResult& r) {
  if (o.merge_time <= 0) return runs;
  std::vector<Run> out;
  for (Run& u : runs) {
    if (!out.empty()) {
      Run& p = out.back();
      if (u.f.start - p.f.end < o.merge_time &&
          screen.AngleDeg(p.f.x, p.f.y, u.f.x, u.f.y) < o.merge_angle) {
        p.f.last = u.f.last;
        p.f.end = u.f.end;
        p.f.samples += u.f.samples;
        p.sx += u.sx;
        p.sy += u.sy;
        p.f.x = p.sx / p.f.samples;
        p.f.y = p.sy / p.f.samples;
        ++r.merged;
        continue;
      }
    }
    out.push_back(u);
  }
  return out;
}

}  // namespace

IvtResult RunIvt(const std::vector<GazeSample>& samples, const ScreenGeometry& screen,
                 const IvtOptions& o) {
  if (samples.size() < 2) throw Error("the I-VT filter needs at least two gaze samples");
  for (size_t i = 1; i < samples.size(); ++i)
    if (!(samples[i].time > samples[i - 1].time))
      throw Error("", samples[i].line, "gaze times must strictly increase");
  IvtResult r;
  r.filtered = samples;
  FillGaps(r.filtered, o.max_gap, r);
  MedianFilter(r.filtered, o.median_window);
  Velocities(r, screen, o.velocity_window);
  r.classes.resize(samples.size());
  for (size_t i = 0; i < samples.size(); ++i)
    r.classes[i] = std::isnan(r.velocity[i])     ? SampleClass::kInvalid
                   : r.velocity[i] < o.threshold ? SampleClass::kFixation
                                                 : SampleClass::kSaccade;
  for (const Run& u : Merge(Runs(r), screen, o, r)) {
    if (o.min_duration > 0 && u.f.duration() < o.min_duration) {
      ++r.discarded;
      for (size_t i = u.f.first; i <= u.f.last; ++i)
        if (r.classes[i] == SampleClass::kFixation) r.classes[i] = SampleClass::kDiscarded;
      continue;
    }
    r.fixations.push_back(u.f);
  }
  return r;
}

}  // namespace mvtm
