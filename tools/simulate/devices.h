// simulate's input: the keyboard, game controllers and wheels with pedals through SDL2, with
// hot-plug, a mapping file, and SDL's virtual joystick driven by a script (tests, demos).
//
// Steering is the steering-wheel angle in degrees (positive: left), as in drive's controls log.
//  * Keyboard: Left/Right turn the wheel at 180 °/s while held and let it return at 360 °/s;
//    Up is full throttle, Down full brake, R toggles reverse, Backspace resets the car to the
//    nearest recorded pose, H toggles the HUD, Escape or Q ends the session.
//  * A joystick or wheel (the first opened; others are ignored until it is unplugged): axes
//    mapped by the mapping file (below); without one, axis 0 is the wheel (full deflection =
//    ±450 °), axis 1 the throttle and axis 2 the brake, each 0 (and below) released … 32767
//    pressed ("range": "half"; a wheel's pedals that span the whole axis want "full").
//  * A game controller SDL knows (SDL_GameController): left stick x steers (full = ±450 °), the
//    right trigger is the throttle, the left the brake, button B toggles reverse. With a mapping
//    file every device, game controllers too, is read as a raw joystick through it.
//  When the device in use is unplugged, the next one connected (if any) takes over.
//  A device's pedals and wheel add to the keyboard's (clamped): either drives.
// Mapping file (JSON): {"steer": {"axis": 0, "invert": false, "dead_zone": 0.02,
//   "degrees": 450}, "throttle": {"axis": 1, "invert": false, "dead_zone": 0.02,
//   "range": "full"}, "brake": {...}, "reverse": {"button": 4}}; "range": "full" maps
//   −1 … 1 to 0 … 1 (a pedal on a whole axis), "half" (the default) maps 0 … 1 (and below 0 to
//   0). Missing
//   keys keep the defaults; unknown keys are errors (FILE: what).
// Virtual input script (--virtual-input): a header "time axis0 axis1 ..." (seconds of simulation
// time, then raw axis values −32768 … 32767), rows in increasing time; a row whose first axis
// field is "detach" unplugs the virtual device (a device lost mid-session), "attach" plugs it
// back. SDL's virtual joystick then goes through the very path a real wheel does.
// Thread safety: the main thread only (SDL's event and joystick functions).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "drive/vehicle.h"

namespace mvtm {

struct AxisMap {
  int axis = -1;  // -1: none
  bool invert = false;
  double dead_zone = 0.02;  // of full deflection
  bool half = false;        // pedal range: 0 … 1 instead of −1 … 1
  double degrees = 450;     // steering: wheel degrees at full deflection
};

struct InputMapping {
  AxisMap steer{0, false, 0.02, false, 450};
  AxisMap throttle{1, false, 0.02, true, 450};
  AxisMap brake{2, false, 0.02, true, 450};
  int reverse_button = 4;
  bool given = false;  // read from a file: every device is then a raw joystick read through it
};

// Reads a mapping file (Error "FILE: what" when malformed).
InputMapping ReadInputMapping(const std::string& path);

// One script row: at `time`, set the axes (or detach/attach the device).
struct VirtualRow {
  double time = 0;
  enum Kind { kAxes, kDetach, kAttach } kind = kAxes;
  std::vector<int> axes;
  long line = 0;
};
// Reads a virtual input script (Error "FILE:LINE: what").
std::vector<VirtualRow> ReadVirtualScript(const std::string& path);

// What happened besides the pedals since the last call.
struct InputEvents {
  bool quit = false;             // window closed, Escape, Q, SIGINT/SIGTERM
  bool reset = false;            // Backspace
  bool toggle_hud = false;       // H
  std::vector<std::string> log;  // "wheel attached: NAME", "wheel unplugged: NAME", ...
};

class Devices {
 public:
  // SDL must be initialised with video, joystick and game controller. `keyboard`: read keys (a
  // window is open). `script` (optional): a virtual joystick is attached and driven by it.
  Devices(InputMapping mapping, std::vector<VirtualRow> script, bool keyboard);
  ~Devices();
  Devices(const Devices&) = delete;
  Devices& operator=(const Devices&) = delete;

  // Pumps SDL's events (hot-plug, quit, keys) once per frame; also reports the devices lost or
  // found by Sample() since the last call.
  InputEvents Poll();
  // The controls at simulation time t after a step of dt seconds: the script's rows up to t are
  // applied first, then the devices are read; the keyboard's wheel moves by its rate over dt.
  Pedals Sample(double t, double dt);
  // The device in use: its name, else "keyboard" with a window, else "none".
  std::string Describe() const;

 private:
  void OpenDevice(int index, InputEvents* ev);
  void OpenAny(InputEvents* ev);  // the first connected device, when none is open
  int AttachVirtual();            // the virtual device's index (Error when SDL refuses)
  void CloseDevice(InputEvents* ev, const std::string& why);
  double Axis(const AxisMap& m) const;

  InputMapping map_;
  std::vector<VirtualRow> script_;
  size_t next_row_ = 0;
  bool keyboard_;
  int virtual_instance_ = -1;   // the virtual device's instance id while attached
  void* joystick_ = nullptr;    // SDL_Joystick*
  void* controller_ = nullptr;  // SDL_GameController*
  int instance_ = -1;           // its instance id
  std::string name_;
  InputEvents pending_;   // what Sample() saw, reported by the next Poll()
  double key_steer_ = 0;  // the keyboard's wheel angle, degrees
  bool reverse_ = false, reverse_down_ = false;
};

}  // namespace mvtm
