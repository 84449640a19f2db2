// dynmask — thin main: the declared option table, then RunDynmask().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "dynmask.h"

namespace {

constexpr const char* kAbout =
    "Mask what is not the static road (vehicles, cyclists, pedestrians) without labels: each "
    "photo against its neighbours of the same drive and its partners of the other drives, warped "
    "through the static depth (photometric and optical-flow residuals), as a probability map "
    "(dynamic/NAME.png), then blobs tracked as "
    "segtrack tracks labels (masks/NAME.png, tracks.tsv).";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::DynmaskOptions& o) {
  const auto r = mvtm::RunDynmask(o);
  if (o.quiet) return 0;
  std::fprintf(stderr, "dynmask: %zu probability maps written, %zu up to date (depth: %s)",
               r.written, r.skipped, r.depth_source.c_str());
  if (r.written) std::fprintf(stderr, " (%.0f ms per image)", r.ms_per_image);
  if (r.with_partners)
    std::fprintf(stderr, "; %zu checked against other drives too", r.with_partners);
  if (r.with_ahead)
    std::fprintf(stderr, "; %zu checked against their drive's photos farther along", r.with_ahead);
  if (r.with_veto)
    std::fprintf(stderr,
                 "; %zu whose other drives' evidence their drive's photos farther along veto",
                 r.with_veto);
  if (r.with_behind)
    std::fprintf(stderr, " (%zu at their drive's end: the photos just behind)", r.with_behind);
  if (r.floating) std::fprintf(stderr, "; %zu blobs off the ground left out", r.floating);
  if (r.lying) std::fprintf(stderr, "; %zu blobs lying in the road left out", r.lying);
  if (r.surface)
    std::fprintf(stderr, "; %zu blobs on the static surface (hiding nothing) left out", r.surface);
  if (r.guessed)
    std::fprintf(stderr, "; %zu blobs mostly on corridor walls (a guessed depth) cleared there",
                 r.guessed);
  if (r.explained)
    std::fprintf(stderr, "; %zu pixels the photo's own depth explains cleared", r.explained);
  if (r.driven)
    std::fprintf(stderr, "; %zu pixels seen where a drive's car passed raised", r.driven);
  if (r.completed) std::fprintf(stderr, "; %zu blobs completed from their colours", r.completed);
  if (r.no_neighbours)
    std::fprintf(stderr, "; %zu images seen by no other photo (nothing masked)", r.no_neighbours);
  if (r.masked) {
    const auto& t = r.summary;
    std::fprintf(stderr,
                 "; masks: %zu written, %.2f %% of the image masked on average; %d tracks (%d "
                 "kept, %d rejected)",
                 r.masks_written, 100 * r.masked_share, t.tracks, t.kept, t.rejected);
    if (t.unsupported_gaps)
      std::fprintf(stderr, ", %zu gap fills the probability does not support left out",
                   t.unsupported_gaps);
  } else if (!o.frames.empty() || !o.shard.empty()) {
    std::fprintf(stderr, "; masks not made (a run without --frames/--shard makes them)");
  } else {
    std::fprintf(stderr, "; masks up to date");
  }
  if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
  std::fprintf(stderr, "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::DynmaskOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
