// simulate — thin main: the declared option table, then RunSimulate().
#include <cstdio>
#include <iostream>
#include <string>

#include "cli/app.h"
#include "cli/options.h"
#include "simulate.h"

namespace {

constexpr const char* kAbout =
    "Drive a workspace's road live: a window showing the projective texture mapping of its "
    "photographs at the car's camera, the car steered by a wheel and pedals, a game controller "
    "or the keyboard, on a fixed-step vehicle simulation independent of the frame rate; "
    "adaptive quality holds the frame rate; sessions are recorded for drive, ptmrender and "
    "gazemap, and recorded controls replayed.";

constexpr const char* kFooter =
    "Keys: Left/Right steer, Up throttle, Down brake, R reverse, Backspace reset, H HUD, "
    "Escape or Q quit. Headless: SDL_VIDEODRIVER=offscreen, or --no-window.";

// "full detail" or "mesh simplified beyond D m".
std::string Detail(double lod_m) {
  if (lod_m <= 0) return "full detail";
  char b[48];
  std::snprintf(b, sizeof b, "mesh simplified beyond %g m", lod_m);
  return b;
}

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::SimulateOptions& o) {
  const auto r = mvtm::RunSimulate(o, std::cout);
  if (o.quiet || o.explain) return 0;
  for (const auto& l : r.log) std::fprintf(stderr, "simulate: %s\n", l.c_str());
  for (const auto& q : r.quality)
    std::fprintf(
        stderr, "simulate: t=%.2f s: quality level %d (render %.2fx, %d projectors, %s): %s\n",
        q.time, q.level, q.render_scale, q.projectors, Detail(q.lod_m).c_str(), q.why.c_str());
  if (r.frames) {
    auto st = [&r](const char* k) { return r.stages.count(k) ? r.stages.at(k) : 0.0; };
    std::fprintf(stderr,
                 "simulate: per frame: projectors %.1f ms (choosing, reading), mesh %.1f ms, "
                 "texturing %.1f ms, readback %.1f ms, fill %.1f ms\n",
                 st("load_ms"), st("draw_ms"), st("shade_ms"), st("readback_ms"), st("fill_ms"));
  }
  const auto& d = r.driving;
  std::fprintf(stderr,
               "simulate: %zu frames in %.2f s (%.1f fps, %.1f ms render), %zu steps over "
               "%.3f..%.3f s simulated; quality %d (render %.2fx, %d projectors, %s); input %s; "
               "ended: %s\n",
               r.frames, r.wall_s, r.wall_s > 0 ? r.frames / r.wall_s : 0.0,
               r.frames ? r.render_ms / r.frames : 0.0, r.steps, r.sim_start, r.sim_end,
               r.final_level, r.final_scale, r.final_projectors, Detail(r.final_lod_m).c_str(),
               r.device.c_str(), r.ended.c_str());
  std::fprintf(stderr,
               "simulate: drove %.1f m in %.1f s: speed %.1f +- %.1f km/h; lane offset %.2f m "
               "(SDLP %.2f m, max %.2f m); %zu resets",
               d.distance, d.duration, d.mean_speed * 3.6, d.sd_speed * 3.6, d.mean_offset, d.sdlp,
               d.max_offset, d.resets);
  if (d.speed_limit > 0)
    std::fprintf(stderr, "; over %.0f km/h for %.1f s (RMS excess %.2f km/h)", d.speed_limit * 3.6,
                 d.time_over, d.rms_over_limit * 3.6);
  std::fprintf(stderr, "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::SimulateOptions o;
  return mvtm::RunTool(
      mvtm::DeclareOptions(o), kAbout, argc, argv, [&] { return RunAndReport(o); }, kFooter);
}
