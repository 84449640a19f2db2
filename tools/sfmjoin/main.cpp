// sfmjoin — thin main: the declared option table, then RunSfmjoin().
#include <algorithm>
#include <cstdio>

#include "cli/app.h"
#include "cli/options.h"
#include "sfmjoin.h"

namespace {

constexpr const char* kAbout =
    "Join structure-from-motion models of overlapping stretches of one drive (each mapped on its "
    "own) into one model: each placed by the images it shares with the ones before it, each "
    "image kept from the model it lies most inside of.";

int RunAndReport(const mvtm::SfmjoinOptions& o) {
  const auto r = mvtm::RunSfmjoin(o);
  if (o.quiet) return 0;
  const std::string& out = o.paths.back();
  if (r.up_to_date) {
    std::fprintf(stderr, "sfmjoin: %s is up to date (--force rewrites)\n", out.c_str());
    return 0;
  }
  double worst = 0;
  for (const auto& m : r.models) worst = std::max(worst, m.misfit);
  std::fprintf(stderr,
               "sfmjoin: %zu models joined: %zu images, %zu points, %zu camera%s; shared cameras "
               "misfit at most %.3g %% of their extent (per model in %s/join.tsv)%s\n",
               r.models.size(), r.images, r.points, r.cameras, r.cameras == 1 ? "" : "s",
               100 * worst, out.c_str(), r.why.empty() ? "" : (" [" + r.why + "]").c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::SfmjoinOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
