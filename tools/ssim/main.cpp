// ssim — command line: the option table; the work is RunSsim() (ssim_tool.h).
#include <iostream>
#include <string>

#include "cli/app.h"
#include "ssim_tool.h"

int main(int argc, char** argv) {
  mvtm::SsimToolOptions o;
  CLI::App app;
  mvtm::ConfigureApp(app, "ssim",
                     "Photo-consistency of two images or two folders of images (pairs matched by "
                     "file name): mean SSIM (equal to scikit-image's Gaussian SSIM), zero-mean NCC "
                     "and PSNR, as TSV (or JSON) on standard output.");
  app.footer(
      "See man ssim for details. Exit status: 0 success, 1 data or I/O error, 2 usage error, "
      "3 images (or image and mask) differ in size.");
  app.add_option("A", o.a, "First image, or folder of images")->required()->type_name("PATH");
  app.add_option("B", o.b, "Second image, or folder (pairs matched by file name)")
      ->required()
      ->type_name("PATH");
  app.add_option("--mask", o.mask,
                 "Evaluate only where this mask (image, or folder for folders) is nonzero")
      ->type_name("M");
  app.add_option("--map", o.map,
                 "Write the SSIM map: .exr (float) or .png (8-bit); for folders a folder of "
                 "NAME.exr")
      ->type_name("OUT");
  app.add_flag("--json", o.json, "Write JSON instead of TSV");
  app.add_flag("--fit-exposure", o.fit_exposure,
               "First bring A to the exposure of B: gain and offset fitted by least squares "
               "(inside the mask)");
  app.add_option("--sigma", o.ssim.sigma, "Gaussian window standard deviation in pixels")
      ->capture_default_str()
      ->type_name("S");
  app.add_option("--k1", o.ssim.k1, "Luminance constant, C1 = (K1*R)^2")
      ->capture_default_str()
      ->type_name("K");
  app.add_option("--k2", o.ssim.k2, "Contrast constant, C2 = (K2*R)^2")
      ->capture_default_str()
      ->type_name("K");
  app.add_option("--data-range", o.ssim.data_range,
                 "Data range R (default: from the bit depth: 255, 65535, 1 for float)")
      ->type_name("R");
  std::string channels = "mean";
  app.add_option("--channels", channels,
                 "Colour: mean = per channel, averaged (scikit-image); grey = compare the grey "
                 "images")
      ->check(CLI::IsMember(mvtm::ChannelModeNames()).description(""))
      ->capture_default_str()
      ->type_name("grey|mean");
  return mvtm::RunMain(app, "ssim", argc, argv, [&] {
    o.channels = channels == mvtm::ChannelModeNames()[1] ? mvtm::ChannelMode::kGrey
                                                         : mvtm::ChannelMode::kMean;
    try {
      return mvtm::RunSsim(o, std::cout);
    } catch (const mvtm::SizeMismatchError& e) {
      std::cerr << "ssim: error: " << e.what() << "\n";
      return mvtm::kExitSizeMismatch;
    }
  });
}
