#include "track/blobs.h"

#include <algorithm>
#include <cstring>

namespace mvtm {

namespace {

// Pixel columns [x0, x1) of row y.
struct Run {
  int x0, x1, y;
};

uint64_t Load8(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// True when one of the 8 bytes of v is zero.
bool HasZeroByte(uint64_t v) {
  return ((v - 0x0101010101010101ull) & ~v & 0x8080808080808080ull) != 0;
}

// Appends the runs of non-zero bytes of `row` (row index y, `width` bytes), skipping 8 bytes at
// a time through empty and through full stretches.
void AppendRuns(const uint8_t* row, int width, int y, std::vector<Run>& runs) {
  int x = 0;
  while (x < width) {
    while (x + 8 <= width && Load8(row + x) == 0) x += 8;
    while (x < width && !row[x]) ++x;
    if (x == width) break;
    const int x0 = x;
    while (x + 8 <= width && !HasZeroByte(Load8(row + x))) x += 8;
    while (x < width && row[x]) ++x;
    runs.push_back({x0, x, y});
  }
}

// Union-find over runs; a root is the lowest run index of its set, so the first in raster order.
int Root(std::vector<int>& parent, int i) {
  while (parent[static_cast<size_t>(i)] != i) {
    int& p = parent[static_cast<size_t>(i)];
    p = parent[static_cast<size_t>(p)];  // path halving
    i = p;
  }
  return i;
}

void Join(std::vector<int>& parent, int a, int b) {
  a = Root(parent, a), b = Root(parent, b);
  if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
}

}  // namespace

struct BlobFinder::Scratch {
  std::vector<Run> runs;
  std::vector<int> parent;  // union-find over runs
  std::vector<int> blob;    // each run's blob
  std::vector<uint64_t> sum_x, sum_y;
};

BlobFinder::BlobFinder() : scratch_(std::make_unique<Scratch>()) {}
BlobFinder::~BlobFinder() = default;

std::vector<Blob> BlobFinder::Find(const uint8_t* vehicle, int width, int height) {
  std::vector<Blob> blobs;
  if (width <= 0 || height <= 0) return blobs;
  Scratch& s = *scratch_;
  std::vector<Run>& runs = s.runs;
  runs.clear();
  s.parent.clear();
  // Runs row by row; each joins the runs of the row above that it touches (8-connectivity:
  // columns [a0, a1) and [b0, b1) of adjacent rows touch when a0 <= b1 and b0 <= a1).
  size_t above = 0;  // first run of the row above
  for (int y = 0; y < height; ++y) {
    const size_t begin = runs.size();
    AppendRuns(vehicle + static_cast<size_t>(y) * width, width, y, runs);
    for (size_t i = begin; i < runs.size(); ++i) s.parent.push_back(static_cast<int>(i));
    size_t j = above;
    for (size_t i = begin; i < runs.size(); ++i) {
      while (j < begin && runs[j].x1 < runs[i].x0) ++j;
      for (size_t k = j; k < begin && runs[k].x0 <= runs[i].x1; ++k)
        Join(s.parent, static_cast<int>(i), static_cast<int>(k));
    }
    above = begin;
  }
  // Blobs numbered in run order of their roots, i.e. of their first pixels. Integer coordinate
  // sums divided by the area give OpenCV's centroids exactly.
  s.blob.resize(runs.size());
  s.sum_x.clear();
  s.sum_y.clear();
  std::vector<int> x1, y1;  // last column and row of each blob
  for (size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    const size_t root = static_cast<size_t>(Root(s.parent, static_cast<int>(i)));
    if (root == i) {
      s.blob[i] = static_cast<int>(blobs.size());
      Blob b;
      b.x = r.x0, b.y = r.y;
      blobs.push_back(std::move(b));
      x1.push_back(r.x1 - 1), y1.push_back(r.y);
      s.sum_x.push_back(0), s.sum_y.push_back(0);
    } else {
      s.blob[i] = s.blob[root];  // root < i: already numbered
    }
    const size_t b = static_cast<size_t>(s.blob[i]);
    const uint64_t len = static_cast<uint64_t>(r.x1 - r.x0);
    blobs[b].x = std::min(blobs[b].x, r.x0);
    x1[b] = std::max(x1[b], r.x1 - 1), y1[b] = r.y;
    blobs[b].area += static_cast<int>(len);
    s.sum_x[b] += len * static_cast<uint64_t>(r.x0 + r.x1 - 1) / 2;
    s.sum_y[b] += len * static_cast<uint64_t>(r.y);
  }
  for (size_t b = 0; b < blobs.size(); ++b) {
    Blob& bl = blobs[b];
    bl.w = x1[b] - bl.x + 1, bl.h = y1[b] - bl.y + 1;
    const double area = bl.area;
    bl.cx = static_cast<double>(s.sum_x[b]) / area;
    bl.cy = static_cast<double>(s.sum_y[b]) / area;
    bl.mask.assign(static_cast<size_t>(bl.w) * bl.h, 0);
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    Blob& bl = blobs[static_cast<size_t>(s.blob[i])];
    std::memset(bl.mask.data() + static_cast<size_t>(r.y - bl.y) * bl.w + (r.x0 - bl.x), 1,
                static_cast<size_t>(r.x1 - r.x0));
  }
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
