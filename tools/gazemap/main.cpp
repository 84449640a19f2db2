// gazemap — thin main: the declared option table, then RunGazemap().
#include "cli/app.h"
#include "cli/options.h"
#include "gazemap.h"

namespace {

constexpr const char* kAbout =
    "Map an eye tracker's gaze on ptmrender's frames back onto the road: I-VT fixations (Tobii "
    "defaults), the 3-D point on the workspace's mesh under each, the source photographs that "
    "see it unoccluded with the pixel in each, dwell time per area of interest (printed), and "
    "pictures: fixations on their photos, a top-down heat map.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::GazemapOptions& o) {
  mvtm::PrintGazemapReport(o, mvtm::RunGazemap(o));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::GazemapOptions o;
  return mvtm::RunTool(mvtm::DeclareOptions(o), kAbout, argc, argv,
                       [&] { return RunAndReport(o); });
}
