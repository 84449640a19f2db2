#include "screen.h"

#include <SDL2/SDL.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>

#include "base/error.h"

namespace mvtm {

namespace {

// A canvas the HUD draws rectangles on: an SDL surface's pixels or an Image.
struct Canvas {
  int width, height;
  std::function<void(int, int, int, int, uint8_t, uint8_t, uint8_t)> fill;
};

// Seven-segment digit `d` (0-9, or -1 for a minus sign) at (x, y), segment length s.
void Digit(const Canvas& c, int d, int x, int y, int s) {
  static const uint8_t kSegments[10] = {0x3F, 0x06, 0x5B, 0x4F, 0x66,
                                        0x6D, 0x7D, 0x07, 0x7F, 0x6F};  // gfedcba
  const int t = std::max(1, s / 5);
  const uint8_t on = d < 0 ? 0x40 : kSegments[d];
  const int rect[7][4] = {{x + t, y, s, t},
                          {x + s + t, y + t, t, s},
                          {x + s + t, y + s + 2 * t, t, s},
                          {x + t, y + 2 * s + 2 * t, s, t},
                          {x, y + s + 2 * t, t, s},
                          {x, y + t, t, s},
                          {x + t, y + s + t, s, t}};
  for (int k = 0; k < 7; ++k)
    if (on & (1 << k)) c.fill(rect[k][0], rect[k][1], rect[k][2], rect[k][3], 255, 230, 40);
}

// A non-negative integer right-aligned to `digits` places ending at x_right.
void Number(const Canvas& c, int value, int digits, int x_right, int y, int s) {
  const int pitch = s + 4 * std::max(1, s / 5);
  const bool neg = value < 0;
  value = std::abs(value);
  int x = x_right - pitch;
  for (int k = 0; k < digits; ++k, x -= pitch) {
    Digit(c, value % 10, x, y, s);
    value /= 10;
    if (value == 0) {
      if (neg) Digit(c, -1, x - pitch, y, s);
      break;
    }
  }
}

void Draw(const Canvas& c, const HudState& h) {
  const int s = std::max(4, c.height / 24);  // segment length
  const int pad = s;
  c.fill(0, 0, 6 * s, 3 * s + 2 * pad, 0, 0, 0);  // speed box
  Number(c, int(std::lround(std::abs(h.speed_kmh))), 3, 6 * s - pad / 2, pad, s);
  if (h.reverse) {  // an "R": a 7-segment "r" shape is too small; a red box says it
    c.fill(6 * s + pad, pad, s, 2 * s, 230, 40, 40);
  }
  // Steering bar along the bottom: centre tick, bar to the wheel angle (450 degrees = half).
  const int y = c.height - 2 * s, cx = c.width / 2, half = c.width / 3;
  c.fill(cx - half, y, 2 * half, std::max(2, s / 2), 40, 40, 40);
  const int len = int(std::lround(std::clamp(h.steer_deg / 450.0, -1.0, 1.0) * half));
  if (len > 0) c.fill(cx - len, y, len, std::max(2, s / 2), 255, 230, 40);
  if (len < 0) c.fill(cx, y, -len, std::max(2, s / 2), 255, 230, 40);
  c.fill(cx - 1, y - s / 2, 2, s + s / 2, 255, 255, 255);
  // Quality: one block per level, lit from the full one down to the current.
  for (int q = 0; q < h.qualities; ++q) {
    const bool lit = q >= h.quality;
    c.fill(c.width - (q + 1) * (s + 2) - pad, pad, s, s, lit ? 60 : 50, lit ? 200 : 50,
           lit ? 60 : 50);
  }
}

}  // namespace

Screen::Screen(int width, int height, const std::string& title) : width_(width), height_(height) {
  SDL_Window* w = SDL_CreateWindow(title.c_str(), SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                   width, height, 0);
  if (!w) throw Error(std::string("cannot open a window: ") + SDL_GetError());
  window_ = w;
}

Screen::~Screen() {
  if (window_) SDL_DestroyWindow(static_cast<SDL_Window*>(window_));
}

void Screen::Show(const std::vector<const Image*>& frames, const HudState* hud) {
  auto* win = static_cast<SDL_Window*>(window_);
  SDL_Surface* dst = SDL_GetWindowSurface(win);
  if (!dst) throw Error(std::string("the window has no surface: ") + SDL_GetError());
  const int n = int(frames.size());
  for (int i = 0; i < n; ++i) {
    const Image& f = *frames[size_t(i)];
    SDL_Surface* src =
        SDL_CreateRGBSurfaceWithFormat(0, f.width, f.height, 24, SDL_PIXELFORMAT_RGB24);
    if (!src) throw Error(std::string("cannot make a surface: ") + SDL_GetError());
    for (int y = 0; y < f.height; ++y) {
      auto* row = static_cast<uint8_t*>(src->pixels) + size_t(y) * size_t(src->pitch);
      for (int x = 0; x < f.width; ++x)
        for (int k = 0; k < 3; ++k)
          row[3 * x + k] = uint8_t(std::clamp(f.at(x, y, f.channels == 3 ? k : 0), 0.f, 255.f));
    }
    SDL_Rect r{i * width_ / n, 0, (i + 1) * width_ / n - i * width_ / n, height_};
    SDL_BlitScaled(src, nullptr, dst, &r);
    SDL_FreeSurface(src);
  }
  if (hud) {
    Canvas c{dst->w, dst->h, [dst](int x, int y, int w, int h, uint8_t r, uint8_t g, uint8_t b) {
               SDL_Rect rect{x, y, w, h};
               SDL_FillRect(dst, &rect, SDL_MapRGB(dst->format, r, g, b));
             }};
    Draw(c, *hud);
  }
  SDL_UpdateWindowSurface(win);
}

void DrawHud(Image& frame, const HudState& hud) {
  Canvas c{frame.width, frame.height,
           [&frame](int x, int y, int w, int h, uint8_t r, uint8_t g, uint8_t b) {
             const uint8_t rgb[3] = {r, g, b};
             for (int yy = std::max(0, y); yy < std::min(frame.height, y + h); ++yy)
               for (int xx = std::max(0, x); xx < std::min(frame.width, x + w); ++xx)
                 for (int k = 0; k < frame.channels && k < 3; ++k) frame.at(xx, yy, k) = rgb[k];
           }};
  Draw(c, hud);
}

Image Screen::Capture() const {
  SDL_Surface* src = SDL_GetWindowSurface(static_cast<SDL_Window*>(window_));
  if (!src) throw Error(std::string("the window has no surface: ") + SDL_GetError());
  SDL_Surface* rgb = SDL_ConvertSurfaceFormat(src, SDL_PIXELFORMAT_RGB24, 0);
  if (!rgb) throw Error(std::string("cannot read the window: ") + SDL_GetError());
  Image out(rgb->w, rgb->h, 3);
  for (int y = 0; y < rgb->h; ++y) {
    const auto* row = static_cast<const uint8_t*>(rgb->pixels) + size_t(y) * size_t(rgb->pitch);
    for (int x = 0; x < rgb->w; ++x)
      for (int k = 0; k < 3; ++k) out.at(x, y, k) = row[3 * x + k];
  }
  SDL_FreeSurface(rgb);
  return out;
}

Image Compose(const std::vector<const Image*>& frames, int width, int height, const HudState* hud) {
  Image out(width, height, 3);
  const int n = int(frames.size());
  for (int i = 0; i < n; ++i) {
    const Image& f = *frames[size_t(i)];
    const int x0 = i * width / n, x1 = (i + 1) * width / n;
    for (int y = 0; y < height; ++y)
      for (int x = x0; x < x1; ++x) {
        const int sx = std::min(f.width - 1, (x - x0) * f.width / std::max(1, x1 - x0));
        const int sy = std::min(f.height - 1, y * f.height / height);
        for (int k = 0; k < 3; ++k) out.at(x, y, k) = f.at(sx, sy, f.channels == 3 ? k : 0);
      }
  }
  if (hud) DrawHud(out, *hud);
  return out;
}

}  // namespace mvtm
