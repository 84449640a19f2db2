// ssim — photo-consistency of image pairs: mean SSIM, zero-mean NCC and PSNR (man/ssim.1).
//
// A and B are two images or two folders; in folder mode every image file of A is paired with
// the file of the same name in B (files only in B are ignored), in file-name order. The metric
// conventions (window, borders, data range, colour, masks) are those of libcore image/ssim.h.
// Output: TSV (header, one row per pair, then mean/std/min rows in folder mode) or JSON, on
// stdout: the verdict, computed on every run. Files: the SSIM maps (--map) only; a map is remade
// unless the record says it was made with these options (those that change maps: all but the
// paths, --json and --force) from unchanged A, B and mask files. The record (run/ledger.h) is
// provenance/ssim.json in the folder the maps are in (the --map folder, or the map file's folder).
#pragma once

#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "image/ssim.h"
#include "run/option_table.h"

namespace mvtm {

// How colour images are compared.
enum class ChannelMode {
  kMean,  // each colour channel on its own, results averaged (scikit-image channel_axis)
  kGrey,  // both images first reduced to grey (mean of the colour channels)
};

// Exit status when A and B (or an image and its mask) differ in size; 0, 1 and 2 are the
// common ones (success, data error, usage error).
constexpr int kExitSizeMismatch = 3;

// --channels choices.
inline const std::vector<std::pair<ChannelMode, std::string>> kChannelModes = {
    {ChannelMode::kMean, "mean"}, {ChannelMode::kGrey, "grey"}};

struct SsimToolOptions {
  std::string a;                              // first image or folder
  std::string b;                              // second image or folder
  std::string mask;                           // mask image or folder ("" = none); nonzero = in
  std::string map;                            // SSIM map output: .exr/.png file, or a folder
  bool json = false;                          // JSON instead of TSV
  ChannelMode channels = ChannelMode::kMean;  // colour handling
  bool fit_exposure =
      false;           // first bring A to B's exposure: gain and offset fitted (inside the mask)
  SsimOptions ssim;    // sigma, k1, k2, data_range (0 = bit depth)
  bool force = false;  // rewrite the maps even when they are up to date

  // Throws UsageError naming the bad value.
  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of the maps all come from it.
OptionTable DeclareOptions(SsimToolOptions& o);

// Compares the pairs and writes the table to `out`. Returns the exit status (0). Throws
// UsageError (bad combination of paths), SizeMismatchError, Error.
int RunSsim(const SsimToolOptions& options, std::ostream& out);

}  // namespace mvtm
