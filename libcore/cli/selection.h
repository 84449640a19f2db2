// mvtm — choosing a subset of work items: --frames A:B and --shard I/N.
//
// Items are indexed 0..n-1 in a fixed, documented order (each tool states its order). A range
// "A:B" is half-open like Python slices (A or B may be empty; negatives count from the end).
// A shard "I/N" (0 <= I < N) takes items i with i % N == I, so N shards partition the items and
// the union of their outputs is byte-identical to one run. Where items are worth keeping
// together (a road's frames, fragment by fragment), ApplyBlocks gives shard I the I-th of N
// contiguous blocks instead: N shards still partition the items.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace mvtm {

struct Selection {
  long begin = 0;        // range start (may be negative: from the end)
  long end = 0;          // range end, exclusive
  bool has_end = false;  // false: to the end
  int shard_index = 0;
  int shard_count = 1;

  // Parses "A:B" / "A:" / ":B" / "A". Throws UsageError.
  static Selection Frames(const std::string& spec);
  // Parses "I/N". Throws UsageError.
  static Selection Shard(const std::string& spec);

  // The selected indices of n items, ascending.
  std::vector<size_t> Apply(size_t n) const;
  // As Apply, but a shard I/N takes items [floor(I·n/N), floor((I+1)·n/N)).
  std::vector<size_t> ApplyBlocks(size_t n) const;
};

}  // namespace mvtm
