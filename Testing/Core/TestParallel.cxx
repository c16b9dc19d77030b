// SPDX-License-Identifier: BSD-3-Clause
// The core's parallel primitives (Source/Core/Parallel/detail/Parallel.h): each visits what
// it promises exactly once, and the results the core relies on are the same for any thread
// count.
#include "detail/Parallel.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <numeric>
#include <new>
#include <random>
#include <utility>
#include <vector>

namespace
{

namespace detail = mtpt::detail;

constexpr int ThreadCounts[] = { 1, 2, 3, 7 };

TEST(Parallel, BlocksCutARangeInOrderWithoutGapsOrOverlaps)
{
  for (const std::size_t n : { std::size_t{ 0 }, std::size_t{ 5 }, std::size_t{ 1000 } })
  {
    for (const std::size_t blocks : { std::size_t{ 1 }, std::size_t{ 3 }, std::size_t{ 8 } })
    {
      std::size_t next = 0;
      for (std::size_t b = 0; b < blocks; ++b)
      {
        const detail::IndexRange r = detail::BlockOf(n, b, blocks);
        EXPECT_EQ(r.begin, next);
        EXPECT_LE(r.begin, r.end);
        EXPECT_LE(r.end - r.begin, n / blocks + 1);
        next = r.end;
      }
      EXPECT_EQ(next, n);
    }
  }
}

TEST(Parallel, ParallelForVisitsEveryIndexOnce)
{
  for (const int threads : ThreadCounts)
  {
    std::vector<int> visits(1003, 0);
    detail::ParallelFor(
      3, 1003, threads, [&](std::int64_t i) { ++visits[static_cast<std::size_t>(i)]; });
    for (std::size_t i = 0; i < visits.size(); ++i)
    {
      ASSERT_EQ(visits[i], i < 3 ? 0 : 1) << "index " << i << ", " << threads << " threads";
    }
    detail::ParallelFor(5, 5, threads, [&](std::int64_t) { ADD_FAILURE() << "empty range"; });
  }
}

TEST(Parallel, ParallelForDynamicVisitsEveryIndexOnceWithTheCallingThreadsIndex)
{
  for (const int threads : ThreadCounts)
  {
    for (const int chunk : { 1, 64 })
    {
      std::vector<int> visits(777, 0);
      std::atomic<int> badThread{ 0 };
      detail::ParallelForDynamic(
        777, threads,
        [&](std::int64_t i, int thread)
        {
          ++visits[static_cast<std::size_t>(i)];
          badThread += thread < 0 || thread >= threads ? 1 : 0;
        },
        chunk);
      EXPECT_EQ(badThread.load(), 0);
      EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; }));
    }
  }
}

TEST(Parallel, EveryBlockOnceWhateverTheTeam)
{
  for (const int threads : ThreadCounts)
  {
    for (const int blocks : { 1, 4, 9 })
    {
      std::vector<int> visits(static_cast<std::size_t>(blocks), 0);
      detail::ForEachBlock(blocks, threads, [&](int b) { ++visits[static_cast<std::size_t>(b)]; });
      EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; }));
    }
    std::vector<int> covered(100, 0);
    detail::ForEachThreadBlock(100, threads,
      [&](detail::IndexRange r)
      {
        for (std::size_t i = r.begin; i < r.end; ++i)
        {
          ++covered[i];
        }
      });
    EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int v) { return v == 1; }));
  }
}

TEST(Parallel, ReductionsOfCountsAndFlagsDoNotDependOnTheTeam)
{
  for (const int threads : ThreadCounts)
  {
    const auto sum = detail::ParallelReduce(
      0, 10001, threads, std::uint64_t{ 0 }, [](std::uint64_t a, std::uint64_t b) { return a + b; },
      [](std::int64_t i) { return static_cast<std::uint64_t>(i); });
    EXPECT_EQ(sum, 10000u * 10001u / 2);
    const bool all = detail::ParallelReduce(
      0, 500, threads, true, [](bool a, bool b) { return a && b; },
      [](std::int64_t i) { return i != 321; });
    EXPECT_FALSE(all);
    const int any = detail::ParallelReduce(
      0, 500, threads, 0, [](int a, int b) { return a | b; },
      [](std::int64_t i) { return i == 499 ? 4 : 0; });
    EXPECT_EQ(any, 4);
    // An empty range gives the identity.
    EXPECT_EQ(
      detail::ParallelReduce(
        7, 7, threads, 0, [](int a, int b) { return a + b; }, [](std::int64_t) { return 1; }),
      0);
  }
}

TEST(Parallel, ReductionsHearTheFlagOfEveryThreadWhenTheThreadsFinishTogether)
{
  // One item per thread, each held until the whole team has arrived: the threads fold their
  // partials at the same moment, and the one "false" must survive wherever it is.
  for (const int threads : { 2, 3 })
  {
    for (int round = 0; round < 12; ++round)
    {
      const int odd = round % threads;
      std::atomic<int> arrived{ 0 };
      const bool all = detail::ParallelReduce(
        0, threads, threads, true, [](bool a, bool b) { return a && b; },
        [&](std::int64_t i)
        {
          arrived.fetch_add(1);
          const auto start = std::chrono::steady_clock::now();
          while (arrived.load() < threads &&
            std::chrono::steady_clock::now() - start < std::chrono::milliseconds(100))
          {
          }
          return i != odd;
        });
      ASSERT_FALSE(all) << threads << " threads, the false at " << odd;
    }
  }
}

TEST(Parallel, ThreadCountsOfZeroOrLessMeanTheDefault)
{
  // A default other than 1 (OpenMP's count, mtpt/Threads.h), restored at the end.
  const int openMP = omp_get_max_threads();
  omp_set_num_threads(3);
  const int standard = mtpt::DefaultThreadCount();
  EXPECT_GE(standard, 1);
  EXPECT_EQ(detail::ResolveThreads(0), standard);
  EXPECT_EQ(detail::ResolveThreads(-2), standard);
  EXPECT_EQ(detail::ResolveThreads(3), 3);
  for (const int threads : { 0, -1 })
  {
    std::atomic<int> blocks{ 0 };
    detail::ForEachThreadBlock(1000, threads, [&](detail::IndexRange) { ++blocks; });
    EXPECT_EQ(blocks.load(), standard);
    std::atomic<int> badThread{ 0 };
    detail::ParallelForDynamic(
      300, threads, [&](std::int64_t, int thread) { badThread += thread >= standard ? 1 : 0; });
    EXPECT_EQ(badThread.load(), 0);
    detail::PerThread<int> scratch;
    scratch.Prepare(threads, [] { return 0; });
    EXPECT_EQ(scratch.size(), static_cast<std::size_t>(standard));
    std::vector<int> items(100, 1);
    std::atomic<int> compacted{ 0 };
    EXPECT_EQ(detail::CompactInOrder(items.size(), threads, items.data(),
                [&](std::size_t begin, std::size_t end, int*)
                {
                  ++compacted;
                  return end - begin;
                }),
      100u);
    EXPECT_EQ(compacted.load(), standard);
    std::vector<int> keys = { 5, 3, 9, 1, 7, 2 };
    detail::ParallelSort(keys.data(), keys.size(), threads);
    EXPECT_EQ(keys, (std::vector<int>{ 1, 2, 3, 5, 7, 9 }));
    EXPECT_EQ(
      detail::ParallelReduce(
        0, 1000, threads, 0, [](int a, int b) { return a + b; }, [](std::int64_t) { return 1; }),
      1000);
  }
  omp_set_num_threads(openMP);
}

TEST(Parallel, PerThreadScratchIsMadeBeforeAndKept)
{
  detail::PerThread<std::vector<int>> scratch;
  int made = 0;
  scratch.Prepare(3, [&] { return std::vector<int>(static_cast<std::size_t>(++made), 0); });
  EXPECT_EQ(scratch.size(), 3u);
  EXPECT_EQ(made, 3);
  scratch[1].push_back(9);
  scratch.Prepare(2, [&] { return std::vector<int>(++made, 0); }); // enough already
  scratch.Prepare(4, [&] { return std::vector<int>(++made, 0); });
  EXPECT_EQ(scratch.size(), 4u);
  EXPECT_EQ(made, 4);
  EXPECT_EQ(scratch[1].back(), 9); // kept
  // Each thread of a loop reaches its own.
  detail::ParallelForDynamic(
    1000, 4, [&](std::int64_t, int thread) { scratch[thread].push_back(1); });
  std::size_t total = 0;
  for (const std::vector<int>& mine : scratch)
  {
    total += static_cast<std::size_t>(std::count(mine.begin(), mine.end(), 1));
  }
  EXPECT_EQ(total, 1000u);
}

TEST(Parallel, ThePrefixByBucketPlacesEachBlockAfterTheEarlierOnes)
{
  // Two blocks, three buckets: counts[block * 3 + bucket].
  std::vector<std::uint32_t> counts = { 2, 0, 1, 3, 4, 0 };
  std::vector<std::pair<std::size_t, std::size_t>> buckets;
  const std::size_t total = detail::ExclusivePrefixByBucket(counts.data(), 2, 3,
    [&](std::size_t, std::size_t first, std::size_t size) { buckets.emplace_back(first, size); });
  EXPECT_EQ(total, 10u);
  EXPECT_EQ(counts, (std::vector<std::uint32_t>{ 0, 5, 9, 2, 5, 10 }));
  EXPECT_EQ(
    buckets, (std::vector<std::pair<std::size_t, std::size_t>>{ { 0, 5 }, { 5, 4 }, { 9, 1 } }));
  // One bucket: each block's count becomes its offset (an exclusive prefix sum).
  std::vector<std::size_t> perBlock = { 4, 0, 3, 5 };
  std::size_t calls = 0;
  EXPECT_EQ(detail::ExclusivePrefixByBucket(perBlock.data(), 4, 1,
              [&](std::size_t, std::size_t first, std::size_t size)
              {
                ++calls;
                EXPECT_EQ(first, 0u);
                EXPECT_EQ(size, 12u);
              }),
    12u);
  EXPECT_EQ(calls, 1u);
  EXPECT_EQ(perBlock, (std::vector<std::size_t>{ 0, 4, 4, 7 }));
}

TEST(Parallel, CountPlaceScatterIsAStableCountingSortForAnyTeam)
{
  std::mt19937 random(7);
  std::vector<std::uint32_t> items(5000);
  for (std::uint32_t& item : items)
  {
    item = static_cast<std::uint32_t>(random() % 50) << 16 |
      static_cast<std::uint32_t>(&item - items.data());
  }
  std::vector<std::uint32_t> expected = items;
  std::stable_sort(expected.begin(), expected.end(),
    [](std::uint32_t a, std::uint32_t b) { return (a >> 16) < (b >> 16); });
  for (const int threads : ThreadCounts)
  {
    for (const int blocks : { 1, 3, 8 })
    {
      std::vector<std::size_t> counts(static_cast<std::size_t>(blocks) * 50, 0);
      std::vector<std::uint32_t> sorted;
      detail::CountPlaceScatter(
        items.size(), blocks, threads,
        [&](int b, detail::IndexRange r)
        {
          for (std::size_t i = r.begin; i < r.end; ++i)
          {
            ++counts[static_cast<std::size_t>(b) * 50 + (items[i] >> 16)];
          }
        },
        [&]
        {
          sorted.resize(detail::ExclusivePrefixByBucket(
            counts.data(), static_cast<std::size_t>(blocks), 50, [](auto, auto, auto) {}));
          return true;
        },
        [&](int b, detail::IndexRange r)
        {
          for (std::size_t i = r.begin; i < r.end; ++i)
          {
            sorted[counts[static_cast<std::size_t>(b) * 50 + (items[i] >> 16)]++] = items[i];
          }
        });
      EXPECT_EQ(sorted, expected) << threads << " threads, " << blocks << " blocks";
    }
  }
  // A place step that declines skips the scatter.
  bool scattered = false;
  detail::CountPlaceScatter(
    10, 2, 2, [](int, detail::IndexRange) {}, [] { return false; },
    [&](int, detail::IndexRange) { scattered = true; });
  EXPECT_FALSE(scattered);
}

TEST(Parallel, CompactionKeepsTheInputOrderAndSortingTheOneOrder)
{
  std::vector<int> input(1234);
  std::iota(input.begin(), input.end(), 0);
  std::vector<int> odd;
  std::copy_if(
    input.begin(), input.end(), std::back_inserter(odd), [](int v) { return v % 3 == 1; });
  std::mt19937 random(3);
  std::vector<std::uint64_t> keys(4321);
  for (std::uint64_t& k : keys)
  {
    k = static_cast<std::uint64_t>(random()) << 32 | static_cast<std::uint64_t>(&k - keys.data());
  }
  std::vector<std::uint64_t> sortedKeys = keys;
  std::sort(sortedKeys.begin(), sortedKeys.end());
  for (const int threads : ThreadCounts)
  {
    std::vector<int> items = input;
    const std::size_t kept = detail::CompactInOrder(items.size(), threads, items.data(),
      [&](std::size_t begin, std::size_t end, int* out)
      {
        std::size_t n = 0;
        for (std::size_t i = begin; i < end; ++i)
        {
          if (input[i] % 3 == 1)
          {
            out[n++] = input[i];
          }
        }
        return n;
      });
    items.resize(kept);
    EXPECT_EQ(items, odd) << threads << " threads";
    std::vector<std::uint64_t> k = keys;
    detail::ParallelSort(k.data(), k.size(), threads);
    EXPECT_EQ(k, sortedKeys) << threads << " threads";
  }
}

TEST(Parallel, FetchAddGivesEveryCallerItsOwnValue)
{
  for (const int threads : ThreadCounts)
  {
    std::uint32_t counter = 0;
    std::vector<std::uint32_t> got(2000);
    detail::ParallelFor(0, 2000, threads,
      [&](std::int64_t i) { got[static_cast<std::size_t>(i)] = detail::FetchAdd(counter, 1u); });
    EXPECT_EQ(counter, 2000u);
    std::sort(got.begin(), got.end());
    for (std::uint32_t i = 0; i < 2000; ++i)
    {
      ASSERT_EQ(got[i], i);
    }
  }
}

TEST(Parallel, AnExceptionOnAWorkerThreadReachesTheCaller)
{
  // A body that fails on a thread other than the caller's (std::bad_alloc, as an allocation
  // where memory runs out): the exception must come out of the primitive on the calling
  // thread, not end the process inside the region. Teams of 4 have workers on any host, and
  // the static schedules give each of them its own items.
  const auto onWorker = []
  {
    if (omp_get_thread_num() != 0 || omp_get_num_threads() == 1) // a team of 1: its only thread
    {
      throw std::bad_alloc();
    }
  };
  const std::int64_t n = 1000;
  EXPECT_THROW(detail::ParallelFor(0, n, 4, [&](std::int64_t) { onWorker(); }), std::bad_alloc);
  // The dynamic schedule hands items to whichever thread is free (the calling thread may
  // take them all): every item fails there.
  EXPECT_THROW(detail::ParallelForDynamic(n, 4, [&](std::int64_t, int) { throw std::bad_alloc(); }),
    std::bad_alloc);
  EXPECT_THROW(detail::ForEachBlock(8, 4, [&](int) { onWorker(); }), std::bad_alloc);
  EXPECT_THROW(
    detail::ForEachThreadBlock(n, 4, [&](detail::IndexRange) { onWorker(); }), std::bad_alloc);
  EXPECT_THROW(detail::ParallelReduce(
                 std::int64_t{ 0 }, n, 4, 0, [](int a, int b) { return a + b; },
                 [&](std::int64_t)
                 {
                   onWorker();
                   return 1;
                 }),
    std::bad_alloc);
  std::vector<int> items(n, 1);
  EXPECT_THROW(detail::CompactInOrder(items.size(), 4, items.data(),
                 [&](std::size_t, std::size_t, int*) -> std::size_t
                 {
                   onWorker();
                   return 0;
                 }),
    std::bad_alloc);
  EXPECT_THROW(detail::CountPlaceScatter(
                 items.size(), 4, 4, [&](int, detail::IndexRange) { onWorker(); },
                 [] { return true; }, [](int, detail::IndexRange) {}),
    std::bad_alloc);
  // The first exception of several is the one thrown; the primitives work afterwards.
  EXPECT_THROW(
    detail::ParallelFor(0, n, 4, [](std::int64_t) { throw std::bad_alloc(); }), std::bad_alloc);
  std::atomic<std::int64_t> visited{ 0 };
  detail::ParallelFor(0, n, 4, [&](std::int64_t) { ++visited; });
  EXPECT_EQ(visited.load(), n);
}

} // namespace
