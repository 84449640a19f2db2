// segtrack — thin main: option table, then RunSegtrack() or RankSequences().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "segtrack.h"

int main(int argc, char** argv) {
  mvtm::SegtrackOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "segtrack",
      "Turn semantic label images into cleaned per-frame vehicle masks: connected components, "
      "centroid tracking, gap interpolation, Gaussian smoothing, false-positive rejection. "
      "With --rank, order sequences by total vehicle area.");
  app.add_option("PATHS", o.paths,
                 "LABELDIR WS: label images (*.png, name order) and the workspace written to; "
                 "with --rank: LABELDIR...")
      ->required()
      ->type_name("");
  auto* classes = app.add_option("--classes", o.classes,
                                 "Vehicle class ids, comma-separated (class-id or palette labels)")
                      ->type_name("IDS")
                      ->capture_default_str();
  auto* palette = app.add_option("--palette", o.palette,
                                 "Labels are RGB: FILE's pixels, in row-major order, are the "
                                 "colours of class 0, 1, ...")
                      ->type_name("FILE");
  auto* binary =
      app.add_flag("--binary", o.binary, "Labels are masks: first channel non-zero = vehicle");
  app.add_option("--max-jump", o.track.max_jump,
                 "Largest distance from a track's predicted centroid to its blob")
      ->type_name("PX")
      ->capture_default_str();
  app.add_option("--max-missed", o.track.max_missed,
                 "A track ends after N consecutive frames without a blob")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--max-gap", o.track.max_gap,
                 "Fill gaps of at most G missed frames by interpolation")
      ->type_name("G")
      ->capture_default_str();
  app.add_option("--smooth", o.track.smooth,
                 "Gaussian sigma in frames for centroid and size (0: off)")
      ->type_name("SIGMA")
      ->capture_default_str();
  app.add_option("--min-life", o.track.min_life, "Reject tracks spanning fewer than N frames")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--min-ratio", o.track.min_ratio,
                 "Reject tracks detected in less than this share of their span")
      ->type_name("R")
      ->capture_default_str();
  app.add_option("--dilate", o.track.dilate, "Dilate the masks by a disk of radius PX")
      ->type_name("PX")
      ->capture_default_str();
  app.add_flag("--rank", o.rank,
               "Print the LABELDIRs ordered by total vehicle area (fewest first) on stdout");
  app.add_flag("-q,--quiet", o.quiet, "No progress bar, no summary on stderr");
  binary->excludes(classes)->excludes(palette);
  return mvtm::RunMain(app, "segtrack", argc, argv, [&] {
    if (o.rank) {
      auto rows = mvtm::RankSequences(o);
      std::printf("rank\tarea\tfraction\tframes\tlabeldir\n");
      for (size_t i = 0; i < rows.size(); ++i)
        std::printf("%zu\t%.0f\t%.6f\t%zu\t%s\n", i + 1, rows[i].area, rows[i].fraction,
                    rows[i].frames, rows[i].labeldir.c_str());
      return 0;
    }
    auto r = mvtm::RunSegtrack(o);
    if (!o.quiet) {
      const auto& s = r.summary;
      std::cerr << "segtrack: " << s.frames << " frames, " << s.tracks << " tracks (" << s.kept
                << " kept, " << s.rejected << " rejected); blobs: " << s.detected << " detected, "
                << s.interpolated << " interpolated, " << s.rejected_blobs << " rejected";
      if (s.unfilled_gaps)
        std::cerr << "; " << s.unfilled_gaps << " gaps longer than --max-gap left open";
      std::cerr << "; masks in " << r.masks_dir.string() << "\n";
    }
    return 0;
  });
}
