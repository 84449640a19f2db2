// ssim — thin main: the declared option table, then RunSsim() (ssim_tool.h).
#include <iostream>

#include "cli/app.h"
#include "cli/options.h"
#include "ssim_tool.h"

int main(int argc, char** argv) {
  mvtm::SsimToolOptions o;
  mvtm::OptionTable table = mvtm::DeclareOptions(o);
  return mvtm::RunTool(
      table,
      "Photo-consistency of two images or two folders of images (pairs matched by "
      "file name): mean SSIM (equal to scikit-image's Gaussian SSIM), zero-mean NCC "
      "and PSNR, as TSV (or JSON) on standard output.",
      argc, argv,
      [&] {
        try {
          return mvtm::RunSsim(o, std::cout);
        } catch (const mvtm::SizeMismatchError& e) {
          std::cerr << "ssim: error: " << e.what() << "\n";
          return mvtm::kExitSizeMismatch;
        }
      },
      "See man ssim for details. Exit status: 0 success, 1 data or I/O error, 2 usage error, "
      "3 images (or image and mask) differ in size.");
}
