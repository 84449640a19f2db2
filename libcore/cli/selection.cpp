#include "cli/selection.h"

#include <algorithm>
#include <cstdint>
#include <limits>

#include "base/error.h"
#include "base/text.h"

namespace mvtm {

Selection Selection::Frames(const std::string& spec) {
  Selection s;
  auto colon = spec.find(':');
  if (colon == std::string::npos) {
    s.begin = ParseIntArg(spec, "--frames");
    if (s.begin == std::numeric_limits<int64_t>::max())
      throw UsageError("--frames: '" + spec + "' is out of range");
    s.end = s.begin + 1;
    s.has_end = true;
    if (s.begin == -1) s.has_end = false;
    return s;
  }
  std::string a = spec.substr(0, colon), b = spec.substr(colon + 1);
  if (!a.empty()) s.begin = ParseIntArg(a, "--frames start");
  if (!b.empty()) {
    s.end = ParseIntArg(b, "--frames end");
    s.has_end = true;
  }
  // Counted from the same end, a start after the end selects nothing: surely a typo.
  if (s.has_end && (s.begin < 0) == (s.end < 0) && s.begin > s.end)
    throw UsageError("--frames: '" + spec + "' starts after it ends");
  return s;
}

Selection Selection::Shard(const std::string& spec) {
  Selection s;
  auto slash = spec.find('/');
  if (slash == std::string::npos) throw UsageError("--shard: '" + spec + "' is not I/N");
  const int64_t index = ParseIntArg(spec.substr(0, slash), "--shard index");
  const int64_t count = ParseIntArg(spec.substr(slash + 1), "--shard count");
  // Checked before narrowing: 0/4294967297 must not become 0/1.
  if (count < 1 || count > std::numeric_limits<int>::max() || index < 0 || index >= count)
    throw UsageError("--shard: '" + spec +
                     "' needs 0 <= I < N <= " + std::to_string(std::numeric_limits<int>::max()));
  s.shard_index = static_cast<int>(index);
  s.shard_count = static_cast<int>(count);
  return s;
}

std::vector<size_t> Selection::Apply(size_t n) const {
  long ln = static_cast<long>(n);
  auto clampi = [ln](long v) { return std::clamp(v < 0 ? v + ln : v, 0L, ln); };
  long b = clampi(begin), e = has_end ? clampi(end) : ln;
  std::vector<size_t> out;
  for (long i = b; i < e; ++i)
    if (i % shard_count == shard_index) out.push_back(static_cast<size_t>(i));
  return out;
}

std::vector<size_t> Selection::ApplyBlocks(size_t n) const {
  if (shard_count == 1) return Apply(n);
  const size_t count = static_cast<size_t>(shard_count), index = static_cast<size_t>(shard_index);
  std::vector<size_t> out;
  for (size_t i = index * n / count; i < (index + 1) * n / count; ++i) out.push_back(i);
  return out;
}

}  // namespace mvtm
