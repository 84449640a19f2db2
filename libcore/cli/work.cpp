#include "cli/work.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

void WorkOptions::CheckWork() const {
  if (!frames.empty() && !shard.empty()) throw UsageError("give --frames or --shard, not both");
  Select();
}

Selection WorkOptions::Select() const {
  if (!shard.empty()) return Selection::Shard(shard);
  if (!frames.empty()) return Selection::Frames(frames);
  return Selection();
}

std::string WorkOptions::ProvenanceName(const std::string& tool) const {
  if (shard.empty()) return tool;
  return tool + "-shard-" + std::to_string(Selection::Shard(shard).shard_index);
}

void DeclareWorkOptions(OptionTable& table, WorkOptions& work, const std::string& items,
                        const std::string& order, const std::string& force_help) {
  table.Text("--frames", &work.frames, "Only " + items + " A:B (half-open, " + order + ")")
      .Cosmetic()
      .Excludes("--shard")
      .Check([&work] { work.CheckWork(); });
  table.Text("--shard", &work.shard, "Only " + items + " i with i % N == I (I/N)").Cosmetic();
  table.Flag("--force", &work.force, force_help).Cosmetic();
  DeclareQuietOption(table, work.quiet);
}

void DeclareQuietOption(OptionTable& table, bool& quiet) {
  table.Flag("-q,--quiet", &quiet, "No progress bar or summary").Cosmetic();
}

void CheckRange(double v, double lo, double hi, bool lo_open, const std::string& option) {
  if (std::isfinite(v) && v <= hi && v >= lo && !(lo_open && v == lo)) return;
  char range[64];
  std::snprintf(range, sizeof range, "%s%g, %g]", lo_open ? "(" : "[", lo, hi);
  throw UsageError(option + ": must be in " + range);
}

ImageSize ParseImageSize(const std::string& spec, const std::string& option) {
  const auto x = spec.find('x');
  if (x == std::string::npos || x == 0 || x + 1 == spec.size())
    throw UsageError(option + ": '" + spec + "' is not WxH");
  const int64_t w = ParseIntArg(spec.substr(0, x), option + " width");
  const int64_t h = ParseIntArg(spec.substr(x + 1), option + " height");
  if (w <= 0 || h <= 0 || w > kMaxImageSide || h > kMaxImageSide)
    throw UsageError(option + ": '" + spec + "' must be 1.." + std::to_string(kMaxImageSide) +
                     " on each side");
  return {static_cast<uint64_t>(w), static_cast<uint64_t>(h)};
}

}  // namespace mvtm
