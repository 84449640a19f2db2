#include "workspace/assets.h"

#include <algorithm>
#include <cmath>

#include "base/atomic_file.h"
#include "base/error.h"
#include "image/mask.h"

namespace mvtm {

Image ResizeNearest(const Image& d, int w, int h) {
  if (d.width == w && d.height == h) return d;
  Image r(w, h, d.channels, d.bits);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int sx = std::min(d.width - 1, int((x + 0.5) * d.width / w));
      int sy = std::min(d.height - 1, int((y + 0.5) * d.height / h));
      for (int c = 0; c < d.channels; ++c) r.at(x, y, c) = d.at(sx, sy, c);
    }
  return r;
}

Image ReadSourceImage(const Workspace& ws, const std::string& name, const Camera& cam,
                      bool prefer_textures) {
  const fs::path p = prefer_textures ? ws.SourceImagePath(name) : ws.ImagePath(name);
  Image img = ReadImage(p.string());
  RequireImageSize(img, p.string(), cam.width, cam.height);
  return img;
}

namespace {

// Float map `d`, read from `p` (a scaled copy of the camera's image: round(W·s) × round(H·s)), at
// the camera's size, nearest neighbour. `fix` says how to remake it.
Image MapAtCamera(const Image& d, const fs::path& p, const Camera& cam, const std::string& fix) {
  // bakedepth --scale S writes round(W*S) x round(H*S): the same aspect within a pixel.
  const double s = double(d.width) / double(cam.width);
  if (d.width < 1 || std::fabs(double(d.height) - double(cam.height) * s) > 1.0)
    throw Error(p.string(), 0,
                "depth map is " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                    ", not the camera's " + std::to_string(cam.width) + "x" +
                    std::to_string(cam.height) + " at any scale (" + fix + ")");
  return ResizeNearest(d, int(cam.width), int(cam.height));
}

// The float map at `p` at the camera's size (MapAtCamera); empty when there is no file.
Image ReadMapAtCamera(const fs::path& p, const Camera& cam, const std::string& fix) {
  if (!fs::exists(p)) return Image();
  return MapAtCamera(ReadFloatMap(p.string()), p, cam, fix);
}

}  // namespace

Image ReadDepthAtCamera(const Workspace& ws, const std::string& name, const Camera& cam) {
  return ReadMapAtCamera(ws.DepthPath(name), cam, "rebake with bakedepth");
}

Image ReadSeenDepthAtCamera(const Workspace& ws, const std::string& name, const Camera& cam) {
  const fs::path p = ws.StereoDepthPath(name), cp = ws.StereoConfidencePath(name);
  Image d, c;
  {
    // densify killed between a pair's renames: both new; a live one's renames waited for.
    const FolderLock lock = LockForReading(ws.StereoDir());
    if (!fs::exists(p)) return Image();
    d = ReadFloatMap(p.string());
    if (fs::exists(cp)) c = ReadFloatMap(cp.string());
  }
  if (!c.empty() && (c.width != d.width || c.height != d.height))
    throw Error(cp.string(), 0,
                "confidence map is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                    ", its depth map " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                    " (rerun densify)");
  Image both(d.width, d.height, 2, 32);
  for (size_t i = 0; i < d.pixels(); ++i) {
    both.data[2 * i] = d.data[i * d.channels];
    both.data[2 * i + 1] = c.empty() ? 1.f : c.data[i * c.channels];
  }
  return MapAtCamera(both, p, cam, "rerun densify");
}

Image ReadMaskAtCamera(const Workspace& ws, const std::string& name, const Camera& cam) {
  const fs::path p = ws.MaskPath(name);
  if (!fs::exists(p)) return Image();
  Image m = ReadMask(p.string());
  RequireImageSize(m, p.string(), cam.width, cam.height);
  return m;
}

Image ReadLabelsAtCamera(const Workspace& ws, const std::string& name, const Camera& cam) {
  const fs::path p = ws.LabelPath(name);
  if (!fs::exists(p)) return Image();
  Image l = ReadImage(p.string());
  RequireImageSize(l, p.string(), cam.width, cam.height);
  return l;
}

}  // namespace mvtm
