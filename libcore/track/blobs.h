// mvtm — vehicle blobs: the 8-connected components of one frame's vehicle mask.
//
// Conventions:
//  * A vehicle mask is width*height bytes, row-major, row 0 at the top; non-zero = vehicle pixel.
//  * Coordinates are pixel indices: column x, row y. A blob's centroid is the mean (x, y) of its
//    pixels (so a single pixel at column 3, row 4 has centroid (3, 4)).
//  * A blob keeps its own pixels as a bounding-box sized mask, so it can be drawn again later
//    (moved, for gap filling) without the frame it came from.
//
// Thread safety: a BlobFinder holds scratch buffers; use one per thread.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace mvtm {

struct Blob {
  int x = 0, y = 0, w = 0, h = 0;  // bounding box: columns [x, x+w), rows [y, y+h)
  double cx = 0, cy = 0;           // centroid (mean pixel column, row)
  int area = 0;                    // number of pixels
  std::vector<uint8_t> mask;       // w*h bytes, row-major; 1 = pixel of this blob, 0 = not
};

// Finds the 8-connected components of a vehicle mask, in the order of their first pixel in
// raster order (top row first, left to right): the components, boxes, areas and centroids of
// cv::connectedComponentsWithStats (8-connectivity), bit for bit. One pass over the mask collects
// its runs of set pixels; the components are unions of runs (a run touches the runs of the row
// above that it overlaps or meets diagonally), so a mostly empty mask costs little more than
// reading it.
class BlobFinder {
 public:
  BlobFinder();
  ~BlobFinder();
  BlobFinder(const BlobFinder&) = delete;
  BlobFinder& operator=(const BlobFinder&) = delete;

  std::vector<Blob> Find(const uint8_t* vehicle, int width, int height);

 private:
  struct Scratch;
  std::unique_ptr<Scratch> scratch_;
};

// Paints `blob` into a width*height byte image with its box moved to (x, y) — pixels that fall
// outside the image are dropped — setting covered pixels to `value`.
void PaintBlob(const Blob& blob, int x, int y, uint8_t value, uint8_t* image, int width,
               int height);

}  // namespace mvtm
