// SPDX-License-Identifier: BSD-3-Clause
// Every visibility-order implementation returns the unique sorted permutation (depth
// descending, ties by ascending cell id) for every thread count.
#include "mtpt/DepthKeys.h"
#include "mtpt/VisibilityOrder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

namespace
{

using mtpt::SortKey;

TEST(DepthEncoding, AscendingCodesAreDescendingDepths)
{
  const float depths[] = { -1e30f, -5.0f, -1e-30f, 0.0f, 1e-38f, 1e-30f, 1.0f, 1.5f, 3e38f,
    std::numeric_limits<float>::infinity() };
  for (std::size_t i = 1; i < std::size(depths); ++i)
  {
    EXPECT_GT(mtpt::EncodeDepth(depths[i - 1]), mtpt::EncodeDepth(depths[i])) << depths[i];
  }
  EXPECT_EQ(mtpt::EncodeDepth(-0.0f), mtpt::EncodeDepth(0.0f));
  EXPECT_EQ(mtpt::EncodeDepth(std::nanf("")), mtpt::EncodeDepth(INFINITY));
  EXPECT_EQ(mtpt::EncodeDepth(-INFINITY), mtpt::EncodeDepth(INFINITY));
  // Keys: farther first; equal depths by ascending cell id.
  EXPECT_LT(mtpt::MakeSortKey(2.0f, 9), mtpt::MakeSortKey(1.0f, 0));
  EXPECT_LT(mtpt::MakeSortKey(1.0f, 3), mtpt::MakeSortKey(1.0f, 4));
  EXPECT_EQ(mtpt::CellOfKey(mtpt::MakeSortKey(1.0f, 123456u)), 123456u);
}

/// Keys with heavy ties (few distinct depths), negative depths, and either ascending ids
/// (as ComputeDepthKeys writes them) or shuffled ids.
std::vector<SortKey> MakeKeys(std::size_t n, int distinctDepths, bool shuffleIds, unsigned seed)
{
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> level(0, distinctDepths - 1);
  std::vector<SortKey> keys(n);
  for (std::size_t c = 0; c < n; ++c)
  {
    const float depth = static_cast<float>(level(random) - distinctDepths / 3) * 0.37f;
    keys[c] = mtpt::MakeSortKey(depth, static_cast<std::uint32_t>(c));
  }
  if (shuffleIds)
  {
    std::shuffle(keys.begin(), keys.end(), random);
  }
  return keys;
}

struct OrderCase
{
  mtpt::OrderMethod method;
  std::size_t maxSubArray;
};

class OrderTest : public ::testing::TestWithParam<OrderCase>
{
};

TEST_P(OrderTest, SortedPermutationForEveryThreadCount)
{
  const OrderCase param = GetParam();
  for (std::size_t n :
    { std::size_t(0), std::size_t(1), std::size_t(1000), std::size_t(5000), std::size_t(250000) })
  {
    for (int distinct : { 1, 7, 1 << 20 })
    {
      for (bool shuffled : { false, true })
      {
        const std::vector<SortKey> input = MakeKeys(n, distinct, shuffled, 17u + n);
        std::vector<SortKey> expected = input;
        std::sort(expected.begin(), expected.end());
        for (int threads : { 1, 2, 3, 8 })
        {
          SCOPED_TRACE(::testing::Message() << "n=" << n << " distinct=" << distinct
                                            << " shuffled=" << shuffled << " threads=" << threads);
          auto order = mtpt::MakeVisibilityOrder(param.method, param.maxSubArray);
          ASSERT_EQ(order->Method(), param.method);
          std::vector<SortKey> keys = input;
          order->Sort(keys.data(), keys.size(), threads);
          ASSERT_EQ(keys, expected);
          // The same object again (scratch reuse) gives the same result.
          keys = input;
          order->Sort(keys.data(), keys.size(), threads);
          ASSERT_EQ(keys, expected);
          // With a lent scratch, too short and holding other keys: the same result, and
          // the sorter holds no scratch of its own (at most the radix order's counts).
          auto lending = mtpt::MakeVisibilityOrder(param.method, param.maxSubArray);
          mtpt::LargeVector<SortKey> scratch(n / 2, ~SortKey{ 0 });
          keys = input;
          lending->Sort(keys.data(), keys.size(), threads, scratch);
          ASSERT_EQ(keys, expected);
          EXPECT_LE(lending->MemoryBytes(), 8 * 256 * sizeof(std::size_t));
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, OrderTest,
  ::testing::Values(OrderCase{ mtpt::OrderMethod::PartitionSort, mtpt::DefaultMaxSubArraySize },
    OrderCase{ mtpt::OrderMethod::PartitionSort, 64 }, // many sub-arrays
    OrderCase{ mtpt::OrderMethod::PartitionSort, 1 },  // clamped to the minimum
    OrderCase{ mtpt::OrderMethod::RadixSort, 0 }),
  [](const auto& info)
  {
    return std::string(mtpt::ToString(info.param.method)) + "_max" +
      std::to_string(info.param.maxSubArray);
  });

TEST(VisibilityOrder, Names)
{
  EXPECT_STREQ(mtpt::ToString(mtpt::OrderMethod::PartitionSort), "partition");
  EXPECT_STREQ(mtpt::ToString(mtpt::OrderMethod::RadixSort), "radix");
}

} // namespace
