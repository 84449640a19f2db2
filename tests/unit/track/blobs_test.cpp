// The run-length blob finder against cv::connectedComponentsWithStats (8-connectivity) on random
// masks: the same components in the order of their first pixels, the same boxes and areas,
// centroids bit for bit, and each blob's mask equal to its component's pixels.
#include "track/blobs.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

using namespace mvtm;

namespace {

void ExpectLikeOpenCv(const std::vector<uint8_t>& m, int w, int h, BlobFinder& finder) {
  const std::vector<Blob> blobs = finder.Find(m.data(), w, h);
  cv::Mat labels, stats, centroids;
  const cv::Mat in(h, w, CV_8U, const_cast<uint8_t*>(m.data()));
  const int n = cv::connectedComponentsWithStats(in, labels, stats, centroids, 8, CV_32S);
  ASSERT_EQ(blobs.size(), static_cast<size_t>(n - 1)) << w << "x" << h;
  // OpenCV's label ids, in order of their first pixel in raster order (its own numbering follows
  // its 2x2 blocks).
  std::vector<int> ids;
  std::vector<char> seen(static_cast<size_t>(n), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int id = labels.at<int>(y, x);
      if (id > 0 && !seen[static_cast<size_t>(id)])
        seen[static_cast<size_t>(id)] = 1, ids.push_back(id);
    }
  for (size_t i = 0; i < ids.size(); ++i) {
    const int id = ids[i];
    const Blob& b = blobs[i];
    const int* st = stats.ptr<int>(id);
    ASSERT_EQ(b.x, st[cv::CC_STAT_LEFT]);
    ASSERT_EQ(b.y, st[cv::CC_STAT_TOP]);
    ASSERT_EQ(b.w, st[cv::CC_STAT_WIDTH]);
    ASSERT_EQ(b.h, st[cv::CC_STAT_HEIGHT]);
    ASSERT_EQ(b.area, st[cv::CC_STAT_AREA]);
    ASSERT_EQ(b.cx, centroids.at<double>(id, 0));  // exact: both are integer sums / area
    ASSERT_EQ(b.cy, centroids.at<double>(id, 1));
    ASSERT_EQ(b.mask.size(), static_cast<size_t>(b.w) * b.h);
    for (int r = 0; r < b.h; ++r)
      for (int c = 0; c < b.w; ++c)
        ASSERT_EQ(b.mask[static_cast<size_t>(r) * b.w + c], labels.at<int>(b.y + r, b.x + c) == id)
            << "blob " << id << " pixel " << b.x + c << "," << b.y + r;
  }
}

TEST(BlobFinder, MatchesOpenCvOnRandomMasks) {
  std::mt19937 rng(7);
  BlobFinder finder;  // reused: scratch from one frame must not leak into the next
  const int sizes[][2] = {{1, 1}, {1, 17}, {17, 1}, {7, 5}, {8, 8}, {9, 3}, {63, 41}, {130, 97}};
  for (const auto& s : sizes)
    for (double p : {0.0, 0.05, 0.3, 0.5, 0.7, 1.0})
      for (int rep = 0; rep < 4; ++rep) {
        const int w = s[0], h = s[1];
        std::vector<uint8_t> m(static_cast<size_t>(w) * h);
        std::bernoulli_distribution on(p);
        std::uniform_int_distribution<int> value(1, 255);  // any non-zero byte is set
        for (uint8_t& v : m) v = on(rng) ? static_cast<uint8_t>(value(rng)) : 0;
        ExpectLikeOpenCv(m, w, h, finder);
      }
}

TEST(BlobFinder, MatchesOpenCvOnBoxesAndShapes) {
  std::mt19937 rng(11);
  BlobFinder finder;
  const int w = 301, h = 123;
  for (int rep = 0; rep < 30; ++rep) {
    cv::Mat m(h, w, CV_8U, cv::Scalar(0));
    std::uniform_int_distribution<int> x(-20, w), y(-20, h), size(1, 60);
    for (int k = 0; k < 12; ++k) {
      const cv::Point p(x(rng), y(rng));
      switch (k % 4) {
        case 0:  // a filled box
          cv::rectangle(m, cv::Rect(p.x, p.y, size(rng), size(rng)), 1, cv::FILLED);
          break;
        case 1:  // a ring (a hole, and a U when clipped)
          cv::circle(m, p, size(rng), 1, 3);
          break;
        case 2:  // a one-pixel diagonal line: joined only through corners
          cv::line(m, p, p + cv::Point(size(rng), size(rng)), 1, 1, cv::LINE_8);
          break;
        default:  // a box outline
          cv::rectangle(m, cv::Rect(p.x, p.y, size(rng), size(rng)), 1, 1);
      }
    }
    ExpectLikeOpenCv(std::vector<uint8_t>(m.datastart, m.dataend), w, h, finder);
  }
}

}  // namespace
