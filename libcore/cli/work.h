// mvtm — the options shared by every tool that processes a list of items (images, poses,
// frames), and the parsing and validation of option values that several tools take.
//
// No CLI11 here: tool libraries and tests use these types; cli/options.h puts them into a
// command line. Every function throws UsageError naming the option and the allowed range.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cli/selection.h"
#include "run/option_table.h"

namespace mvtm {

// --frames A:B | --shard I/N, --force, --quiet. A tool's Options struct derives from it.
struct WorkOptions {
  std::string frames;  // --frames A:B: half-open range of items in the tool's documented order
  std::string shard;   // --shard I/N: items i with i % N == I
  bool force = false;  // redo outputs that are up to date
  bool quiet = false;  // no progress bar, no summary

  // Throws UsageError when both --frames and --shard are given or either is malformed.
  void CheckWork() const;
  // The items to process (all when neither option is given).
  Selection Select() const;
  // The provenance record of this run: "TOOL", or "TOOL-shard-I" for shard I (each shard of a
  // job array records its own run, so shards never overwrite each other's record).
  std::string ProvenanceName(const std::string& tool) const;
};

// Declares --frames, --shard (mutually exclusive), --force and -q/--quiet in a tool's table; none
// of them changes an output (--force redoes it as it would be made anyway).
//   items:      what is selected, plural ("poses", "images", "label frames")
//   order:      the documented order of the items ("in pose order", "by name order")
//   force_help: what --force redoes for this tool
void DeclareWorkOptions(OptionTable& table, WorkOptions& work, const std::string& items,
                        const std::string& order, const std::string& force_help);
// -q/--quiet alone, for tools without a work list.
void DeclareQuietOption(OptionTable& table, bool& quiet);

// The largest image side a tool accepts (the OpenGL texture limit of Mesa's llvmpipe).
inline constexpr int64_t kMaxImageSide = 16384;

struct ImageSize {
  uint64_t width = 0, height = 0;
};

// Throws UsageError("OPTION: must be in [lo, hi]" or "(lo, hi]" when lo_open) unless v is a
// finite number in that range.
void CheckRange(double v, double lo, double hi, bool lo_open, const std::string& option);

// Parses "WxH" (1..kMaxImageSide each). `option` names the option in messages ("--size").
ImageSize ParseImageSize(const std::string& spec, const std::string& option = "--size");

}  // namespace mvtm
