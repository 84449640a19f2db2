// pickview — thin main: the declared option table, then RunPickView().
#include <cstdio>
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "pickview.h"

namespace {

constexpr const char* kAbout =
    "Pick the best projector images for each query pose (nearest camera centre under a heading "
    "gate), or partner images between the passes of a road; exact or approximate search.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::PickViewOptions& o) {
  auto r = mvtm::RunPickView(o, std::cout, std::cin);
  if (!o.quiet) {
    std::fprintf(stderr, "pickview: %zu queries, %zu images indexed, %zu rows; %s %.3f us/query",
                 r.queries, r.candidates, r.rows, r.method.c_str(), r.us_per_query);
    if (r.grid_cell > 0) std::fprintf(stderr, " (cell %.3f)", r.grid_cell);
    if (r.compared)
      std::fprintf(stderr, "; against exact: miss rate %.4f (%zu of %zu), mean extra distance %.6f",
                   r.slots ? static_cast<double>(r.misses) / static_cast<double>(r.slots) : 0.0,
                   r.misses, r.slots, r.mean_extra);
    if (r.unmatched)
      std::fprintf(stderr, "; %zu queries with no image inside the heading gate", r.unmatched);
    if (r.partners_written)
      std::fprintf(stderr, "; wrote %s", r.partners_path.c_str());
    else if (!r.partners_path.empty())
      std::fprintf(stderr, "; %s up to date", r.partners_path.c_str());
    if (!r.why.empty()) std::fprintf(stderr, " [%s]", r.why.c_str());
    std::fprintf(stderr, "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::PickViewOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
