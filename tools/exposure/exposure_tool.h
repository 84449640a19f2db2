// exposure — a gain and an offset per workspace image, fitted to the sparse points the images
// share (radiometry/exposure.h), written to WS/exposure.tsv for ptmrender.
#pragma once

#include <string>

#include "radiometry/exposure.h"

namespace mvtm {

struct ExposureToolOptions {
  std::string workspace;
  ExposureOptions fit;  // --offsets, --iterations, --outlier-mads, --min-points
  bool force = false;   // refit when exposure.tsv is newer than the sparse model
  bool quiet = false;

  void Check() const;
};

struct ExposureToolReport {
  bool up_to_date = false;
  size_t images = 0, fitted = 0, observations = 0;
  double gain_min = 1, gain_max = 1, offset_min = 0, offset_max = 0;
};

ExposureToolReport RunExposure(const ExposureToolOptions& options);

}  // namespace mvtm
