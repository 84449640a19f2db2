// sfmjoin — structure-from-motion models of overlapping stretches of one drive (each mapped on
// its own, e.g. `colmap mapper --image_list_path` per stretch: a cost per stretch that does not
// grow with the road) joined into one model in the first model's frame. Each model after the
// first is placed by the similarity its images shared with the models before it give
// (geometry/align.h AlignPoses: centres and camera axes, robust to a few wrong poses); each image
// is kept from the model in which it lies farthest from the stretch's ends (in name order), each
// 3-D point with its observations in the images its model keeps (dropped under two). Cameras that
// differ between models (each stretch refines its own intrinsics) stay separate. The joined model
// is then made upright, metric or placed by GPS once, by georef: one alignment for the road.
#pragma once

#include <string>
#include <vector>

#include "run/option_table.h"

namespace mvtm {

struct SfmjoinOptions {
  std::vector<std::string> paths;  // MODEL... OUTDIR
  size_t min_shared = 3;           // images a model must share with the ones before it
  double max_misfit = 0.05;        // shared centres' RMS misfit / their extent
  bool rigid = false;              // no scale: the models are metric already
  bool binary = false;
  bool force = false;
  bool quiet = false;

  void Check() const;
};

OptionTable DeclareOptions(SfmjoinOptions& o);

struct SfmjoinModelReport {
  std::string model;
  size_t images = 0, shared = 0, inliers = 0, kept_images = 0, kept_points = 0;
  double scale = 1, rotation_rms_deg = 0, centre_rms = 0, misfit = 0;
};

struct SfmjoinReport {
  bool up_to_date = false;
  std::string why;
  std::vector<SfmjoinModelReport> models;
  size_t images = 0, points = 0, cameras = 0;
};

// Writes OUTDIR's model and join.tsv unless they are up to date (run/ledger.h). Throws Error when
// a model shares too few images with the ones before it or misfits them.
SfmjoinReport RunSfmjoin(const SfmjoinOptions& options);

}  // namespace mvtm
