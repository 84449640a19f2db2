// exposure — a gain and an offset per workspace image, fitted to the sparse points the images
// share (radiometry/exposure.h), written to WS/exposure.tsv for ptmrender.
#pragma once

#include <string>

#include "radiometry/exposure.h"
#include "run/option_table.h"

namespace mvtm {

struct ExposureToolOptions {
  std::string workspace;
  ExposureOptions fit;  // --offsets, --iterations, --outlier-mads, --min-points
  bool force = false;   // refit even when exposure.tsv is up to date
  bool quiet = false;

  void Check() const;
};

// The option table (run/option_table.h) bound to `o`: --help, checks, provenance and the
// staleness key of exposure.tsv all come from it.
OptionTable DeclareOptions(ExposureToolOptions& o);

struct ExposureToolReport {
  bool up_to_date = false;
  size_t images = 0, fitted = 0, observations = 0;
  double gain_min = 1, gain_max = 1, offset_min = 0, offset_max = 0;
  std::string why;  // why an existing exposure.tsv was refitted ("1 redone: --offsets changed")
};

ExposureToolReport RunExposure(const ExposureToolOptions& options);

}  // namespace mvtm
