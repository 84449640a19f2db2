// pickview — thin main: option table, then RunPickView().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "index/pose_index.h"
#include "pickview.h"

int main(int argc, char** argv) {
  mvtm::PickViewOptions o;
  CLI::App app;
  mvtm::ConfigureApp(
      app, "pickview",
      "Pick the best projector images for each query pose (nearest camera centre under a heading "
      "gate), or partner images between the passes of a road; exact or approximate search.");
  app.add_option("WS", o.workspace, "Workspace folder (sparse/; masks/ with --prefer-unmasked)")
      ->required();
  app.add_option("QUERIES", o.queries,
                 "Query poses: COLMAP images.txt, TUM or KITTI trajectory; - for stdin (default: "
                 "the workspace's own images)");
  app.add_option("--k", o.k, "Images per query")->capture_default_str();
  app.add_option("--max-heading", o.max_heading_deg,
                 "Heading gate, degrees: images looking further away are never picked")
      ->capture_default_str();
  app.add_option("--heading-weight", o.heading_weight,
                 "Metres of cost per radian of heading difference")
      ->capture_default_str();
  app.add_option("--ahead-weight", o.ahead_weight,
                 "Metres of cost per metre an image is ahead of the query (ptmrender uses 1; 0 = "
                 "nearest pose)")
      ->capture_default_str();
  mvtm::AddChoiceOption(app, "--method", o.method, mvtm::SearchMethodNames(),
                        "Search: kdtree and brute are exact; flann (randomised trees) and grid9 "
                        "(the thesis's grid) approximate");
  app.add_option("--checks", o.checks,
                 "flann: leaves visited per query (more: slower, fewer misses)")
      ->capture_default_str();
  app.add_flag("--exclude-self", o.exclude_self,
               "With the workspace's own images as queries: never pick the image itself");
  app.add_flag("--partners", o.partners,
               "Partners mode: for every image, the nearest images of the other passes (name "
               "prefix before '_'); also writes WS/partners.tsv");
  app.add_option("--other", o.other, "Partners: the other pass is this workspace");
  app.add_flag(
      "--prefer-unmasked", o.prefer_unmasked,
      "Partners: near-ties go to images with fewer mask pixels where the image's own mask is set");
  app.add_option(
         "--tie-margin", o.tie_margin,
         "Partners with --prefer-unmasked: metres of cost within which candidates are near-ties")
      ->capture_default_str();
  app.add_flag("-q,--quiet", o.quiet,
               "No summary on stderr (and no comparison with the exact search)");
  return mvtm::RunMain(app, "pickview", argc, argv, [&] {
    auto r = mvtm::RunPickView(o, std::cout, std::cin);
    if (!o.quiet) {
      std::fprintf(stderr, "pickview: %zu queries, %zu images indexed, %zu rows; %s %.3f us/query",
                   r.queries, r.candidates, r.rows, r.method.c_str(), r.us_per_query);
      if (r.grid_cell > 0) std::fprintf(stderr, " (cell %.3f)", r.grid_cell);
      if (r.compared)
        std::fprintf(stderr,
                     "; against exact: miss rate %.4f (%zu of %zu), mean extra distance %.6f",
                     r.slots ? static_cast<double>(r.misses) / static_cast<double>(r.slots) : 0.0,
                     r.misses, r.slots, r.mean_extra);
      if (r.unmatched)
        std::fprintf(stderr, "; %zu queries with no image inside the heading gate", r.unmatched);
      if (!r.partners_path.empty()) std::fprintf(stderr, "; wrote %s", r.partners_path.c_str());
      std::fprintf(stderr, "\n");
    }
    return 0;
  });
}
