// ssim — thin main: the declared option table, then RunSsim() (ssim_tool.h).
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "ssim_tool.h"

namespace {

constexpr const char* kAbout =
    "Photo-consistency of two images or two folders of images (pairs matched by "
    "file name): mean SSIM (equal to scikit-image's Gaussian SSIM), zero-mean NCC "
    "and PSNR, as TSV (or JSON) on standard output.";
constexpr const char* kExitStatuses =
    "See man ssim for details. Exit status: 0 success, 1 data or I/O error, 2 usage error, "
    "3 images (or image and mask) differ in size.";

// Runs the tool and prints its summary; the exit status.
int RunAndReport(mvtm::SsimToolOptions& o) {
  try {
    return mvtm::RunSsim(o, std::cout);
  } catch (const mvtm::SizeMismatchError& e) {
    std::cerr << "ssim: error: " << e.what() << "\n";
    return mvtm::kExitSizeMismatch;
  }
}

}  // namespace

int main(int argc, char** argv) {
  mvtm::SsimToolOptions o;
  return mvtm::RunTool(
      mvtm::DeclareOptions(o), kAbout, argc, argv, [&] { return RunAndReport(o); }, kExitStatuses);
}
