#include "track/blobs.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace mvtm {

struct BlobFinder::Scratch {
  cv::Mat labels, stats, centroids;
};

BlobFinder::BlobFinder() : scratch_(std::make_unique<Scratch>()) {}
BlobFinder::~BlobFinder() = default;

std::vector<Blob> BlobFinder::Find(const uint8_t* vehicle, int width, int height) {
  std::vector<Blob> blobs;
  if (width <= 0 || height <= 0) return blobs;
  // connectedComponents treats every non-zero byte as foreground; the input is not modified.
  const cv::Mat in(height, width, CV_8U, const_cast<uint8_t*>(vehicle));
  Scratch& s = *scratch_;
  const int n = cv::connectedComponentsWithStats(in, s.labels, s.stats, s.centroids, 8, CV_32S);
  blobs.resize(static_cast<size_t>(std::max(0, n - 1)));
  for (int id = 1; id < n; ++id) {
    Blob& b = blobs[static_cast<size_t>(id - 1)];
    const int* st = s.stats.ptr<int>(id);
    b.x = st[cv::CC_STAT_LEFT];
    b.y = st[cv::CC_STAT_TOP];
    b.w = st[cv::CC_STAT_WIDTH];
    b.h = st[cv::CC_STAT_HEIGHT];
    b.area = st[cv::CC_STAT_AREA];
    b.cx = s.centroids.at<double>(id, 0);
    b.cy = s.centroids.at<double>(id, 1);
    b.mask.assign(static_cast<size_t>(b.w) * b.h, 0);
    for (int r = 0; r < b.h; ++r) {
      const int* lr = s.labels.ptr<int>(b.y + r) + b.x;
      uint8_t* mr = b.mask.data() + static_cast<size_t>(r) * b.w;
      for (int c = 0; c < b.w; ++c) mr[c] = static_cast<uint8_t>(lr[c] == id);
    }
  }
  // OpenCV numbers components by their first pixel in raster order; keep that (documented) order
  // explicit in case an algorithm variant numbers differently.
  std::stable_sort(blobs.begin(), blobs.end(), [](const Blob& a, const Blob& b) {
    auto first = [](const Blob& bl) {
      int c = 0;
      while (c < bl.w && !bl.mask[static_cast<size_t>(c)]) ++c;
      return std::make_pair(bl.y, bl.x + c);
    };
    return first(a) < first(b);
  });
  return blobs;
}

void PaintBlob(const Blob& blob, int x, int y, uint8_t value, uint8_t* image, int width,
               int height) {
  const int c0 = std::max(0, -x), c1 = std::min(blob.w, width - x);
  const int r0 = std::max(0, -y), r1 = std::min(blob.h, height - y);
  for (int r = r0; r < r1; ++r) {
    const uint8_t* mr = blob.mask.data() + static_cast<size_t>(r) * blob.w;
    uint8_t* out = image + static_cast<size_t>(y + r) * width + x;
    for (int c = c0; c < c1; ++c)
      if (mr[c]) out[c] = value;
  }
}

}  // namespace mvtm
