// --frames / --shard: shards partition the items; ranges behave like Python slices.
#include "cli/selection.h"

#include <gtest/gtest.h>

#include <set>

#include "base/error.h"

namespace mvtm {
namespace {

TEST(Selection, ShardsPartition) {
  for (size_t n : {0u, 1u, 7u, 100u}) {
    for (int k : {1, 2, 3, 4, 9}) {
      std::multiset<size_t> all;
      for (int i = 0; i < k; ++i)
        for (size_t x : Selection::Shard(std::to_string(i) + "/" + std::to_string(k)).Apply(n))
          all.insert(x);
      ASSERT_EQ(all.size(), n);
      size_t expect = 0;
      for (size_t x : all) EXPECT_EQ(x, expect++);
    }
  }
}

TEST(Selection, BlocksPartitionInOrder) {
  for (size_t n : {0u, 1u, 7u, 100u}) {
    for (int k : {1, 2, 3, 4, 9}) {
      size_t expect = 0;
      for (int i = 0; i < k; ++i) {
        const std::vector<size_t> block =
            Selection::Shard(std::to_string(i) + "/" + std::to_string(k)).ApplyBlocks(n);
        // Shard i of k holds floor(i·n/k) .. floor((i+1)·n/k) - 1, each after the last.
        EXPECT_EQ(block.size(), (i + 1) * n / k - i * n / k);
        for (size_t x : block) EXPECT_EQ(x, expect++);
      }
      EXPECT_EQ(expect, n);
    }
  }
  EXPECT_EQ(Selection::Frames("2:5").ApplyBlocks(9), Selection::Frames("2:5").Apply(9));
}

TEST(Selection, RangesLikeSlices) {
  EXPECT_EQ(Selection::Frames("2:5").Apply(10), (std::vector<size_t>{2, 3, 4}));
  EXPECT_EQ(Selection::Frames("8:").Apply(10), (std::vector<size_t>{8, 9}));
  EXPECT_EQ(Selection::Frames(":2").Apply(10), (std::vector<size_t>{0, 1}));
  EXPECT_EQ(Selection::Frames("-2:").Apply(10), (std::vector<size_t>{8, 9}));
  EXPECT_EQ(Selection::Frames("3").Apply(10), (std::vector<size_t>{3}));
  EXPECT_EQ(Selection::Frames("5:100").Apply(7), (std::vector<size_t>{5, 6}));
  // Counted from the same end, a start after the end is a typo; from different ends it depends
  // on n and may select nothing.
  EXPECT_THROW(Selection::Frames("5:2"), UsageError);
  EXPECT_THROW(Selection::Frames("-2:-5"), UsageError);
  EXPECT_TRUE(Selection::Frames("5:-8").Apply(10).empty());
  EXPECT_EQ(Selection::Frames("-3:9").Apply(10), (std::vector<size_t>{7, 8}));
}

TEST(Selection, BadSpecsAreUsageErrors) {
  EXPECT_THROW(Selection::Shard("3/3"), UsageError);
  EXPECT_THROW(Selection::Shard("1"), UsageError);
  EXPECT_THROW(Selection::Shard("a/2"), UsageError);
  EXPECT_THROW(Selection::Frames("x:3"), UsageError);
  // Beyond int: refused, never wrapped (0/4294967297 used to be taken as 0/1).
  EXPECT_THROW(Selection::Shard("0/4294967297"), UsageError);
  EXPECT_THROW(Selection::Shard("4294967296/4294967297"), UsageError);
  try {
    Selection::Shard("0/4294967297");
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--shard: '0/4294967297' needs 0 <= I < N <= 2147483647");
  }
  EXPECT_EQ(Selection::Shard("5/2147483647").shard_count, 2147483647);
}

}  // namespace
}  // namespace mvtm
