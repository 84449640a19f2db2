// bakedepth — one linear float32 depth map per projector image, from the workspace mesh, so the
// PTM occlusion test needs no extra render pass (thesis appendix D, "pre-baking depth maps").
#pragma once

#include <string>

#include "cli/work.h"
#include "render/context.h"
#include "run/option_table.h"

namespace mvtm {

// Work items: the workspace's images sorted by name (--frames/--shard select among them).
struct BakeDepthOptions : WorkOptions {
  std::string workspace;
  double scale = 1.0;  // depth map size = image size × scale (0 < scale ≤ 4)
  GlBackend gl = GlBackend::kAuto;

  void Check() const;
};

// The option table (run/option_table.h) bound to `o`.
OptionTable DeclareOptions(BakeDepthOptions& o);

struct BakeDepthReport {
  size_t selected = 0, written = 0, skipped = 0;
  double render_ms = 0, write_ms = 0;
  std::string gl;
  std::string why;  // why maps were remade ("4 redone: --scale changed"), "" when none was
};

BakeDepthReport RunBakeDepth(const BakeDepthOptions& options);

}  // namespace mvtm
