// gazemap — thin main: option table, then RunGazemap().
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "gazemap.h"

int main(int argc, char** argv) {
  mvtm::GazemapOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "gazemap",
      "Map an eye tracker's gaze on ptmrender's frames back onto the road: I-VT fixations (Tobii "
      "defaults), the 3-D point on the workspace's mesh under each, the source photographs that "
      "see it unoccluded with the pixel in each, dwell time per area of interest (printed), and "
      "pictures: fixations on their photos, a top-down heat map.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/, mesh.ply; depth/, labels/ used)")
      ->required();
  app.add_option("FRAMES", o.frames,
                 "The poses the frames were rendered at (ptmrender --poses: TUM, whose timestamps "
                 "are the display times, KITTI or COLMAP images.txt with --frame-rate)")
      ->required();
  app.add_option("GAZE", o.gaze,
                 "Gaze trace: a header naming 'time x y [valid]' (seconds, screen pixels, 0/1), "
                 "then one row per sample")
      ->required();
  app.add_option("OUT", o.out, "Output folder (fixations.tsv, sources.tsv, aoi.tsv, pictures)")
      ->required();
  app.add_option("--frame-rate", o.frame_rate,
                 "Frames per second: frame i is shown at i/HZ seconds (instead of FRAMES' times)");
  app.add_option("--screen", o.screen,
                 "WxH: the screen in pixels, the render shown full screen (default: the render "
                 "camera's size)");
  app.add_option("--screen-mm", o.screen_mm, "WxH: the screen's physical size in millimetres");
  app.add_option("--distance", o.distance, "Eye to screen centre, millimetres (with --screen-mm)");
  app.add_option("--px-per-degree", o.px_per_degree,
                 "Screen pixels per degree of visual angle (instead of --screen-mm, --distance)");
  app.add_option("--max-gap", o.max_gap, "I-VT gap fill-in: fill gaps up to this, ms (0: off)")
      ->capture_default_str();
  app.add_option("--noise-median", o.noise_median,
                 "I-VT noise reduction: moving-median window in samples, odd (0: off)")
      ->capture_default_str();
  app.add_option("--velocity-window", o.velocity_window,
                 "I-VT velocity window, ms (at least 3 samples)")
      ->capture_default_str();
  app.add_option("--threshold", o.threshold, "I-VT velocity threshold, degrees per second")
      ->capture_default_str();
  app.add_option("--merge-time", o.merge_time,
                 "Merge adjacent fixations less than this apart, ms (0: off)")
      ->capture_default_str();
  app.add_option("--merge-angle", o.merge_angle,
                 "... and less than this apart in visual angle, degrees")
      ->capture_default_str();
  app.add_option("--min-duration", o.min_duration,
                 "Discard fixations shorter than this, ms (0: keep all)")
      ->capture_default_str();
  mvtm::AddChoiceOption(app, "--visibility", o.visibility, mvtm::kGazeVisibility,
                        "depth: a photo's baked depth map (WS/depth) decides if it sees the "
                        "point, a ray where it has none; ray: always a ray against the mesh");
  app.add_option("--depth-tolerance", o.depth_tolerance,
                 "Relative depth tolerance of the depth-map test")
      ->capture_default_str();
  app.add_option("--aoi-boxes", o.aoi_boxes,
                 "Areas of interest from 3-D boxes: lines 'name xmin ymin zmin xmax ymax zmax' "
                 "(default: classes of the label images WS/labels)");
  app.add_option("--heatmap-size", o.heatmap_size, "Heat map's larger side, pixels")
      ->capture_default_str();
  app.add_option("--heatmap-sigma", o.heatmap_sigma,
                 "Heat map Gaussian, model units (0: 1% of the map)")
      ->capture_default_str();
  app.add_flag("--no-pictures", o.no_pictures, "Write the tables only (no PNGs)");
  app.add_flag("--force", o.force, "Rewrite OUT when it is newer than its inputs");
  mvtm::AddQuietOption(app, o.quiet);
  return mvtm::RunMain(app, "gazemap", argc, argv, [&] {
    const auto r = mvtm::RunGazemap(o);
    if (!o.quiet && !r.ignored_columns.empty()) {
      std::string cols;
      for (const auto& c : r.ignored_columns) cols += (cols.empty() ? "" : " ") + c;
      std::fprintf(stderr, "gazemap: note: %s: columns not used: %s\n", o.gaze.c_str(),
                   cols.c_str());
    }
    if (r.up_to_date) {
      // The table of the run that wrote OUT, as a fresh run prints it.
      std::ifstream table(std::filesystem::path(o.out) / "aoi.tsv");
      std::cout << table.rdbuf() << std::flush;
      if (!o.quiet)
        std::fprintf(stderr, "gazemap: %s is up to date (--force rewrites)\n", o.out.c_str());
      return 0;
    }
    std::fputs(mvtm::FormatDwellTable(r.aoi).c_str(), stdout);
    if (o.quiet) return 0;
    std::fprintf(stderr,
                 "gazemap: %zu samples (%zu invalid: %zu flagged, %zu not finite; %zu filled in "
                 "%zu gaps); %zu fixations (%zu merges, %zu discarded as short); %zu on the "
                 "mesh, %zu seen by a photo (%zu sources); AOIs: %s; %zu pictures\n",
                 r.samples, r.invalid_flagged + r.invalid_nonfinite, r.invalid_flagged,
                 r.invalid_nonfinite, r.samples_filled, r.gaps_filled, r.fixations, r.merged,
                 r.discarded, r.on_mesh, r.with_source, r.source_rows, r.aoi_from.c_str(),
                 r.pictures);
    return 0;
  });
}
