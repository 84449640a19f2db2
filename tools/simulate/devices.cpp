#include "devices.h"

#include <SDL2/SDL.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

namespace {

constexpr double kKeySteerRate = 180;   // wheel degrees per second while a key is held
constexpr double kKeyReturnRate = 360;  // ... back to the centre when released
constexpr double kKeyMaxSteer = 450;    // the keyboard's wheel stops here

AxisMap ReadAxis(const nlohmann::json& j, AxisMap m, const std::string& path,
                 const std::string& key) {
  if (!j.is_object()) throw Error(path, 0, "'" + key + "' must be an object");
  for (const auto& [k, v] : j.items()) {
    const std::string where = "'" + key + "." + k + "'";
    if (k == "axis" && v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() < 64)
      m.axis = int(v.get<int64_t>());
    else if (k == "invert" && v.is_boolean())
      m.invert = v.get<bool>();
    else if (k == "dead_zone" && v.is_number() && v.get<double>() >= 0 && v.get<double>() < 1)
      m.dead_zone = v.get<double>();
    else if (k == "range" && v.is_string() && (v == "full" || v == "half"))
      m.half = v == "half";
    else if (k == "degrees" && v.is_number() && v.get<double>() > 0 && v.get<double>() <= 3600)
      m.degrees = v.get<double>();
    else
      throw Error(path, 0,
                  where +
                      ": unknown key or bad value (axis 0..63, invert true/false, dead_zone "
                      "[0, 1), range \"full\"/\"half\", degrees (0, 3600])");
  }
  return m;
}

// A finite number in the classic locale, else Error("FILE:LINE: bad WHAT: TEXT").
double Number(const std::string& text, const std::string& path, long line, const char* what) {
  try {
    return ParseDoubleArg(text, what);
  } catch (const std::exception&) {
    throw Error(path, line, std::string("bad ") + what + ": '" + text + "'");
  }
}

}  // namespace

InputMapping ReadInputMapping(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path, 0, "cannot open");
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw Error(path, 0, "not a JSON object");
  InputMapping m;
  m.given = true;
  for (const auto& [k, v] : j.items()) {
    if (k == "steer")
      m.steer = ReadAxis(v, m.steer, path, k);
    else if (k == "throttle")
      m.throttle = ReadAxis(v, m.throttle, path, k);
    else if (k == "brake")
      m.brake = ReadAxis(v, m.brake, path, k);
    else if (k == "reverse" && v.is_object() && v.size() == 1 && v.contains("button") &&
             v["button"].is_number_integer() && v["button"].get<int64_t>() >= 0 &&
             v["button"].get<int64_t>() < 256)
      m.reverse_button = int(v["button"].get<int64_t>());
    else
      throw Error(path, 0,
                  "'" + k +
                      "': expected steer, throttle, brake (objects) or reverse "
                      "({\"button\": N})");
  }
  return m;
}

std::vector<VirtualRow> ReadVirtualScript(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path, 0, "cannot open");
  std::vector<VirtualRow> rows;
  std::string line;
  long n = 0;
  size_t axes = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++n;
    const std::string t(Trim(line));
    if (t.empty() || t[0] == '#') continue;
    std::vector<std::string> f;
    std::istringstream ss(t);
    for (std::string w; ss >> w;) f.push_back(w);
    if (!header) {
      if (f.size() < 2 || f[0] != "time")
        throw Error(path, n, "the header must be 'time axis0 axis1 ...'");
      axes = f.size() - 1;
      header = true;
      continue;
    }
    VirtualRow r;
    r.line = n;
    r.time = Number(f[0], path, n, "time");
    if (f.size() == 2 && (f[1] == "detach" || f[1] == "attach")) {
      r.kind = f[1] == "detach" ? VirtualRow::kDetach : VirtualRow::kAttach;
    } else {
      if (f.size() != axes + 1)
        throw Error(path, n,
                    "expected " + std::to_string(axes + 1) + " fields (or 'TIME detach|attach')");
      for (size_t k = 1; k < f.size(); ++k) {
        const double v = Number(f[k], path, n, "axis value");
        if (!(v >= -32768 && v <= 32767) || v != std::floor(v))
          throw Error(path, n, "an axis value is an integer in -32768 .. 32767: " + f[k]);
        r.axes.push_back(static_cast<int>(v));
      }
    }
    if (!rows.empty() && !(r.time > rows.back().time)) throw Error(path, n, "times must increase");
    rows.push_back(r);
  }
  if (!header) throw Error(path, 0, "empty: no header 'time axis0 axis1 ...'");
  return rows;
}

Devices::Devices(InputMapping mapping, std::vector<VirtualRow> script, bool keyboard)
    : map_(mapping), script_(std::move(script)), keyboard_(keyboard) {
  if (!script_.empty())
    OpenDevice(AttachVirtual(), nullptr);
  else
    OpenAny(nullptr);
}

Devices::~Devices() {
  CloseDevice(nullptr, "");
  for (int i = 0; virtual_instance_ >= 0 && i < SDL_NumJoysticks(); ++i)
    if (SDL_JoystickGetDeviceInstanceID(i) == virtual_instance_) SDL_JoystickDetachVirtual(i);
}

int Devices::AttachVirtual() {
  size_t axes = 0;
  for (const VirtualRow& r : script_) axes = std::max(axes, r.axes.size());
  const int index = SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_WHEEL, int(axes), 8, 0);
  if (index < 0)
    throw Error(std::string("cannot attach SDL's virtual joystick: ") + SDL_GetError());
  virtual_instance_ = SDL_JoystickGetDeviceInstanceID(index);
  return index;
}

void Devices::OpenAny(InputEvents* ev) {
  for (int i = 0; i < SDL_NumJoysticks() && !joystick_; ++i) OpenDevice(i, ev);
}

void Devices::OpenDevice(int index, InputEvents* ev) {
  if (joystick_) return;
  const bool is_virtual = SDL_JoystickGetDeviceInstanceID(index) == virtual_instance_;
  if (SDL_IsGameController(index) && !is_virtual && !map_.given) {
    auto* c = SDL_GameControllerOpen(index);
    if (!c) return;
    controller_ = c;
    joystick_ = SDL_GameControllerGetJoystick(c);
    name_ = SDL_GameControllerName(c) ? SDL_GameControllerName(c) : "game controller";
  } else {
    auto* j = SDL_JoystickOpen(index);
    if (!j) return;
    joystick_ = j;
    name_ = SDL_JoystickName(j) ? SDL_JoystickName(j) : "joystick";
  }
  instance_ = SDL_JoystickInstanceID(static_cast<SDL_Joystick*>(joystick_));
  if (ev) ev->log.push_back("device attached: " + name_);
}

void Devices::CloseDevice(InputEvents* ev, const std::string& why) {
  if (!joystick_) return;
  if (ev) ev->log.push_back("device " + why + ": " + name_ + " (keyboard only)");
  if (controller_)
    SDL_GameControllerClose(static_cast<SDL_GameController*>(controller_));
  else
    SDL_JoystickClose(static_cast<SDL_Joystick*>(joystick_));
  joystick_ = controller_ = nullptr;
  instance_ = -1;
  name_.clear();
}

InputEvents Devices::Poll() {
  InputEvents ev;
  ev.log = std::move(pending_.log);
  pending_.log.clear();
  SDL_Event e;
  while (SDL_PollEvent(&e)) {
    if (e.type == SDL_QUIT) ev.quit = true;
    if (e.type == SDL_WINDOWEVENT && e.window.event == SDL_WINDOWEVENT_CLOSE) ev.quit = true;
    if (e.type == SDL_JOYDEVICEADDED && !joystick_) OpenDevice(e.jdevice.which, &ev);
    if (e.type == SDL_JOYDEVICEREMOVED && e.jdevice.which == instance_) {
      CloseDevice(&ev, "unplugged");
      OpenAny(&ev);
    }
    if (e.type == SDL_KEYDOWN && keyboard_ && !e.key.repeat) {
      const SDL_Keycode k = e.key.keysym.sym;
      if (k == SDLK_ESCAPE || k == SDLK_q) ev.quit = true;
      if (k == SDLK_BACKSPACE) ev.reset = true;
      if (k == SDLK_h) ev.toggle_hud = true;
      if (k == SDLK_r) reverse_ = !reverse_;
    }
  }
  return ev;
}

double Devices::Axis(const AxisMap& m) const {
  if (m.axis < 0 || !joystick_) return 0;
  auto* j = static_cast<SDL_Joystick*>(joystick_);
  if (m.axis >= SDL_JoystickNumAxes(j)) return 0;
  double x = std::clamp(SDL_JoystickGetAxis(j, m.axis) / 32767.0, -1.0, 1.0);
  if (m.invert) x = -x;
  return x;
}

namespace {

// A centred axis (steering) with its dead zone, −1 … 1.
double Centred(double x, double dz) {
  const double a = std::abs(x);
  return a <= dz ? 0 : std::copysign((a - dz) / (1 - dz), x);
}

// A pedal, 0 … 1.
double Pedal(double x, const AxisMap& m) {
  const double p = m.half ? std::max(0.0, x) : (x + 1) / 2;
  return p <= m.dead_zone ? 0 : std::min(1.0, (p - m.dead_zone) / (1 - m.dead_zone));
}

}  // namespace

Pedals Devices::Sample(double t, double dt) {
  while (next_row_ < script_.size() && script_[next_row_].time <= t) {
    const VirtualRow& r = script_[next_row_++];
    const bool on_virtual = joystick_ && instance_ == virtual_instance_;
    if (r.kind == VirtualRow::kDetach && virtual_instance_ >= 0) {
      if (on_virtual) CloseDevice(&pending_, "unplugged");
      for (int i = 0; i < SDL_NumJoysticks(); ++i)
        if (SDL_JoystickGetDeviceInstanceID(i) == virtual_instance_) SDL_JoystickDetachVirtual(i);
      virtual_instance_ = -1;
      OpenAny(&pending_);
    } else if (r.kind == VirtualRow::kAttach && virtual_instance_ < 0) {
      const int index = AttachVirtual();
      if (!joystick_) OpenDevice(index, &pending_);
    } else if (r.kind == VirtualRow::kAxes && on_virtual) {
      for (size_t k = 0; k < r.axes.size(); ++k)
        SDL_JoystickSetVirtualAxis(static_cast<SDL_Joystick*>(joystick_), int(k),
                                   static_cast<Sint16>(r.axes[k]));
    }
  }
  SDL_JoystickUpdate();
  if (joystick_ && !SDL_JoystickGetAttached(static_cast<SDL_Joystick*>(joystick_))) {
    CloseDevice(&pending_, "unplugged");
    OpenAny(&pending_);
  }
  Pedals p;
  if (controller_) {
    auto* c = static_cast<SDL_GameController*>(controller_);
    const double x = SDL_GameControllerGetAxis(c, SDL_CONTROLLER_AXIS_LEFTX) / 32767.0;
    p.steer_deg =
        -map_.steer.degrees * Centred(std::clamp(x, -1.0, 1.0), map_.steer.dead_zone) + 0.0;
    p.throttle = SDL_GameControllerGetAxis(c, SDL_CONTROLLER_AXIS_TRIGGERRIGHT) / 32767.0;
    p.brake = SDL_GameControllerGetAxis(c, SDL_CONTROLLER_AXIS_TRIGGERLEFT) / 32767.0;
    const bool b = SDL_GameControllerGetButton(c, SDL_CONTROLLER_BUTTON_B);
    if (b && !reverse_down_) reverse_ = !reverse_;
    reverse_down_ = b;
  } else if (joystick_) {
    // A wheel turned right gives a positive axis; mvtm's steering is positive to the left.
    p.steer_deg = -map_.steer.degrees * Centred(Axis(map_.steer), map_.steer.dead_zone) + 0.0;
    p.throttle = Pedal(Axis(map_.throttle), map_.throttle);
    p.brake = Pedal(Axis(map_.brake), map_.brake);
    auto* j = static_cast<SDL_Joystick*>(joystick_);
    const bool b = map_.reverse_button < SDL_JoystickNumButtons(j) &&
                   SDL_JoystickGetButton(j, map_.reverse_button);
    if (b && !reverse_down_) reverse_ = !reverse_;
    reverse_down_ = b;
  }
  if (keyboard_) {
    const Uint8* keys = SDL_GetKeyboardState(nullptr);
    const int turn = int(keys[SDL_SCANCODE_LEFT] != 0) - int(keys[SDL_SCANCODE_RIGHT] != 0);
    if (turn != 0)
      key_steer_ = std::clamp(key_steer_ + turn * kKeySteerRate * dt, -kKeyMaxSteer, kKeyMaxSteer);
    else
      key_steer_ =
          std::copysign(std::max(0.0, std::abs(key_steer_) - kKeyReturnRate * dt), key_steer_);
    p.steer_deg += key_steer_;
    if (keys[SDL_SCANCODE_UP]) p.throttle = 1;
    if (keys[SDL_SCANCODE_DOWN]) p.brake = 1;
  }
  p.throttle = std::clamp(p.throttle, 0.0, 1.0);
  p.brake = std::clamp(p.brake, 0.0, 1.0);
  p.reverse = reverse_;
  return p;
}

std::string Devices::Describe() const {
  return joystick_ ? name_ : keyboard_ ? "keyboard" : "none";
}

}  // namespace mvtm
