// frames — thin main: the declared option table, then RunFrames().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "frames.h"

namespace {

constexpr const char* kAbout =
    "Turn a dashcam video into the images of a road build: frames chosen by travelled image "
    "motion (a stop gives one frame), blurred frames dropped, a crop, burned-in overlays "
    "masked, a timestamp per frame.";

int RunAndReport(mvtm::FramesOptions& o) {
  const auto r = mvtm::RunFrames(o);
  if (o.quiet) return 0;
  if (r.up_to_date) {
    std::fprintf(stderr, "frames: %s is up to date (--force rewrites)\n", o.outdir.c_str());
    return 0;
  }
  std::fprintf(stderr,
               "frames: %zu of %zu decoded frames kept (%.1f s); %zu blurred, %zu too close to "
               "the last kept one; %zu written, %zu of an earlier selection removed; overlay "
               "%zu pixels%s\n",
               r.kept, r.decoded, r.duration, r.blurred, r.still, r.written, r.removed,
               r.overlay_pixels, r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  if (r.expected > r.decoded + 1)
    std::fprintf(stderr, "frames: warning: %s announces %zu frames; decoding stopped after %zu\n",
                 o.video.c_str(), r.expected, r.decoded);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::FramesOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
