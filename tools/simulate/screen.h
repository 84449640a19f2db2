// simulate's window: the rendered frames shown through SDL2 (a software window surface, so it
// works with SDL's offscreen and dummy video drivers and under Xvfb), side by side for several
// screens, scaled up from the render size, with the HUD drawn over them.
//
// HUD (the thesis's speedometer): speed in km/h (seven-segment digits, top left), the steering-
// wheel angle as a bar from the centre (left of centre: turning left; ±450° spans a third of
// the width each way), the reverse gear as a red block beside the speed, and the adaptive
// quality level as blocks (full quality: all lit).
// Thread safety: the main thread only.
#pragma once

#include <string>
#include <vector>

#include "image/image.h"

namespace mvtm {

struct HudState {
  double speed_kmh = 0;
  double steer_deg = 0;
  bool reverse = false;
  int quality = 0, qualities = 1;  // level (0 = full) of how many
};

class Screen {
 public:
  // A window of width x height pixels titled `title`. Throws Error with SDL's reason.
  Screen(int width, int height, const std::string& title);
  ~Screen();
  Screen(const Screen&) = delete;
  Screen& operator=(const Screen&) = delete;
  // Shows the frames (3-channel, 0..255, one per screen, left to right; each scaled to its
  // share of the window), with the HUD when `hud`.
  void Show(const std::vector<const Image*>& frames, const HudState* hud);
  // What the window shows now (3 channels, 0..255): a screenshot.
  Image Capture() const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  void* window_ = nullptr;  // SDL_Window*
  int width_, height_;
};

// Draws the HUD into a 3-channel 0..255 image, as Show() draws it over the window.
void DrawHud(Image& frame, const HudState& hud);
// The frames side by side, each scaled (nearest) to width/N x height, with the HUD when given:
// what a window of width x height would show (a screenshot without a window).
Image Compose(const std::vector<const Image*>& frames, int width, int height, const HudState* hud);

}  // namespace mvtm
