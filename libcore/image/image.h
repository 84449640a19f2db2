// mvtm — images in memory and on disk.
//
// Conventions:
//  * Image holds interleaved float samples, row 0 at the top, in the file's own scale: 8-bit
//    files read as 0..255, 16-bit as 0..65535 (both exact in float), float files as stored.
//    `bits` remembers the source depth (8, 16, 32 = float) and fixes the SSIM data range.
//  * Reading and writing go through OpenImageIO (PNG, JPEG, TIFF, EXR, ...; format by
//    extension). Writes are atomic (temporary name + rename). Masks and labels are PNG.
//  * Writing converts to `bits`: 8/16 round to nearest and clamp, 32 writes float (EXR/TIFF).
//
// Thread safety: ReadImage/WriteImage may be called concurrently on different files.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mvtm {

struct Image {
  int width = 0, height = 0, channels = 0;
  int bits = 8;  // 8, 16 or 32 (float)
  std::vector<float> data;

  Image() = default;
  Image(int w, int h, int c, int b = 8, float fill = 0.f)
      : width(w), height(h), channels(c), bits(b), data(static_cast<size_t>(w) * h * c, fill) {}

  float& at(int x, int y, int c = 0) {
    return data[(static_cast<size_t>(y) * width + x) * channels + c];
  }
  float at(int x, int y, int c = 0) const {
    return data[(static_cast<size_t>(y) * width + x) * channels + c];
  }
  size_t pixels() const { return static_cast<size_t>(width) * height; }
  bool empty() const { return data.empty(); }
  // The nominal maximum of the type: 255, 65535, or 1 for float.
  double MaxValue() const { return bits == 8 ? 255.0 : bits == 16 ? 65535.0 : 1.0; }
};

// Largest images read (an image header is not trusted with an allocation beyond these).
inline constexpr int kMaxReadImageSide = 65536;
inline constexpr uint64_t kMaxImagePixels = uint64_t(1) << 30;

// Size and channel count without reading the pixels. Throws Error.
struct ImageSpecInfo {
  int width = 0, height = 0, channels = 0, bits = 8;
};
ImageSpecInfo ReadImageSpec(const std::string& path);

// Throws Error("PATH: ...") when the file is missing, unreadable or of an unsupported type.
Image ReadImage(const std::string& path);
// A float map (depth maps, confidences): one 32-bit float channel, else an Error naming the file
// (an RGB PNG saved as NAME.exr, a 3-channel EXR).
Image ReadFloatMap(const std::string& path);
// Throws Error(path, 0, "image is AxB but its camera is WxH") unless `img` is w×h.
void RequireImageSize(const Image& img, const std::string& path, uint64_t w, uint64_t h);
// How a PNG is compressed; the pixels are the same either way.
enum class PngCompression {
  kDefault,   // zlib level 6, libpng's adaptive row filters: the bytes OpenImageIO 2.4 wrote
  kFast,      // zlib level 1, run-length strategy, adaptive row filters: for photos and renders
              // 3x faster to encode than kDefault and smaller (a KITTI colour frame: 731 KB
              // against 797 KB)
  kFastFlat,  // zlib level 1, run-length strategy, no row filter: for masks and index maps
              // (long runs of one value) 4-5x faster than kDefault at about the same size
};

// Writes atomically; the format follows the extension. Throws Error.
void WriteImage(const std::string& path, const Image& img,
                PngCompression png = PngCompression::kDefault);

// Images that only make sense together (densify's depth map and its confidence), in one folder,
// written as one step (WriteTogetherAtomic): a full disk leaves every final file as it was, and
// a writer killed between the renames leaves a journal that the next FinishInterruptedWrites of
// the folder completes, so a reader that calls it first never meets a new image beside an old
// one. The pipeline's own formats only (8/16-bit PNG, float EXR): else an Error.
struct ImageToWrite {
  std::string path;
  const Image* image;
};
void WriteImagesTogether(const std::vector<ImageToWrite>& images);

// One channel: the mean of the colour channels (alpha excluded when there are 2 or 4 channels).
Image ToGrey(const Image& img);

}  // namespace mvtm
