#include "gaze/pictures.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "base/error.h"

namespace mvtm {

void DrawFixations(Image& image, const std::vector<FixationMark>& marks) {
  cv::Mat m(image.height, image.width, CV_8UC3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int src = image.channels >= 3 ? c : 0;
        const float v = image.at(x, y, src) * 255.f / static_cast<float>(image.MaxValue());
        m.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uchar>(std::lround(v));
      }
  const int r = std::max(3, std::min(image.width, image.height) / 25);
  const int thick = std::max(1, r / 5);
  for (const FixationMark& k : marks) {
    // Sub-pixel centre (shift 4): pixel centres are at +0.5 in COLMAP, at integers in OpenCV.
    const cv::Point c(static_cast<int>(std::lround((k.u - 0.5) * 16)),
                      static_cast<int>(std::lround((k.v - 0.5) * 16)));
    cv::circle(m, c, r * 16, cv::Scalar(0, 0, 0), thick + 2, cv::LINE_AA, 4);
    cv::circle(m, c, r * 16, cv::Scalar(255, 230, 0), thick, cv::LINE_AA, 4);
    const cv::Point at(static_cast<int>(k.u + r), static_cast<int>(k.v - r));
    const double scale = std::max(0.3, r / 14.0);
    cv::putText(m, k.label, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), thick + 2,
                cv::LINE_AA);
    cv::putText(m, k.label, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 230, 0), thick,
                cv::LINE_AA);
  }
  Image out(image.width, image.height, 3, 8);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = m.at<cv::Vec3b>(y, x)[c];
  image = std::move(out);
}

namespace {

struct MapFrame {
  Eigen::Vector3d e1, e2, up;
  double x0 = 0, y1 = 0, px = 1;  // left edge, top edge (in e1, e2), model units per pixel
  int w = 1, h = 1;
  Eigen::Vector2d ToPixel(const Eigen::Vector3d& X) const {
    return {(X.dot(e1) - x0) / px, (y1 - X.dot(e2)) / px};
  }
};

MapFrame MakeFrame(const Eigen::Vector3d& up, const std::vector<Eigen::Vector3d>& pts, int size,
                   double& sigma) {
  MapFrame f;
  f.up = up.normalized();
  Eigen::Vector3d a =
      std::abs(f.up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  f.e1 = (a - a.dot(f.up) * f.up).normalized();
  f.e2 = f.up.cross(f.e1);
  double lo1 = INFINITY, hi1 = -INFINITY, lo2 = INFINITY, hi2 = -INFINITY;
  for (const auto& p : pts) {
    lo1 = std::min(lo1, p.dot(f.e1)), hi1 = std::max(hi1, p.dot(f.e1));
    lo2 = std::min(lo2, p.dot(f.e2)), hi2 = std::max(hi2, p.dot(f.e2));
  }
  double side = std::max({hi1 - lo1, hi2 - lo2, 1e-9});
  if (sigma <= 0) sigma = 0.01 * side;
  const double pad = std::max(0.15 * side, 4 * sigma);
  lo1 -= pad, hi1 += pad, lo2 -= pad, hi2 += pad;
  side = std::max(hi1 - lo1, hi2 - lo2);
  f.px = side / size;
  f.w = std::max(1, static_cast<int>(std::ceil((hi1 - lo1) / f.px)));
  f.h = std::max(1, static_cast<int>(std::ceil((hi2 - lo2) / f.px)));
  f.x0 = lo1;
  f.y1 = hi2;
  return f;
}

// The colour of the surface under a map pixel: barycentric vertex colours, grey 150 without.
Eigen::Vector3d SurfaceColour(const Mesh& mesh, const RayHit& hit) {
  if (!mesh.has_colors()) return Eigen::Vector3d::Constant(150);
  const auto& t = mesh.faces[hit.triangle];
  const double w[3] = {1 - hit.u - hit.v, hit.u, hit.v};
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    for (int ch = 0; ch < 3; ++ch) c[ch] += w[k] * mesh.colors[t[k]][ch];
  return c;
}

std::vector<double> Heat(const MapFrame& f, const std::vector<HeatPoint>& points, double sigma) {
  std::vector<double> heat(static_cast<size_t>(f.w) * f.h, 0.0);
  const double s = sigma / f.px;
  const int rad = static_cast<int>(std::ceil(3 * s));
  for (const HeatPoint& p : points) {
    const Eigen::Vector2d c = f.ToPixel(p.point);
    const int cx = static_cast<int>(std::floor(c.x())), cy = static_cast<int>(std::floor(c.y()));
    for (int y = std::max(0, cy - rad); y <= std::min(f.h - 1, cy + rad); ++y)
      for (int x = std::max(0, cx - rad); x <= std::min(f.w - 1, cx + rad); ++x) {
        const double dx = x + 0.5 - c.x(), dy = y + 0.5 - c.y();
        heat[static_cast<size_t>(y) * f.w + x] +=
            p.weight * std::exp(-(dx * dx + dy * dy) / (2 * s * s));
      }
  }
  return heat;
}

}  // namespace

struct HeatmapPainter::State {
  MapFrame f;
  double sigma = 0;
  std::vector<Eigen::Vector3d> path;
  std::vector<HeatPoint> points;
  Image img;
  std::vector<double> height;  // of the surface shown at each pixel (-inf: none yet)
};

HeatmapPainter::HeatmapPainter(const Eigen::Vector3d& up, std::vector<Eigen::Vector3d> path,
                               std::vector<HeatPoint> points, const HeatmapOptions& o)
    : s_(std::make_unique<State>()) {
  std::vector<Eigen::Vector3d> all = path;
  for (const HeatPoint& p : points) all.push_back(p.point);
  if (all.empty()) throw Error("a heat map needs a path or points");
  s_->sigma = o.sigma;
  s_->f = MakeFrame(up, all, o.size, s_->sigma);
  s_->path = std::move(path);
  s_->points = std::move(points);
  s_->img = Image(s_->f.w, s_->f.h, 3, 8);
  for (float& v : s_->img.data) v = 30;
  s_->height.assign(static_cast<size_t>(s_->f.w) * s_->f.h, -INFINITY);
}

HeatmapPainter::~HeatmapPainter() = default;

namespace {

// The pixel rectangle [x0, x1) × [y0, y1) under an axis-aligned box, clipped to the map.
struct PixelRect {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
};

PixelRect RectUnder(const MapFrame& f, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c(corner & 1 ? hi.x() : lo.x(), corner & 2 ? hi.y() : lo.y(),
                            corner & 4 ? hi.z() : lo.z());
    const Eigen::Vector2d p = f.ToPixel(c);
    x_lo = std::min(x_lo, p.x()), x_hi = std::max(x_hi, p.x());
    y_lo = std::min(y_lo, p.y()), y_hi = std::max(y_hi, p.y());
  }
  auto clamp = [](double v, int n) { return static_cast<int>(std::clamp(v, 0.0, double(n))); };
  return {clamp(std::floor(x_lo) - 1, f.w), clamp(std::ceil(x_hi) + 1, f.w),
          clamp(std::floor(y_lo) - 1, f.h), clamp(std::ceil(y_hi) + 1, f.h)};
}

}  // namespace

bool HeatmapPainter::CoversBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  return !RectUnder(s_->f, lo, hi).empty();
}

void HeatmapPainter::AddSurface(const Mesh& mesh, const MeshRaycaster& rc) {
  if (mesh.faces.empty()) return;
  const MapFrame& f = s_->f;
  Eigen::Vector3d lo, hi;
  mesh.Bounds(lo, hi);
  // Rays start above every surface of this part; hits of parts compare by their height.
  const double top = std::max(lo.dot(f.up), hi.dot(f.up)) + (hi - lo).norm() + 1;
  // Only the pixels under the part's bounding box can hit it.
  const PixelRect r = RectUnder(f, lo, hi);
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const double a = f.x0 + (x + 0.5) * f.px, b = f.y1 - (y + 0.5) * f.px;
      const auto hit = rc.Closest(a * f.e1 + b * f.e2 + top * f.up, -f.up);
      if (!hit) continue;
      double& h = s_->height[static_cast<size_t>(y) * f.w + x];
      if (!(top - hit->t > h)) continue;
      h = top - hit->t;
      const Eigen::Vector3d c = SurfaceColour(mesh, *hit);
      for (int ch = 0; ch < 3; ++ch) s_->img.at(x, y, ch) = static_cast<float>(c[ch]);
    }
}

Image HeatmapPainter::Finish() const {
  const MapFrame& f = s_->f;
  Image img = s_->img;
  for (const auto& p : s_->path) {
    const Eigen::Vector2d c = f.ToPixel(p);
    const int x = static_cast<int>(c.x()), y = static_cast<int>(c.y());
    if (x >= 0 && y >= 0 && x < f.w && y < f.h)
      for (int ch = 0; ch < 3; ++ch) img.at(x, y, ch) = 255;
  }
  const std::vector<double> heat = Heat(f, s_->points, s_->sigma);
  const double peak = *std::max_element(heat.begin(), heat.end());
  if (peak <= 0) return img;
  for (int y = 0; y < f.h; ++y)
    for (int x = 0; x < f.w; ++x) {
      const double h = heat[static_cast<size_t>(y) * f.w + x] / peak;
      if (h < 0.02) continue;
      const double alpha = 0.35 + 0.55 * h;
      const double col[3] = {255, 255 * (1 - h), 0};  // yellow (low) to red (high)
      for (int ch = 0; ch < 3; ++ch)
        img.at(x, y, ch) = static_cast<float>((1 - alpha) * img.at(x, y, ch) + alpha * col[ch]);
    }
  return img;
}

Image RenderHeatmap(const Mesh& mesh, const MeshRaycaster& raycaster, const Eigen::Vector3d& up,
                    const std::vector<Eigen::Vector3d>& path, const std::vector<HeatPoint>& points,
                    const HeatmapOptions& o) {
  HeatmapPainter painter(up, path, points, o);
  painter.AddSurface(mesh, raycaster);
  return painter.Finish();
}

}  // namespace mvtm
