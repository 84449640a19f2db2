// segtrack — thin main: the declared option table, then RunSegtrack() or RankSequences().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "segtrack.h"

namespace {

void PrintSummary(const mvtm::SegtrackReport& r) {
  if (!r.tracked) {
    std::cerr << "segtrack: " << r.frames << " frames, masks and tracks.tsv up to date; masks in "
              << r.masks_dir.string() << "\n";
    return;
  }
  const auto& s = r.summary;
  std::cerr << "segtrack: " << s.frames << " frames, " << s.tracks << " tracks (" << s.kept
            << " kept, " << s.rejected << " rejected); blobs: " << s.detected << " detected, "
            << s.interpolated << " interpolated, " << s.rejected_blobs << " rejected";
  if (s.unfilled_gaps)
    std::cerr << "; " << s.unfilled_gaps << " gaps longer than --max-gap left open";
  std::cerr << "; masks in " << r.masks_dir.string();
  if (r.skipped) std::cerr << "; " << r.written << " written, " << r.skipped << " up to date";
  if (!r.why.empty()) std::cerr << " [" << r.why << "]";
  std::cerr << "\n";
}

}  // namespace

namespace {

constexpr const char* kAbout =
    "Turn semantic label images into cleaned per-frame vehicle masks: connected components, "
    "centroid tracking, gap interpolation, Gaussian smoothing, false-positive rejection. "
    "With --rank, order sequences by total vehicle area.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::SegtrackOptions& o) {
  if (o.rank) {
    auto rows = mvtm::RankSequences(o);
    std::printf("rank\tarea\tfraction\tframes\tlabeldir\n");
    for (size_t i = 0; i < rows.size(); ++i)
      std::printf("%zu\t%.0f\t%.6f\t%zu\t%s\n", i + 1, rows[i].area, rows[i].fraction,
                  rows[i].frames, rows[i].labeldir.c_str());
    return 0;
  }
  auto r = mvtm::RunSegtrack(o);
  if (!o.quiet) PrintSummary(r);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::SegtrackOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
