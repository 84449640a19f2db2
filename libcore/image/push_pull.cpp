#include "image/push_pull.h"

#include <algorithm>

#include "base/error.h"

namespace mvtm {

namespace {

// One pyramid level: colour premultiplied by nothing (plain means) and a weight in [0, 1].
struct Level {
  int w = 0, h = 0, c = 0;
  std::vector<float> colour, weight;
};

Level Pull(const Level& f) {
  Level g;
  g.w = (f.w + 1) / 2, g.h = (f.h + 1) / 2, g.c = f.c;
  g.colour.assign(size_t(g.w) * g.h * g.c, 0.f);
  g.weight.assign(size_t(g.w) * g.h, 0.f);
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      const size_t o = size_t(y) * g.w + x;
      float ws = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int fx = 2 * x + dx, fy = 2 * y + dy;
          if (fx >= f.w || fy >= f.h) continue;
          const size_t i = size_t(fy) * f.w + fx;
          const float w = f.weight[i];
          if (w <= 0) continue;
          ws += w;
          for (int ch = 0; ch < f.c; ++ch) g.colour[o * g.c + ch] += w * f.colour[i * f.c + ch];
        }
      if (ws > 0)
        for (int ch = 0; ch < g.c; ++ch) g.colour[o * g.c + ch] /= ws;
      g.weight[o] = std::min(1.f, ws);
    }
  return g;
}

// The coarser level g at fine pixel (x, y), bilinear between coarse pixel centres.
void Interpolate(const Level& g, int x, int y, float* out) {
  const float gx = std::clamp((x + 0.5f) / 2.f - 0.5f, 0.f, float(g.w - 1));
  const float gy = std::clamp((y + 0.5f) / 2.f - 0.5f, 0.f, float(g.h - 1));
  const int x0 = int(gx), y0 = int(gy);
  const int x1 = std::min(x0 + 1, g.w - 1), y1 = std::min(y0 + 1, g.h - 1);
  const float ax = gx - x0, ay = gy - y0;
  for (int ch = 0; ch < g.c; ++ch) {
    auto at = [&](int xx, int yy) { return g.colour[(size_t(yy) * g.w + xx) * g.c + ch]; };
    out[ch] = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x1, y0)) +
              ay * ((1 - ax) * at(x0, y1) + ax * at(x1, y1));
  }
}

// Push: f's colour where it is known, g's where it is not, in proportion to f's weight.
void Push(Level& f, const Level& g) {
  std::vector<float> up(size_t(f.c));
  for (int y = 0; y < f.h; ++y)
    for (int x = 0; x < f.w; ++x) {
      const size_t i = size_t(y) * f.w + x;
      const float w = f.weight[i];
      if (w >= 1) continue;
      Interpolate(g, x, y, up.data());
      for (int ch = 0; ch < f.c; ++ch)
        f.colour[i * f.c + ch] = w * f.colour[i * f.c + ch] + (1 - w) * up[size_t(ch)];
      f.weight[i] = 1;
    }
}

}  // namespace

bool PushPullFill(Image& img, const std::vector<uint8_t>& known) {
  if (known.size() != img.pixels())
    throw Error("push-pull: " + std::to_string(known.size()) + " known flags for " +
                std::to_string(img.pixels()) + " pixels");
  if (std::none_of(known.begin(), known.end(), [](uint8_t k) { return k != 0; })) return false;
  std::vector<Level> levels(1);
  Level& base = levels[0];
  base.w = img.width, base.h = img.height, base.c = img.channels;
  base.colour = img.data;
  base.weight.resize(img.pixels());
  for (size_t p = 0; p < img.pixels(); ++p) base.weight[p] = known[p] ? 1.f : 0.f;
  while (levels.back().w > 1 || levels.back().h > 1) levels.push_back(Pull(levels.back()));
  for (size_t l = levels.size() - 1; l-- > 0;) Push(levels[l], levels[l + 1]);
  for (size_t p = 0; p < img.pixels(); ++p)
    if (!known[p])
      for (int ch = 0; ch < img.channels; ++ch)
        img.data[p * img.channels + ch] = levels[0].colour[p * img.channels + ch];
  return true;
}

}  // namespace mvtm
