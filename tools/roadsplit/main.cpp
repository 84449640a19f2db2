// roadsplit — thin main: the declared option table, then RunRoadSplit().
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "roadsplit.h"

namespace {

constexpr const char* kAbout =
    "Split a long workspace into a road: overlapping fragments along the path of record and "
    "at junctions where the drive passes a place again, ROAD/Graph.txt, and one workspace per "
    "fragment under ROAD/Models/SEQ/FRAGMENT/ that every tool runs on alone.";

}  // namespace

int main(int argc, char** argv) {
  mvtm::RoadSplitOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv, [&] {
    const mvtm::RoadSplitReport r = mvtm::RunRoadSplit(o);
    if (!o.quiet && r.up_to_date)
      std::fprintf(stderr, "roadsplit: %s is up to date (--force rewrites)\n", o.road.c_str());
    else if (!o.quiet)
      std::fprintf(stderr,
                   "roadsplit: %zu fragments of %.4g (path %.4g), %zu junctions, %zu images, "
                   "%zu triangles; %zu files linked, %zu copied%s\n",
                   r.fragments, r.fragment_length, r.path_length, r.junctions, r.images,
                   r.triangles, r.linked, r.copied,
                   r.why.empty() || r.why == "new" ? "" : (" [" + r.why + "]").c_str());
    return 0;
  });
}
