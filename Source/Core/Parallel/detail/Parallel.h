// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Parallel.h
 * @brief Internal: the core's parallel primitives, the one place that names OpenMP.
 *
 * Every loop of the core that runs on several threads goes through a primitive of this
 * header, named for its pattern, so that a stage reads as "for each cell, ...; then count,
 * place, scatter" and its math stays in plain functions (no scheduling inside the per-cell
 * code). OpenMP is the engine: the pragmas are here and nowhere else.
 *
 * Conventions:
 * - A thread count <= 0 means the default (mtpt/Threads.h, ResolveThreads).
 * - [0, n) cut into `blocks` blocks: block b is [n b / blocks, n (b + 1) / blocks)
 *   (BlockOf), contiguous and in order.
 * - Determinism: each primitive says what of its result may depend on the team. The core's
 *   results are the same for any thread count; a primitive whose work per item is
 *   independent (ParallelFor) gives that by itself, the others by how they are used.
 * - Exceptions: an exception that leaves an OpenMP region ends the process, so no primitive
 *   lets one out. A body that throws (std::bad_alloc) has its first exception kept and
 *   thrown again on the calling thread once the region has ended (RegionFailure); what the
 *   other items computed is then unspecified. The primitives themselves allocate nothing
 *   inside their regions, and neither should bodies: scratch a body needs is made
 *   beforehand (PerThread), and what a step sizes from counts is sized between regions
 *   (CountPlaceScatter's place).
 * Each primitive has unit tests in Testing/Core/TestParallel.cxx.
 */
#ifndef mtpt_detail_Parallel_h
#define mtpt_detail_Parallel_h

#include "mtpt/Threads.h"
#include "mtpt/Timing.h"

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <vector>

namespace mtpt
{
namespace detail
{

/// The OpenMP thread count for a requested count: <= 0 means the default (mtpt/Threads.h).
inline int ResolveThreads(int requested)
{
  return ResolveThreadCount(requested);
}

/// Work per thread below which waking another thread does not pay (ThreadsForWork): about
/// a tenth of a millisecond of each stage's work.
constexpr std::size_t CellsPerThread = 8192;
constexpr std::size_t FansPerThread = 4096;
constexpr std::size_t PixelsPerThread = 16384;

using mtpt::SecondsSince;

/// A half-open range of indices.
struct IndexRange
{
  std::size_t begin = 0, end = 0;
};

/// Block `block` of [0, n) cut into `blocks` contiguous blocks.
inline IndexRange BlockOf(std::size_t n, std::size_t block, std::size_t blocks)
{
  return { n * block / blocks, n * (block + 1) / blocks };
}

/**
 * The first exception thrown inside a parallel region, kept to be thrown again on the
 * calling thread after it: Run(body) inside the region, Rethrow() after. Thread-safe.
 */
class RegionFailure
{
public:
  template <typename Body>
  void Run(Body&& body) noexcept
  {
    try
    {
      body();
    }
    catch (...)
    {
      this->Keep(std::current_exception());
    }
  }
  void Rethrow() const
  {
    if (this->First)
    {
      std::rethrow_exception(this->First);
    }
  }

private:
  void Keep(std::exception_ptr failure) noexcept
  {
#pragma omp critical(mtpt_detail_RegionFailure)
    if (!this->First)
    {
      this->First = std::move(failure);
    }
  }
  std::exception_ptr First;
};

/**
 * body(i) for every i in [begin, end), in contiguous chunks, one per thread of a team of
 * `threads` (OpenMP's static schedule). Each i runs once; bodies of different i must not
 * write the same memory, and then the result does not depend on the team.
 */
template <typename Body>
void ParallelFor(std::int64_t begin, std::int64_t end, int threads, Body&& body)
{
  RegionFailure failure;
#pragma omp parallel for num_threads(ResolveThreads(threads)) schedule(static)
  for (std::int64_t i = begin; i < end; ++i)
  {
    failure.Run([&] { body(i); });
  }
  failure.Rethrow();
}

/**
 * body(i, thread) for every i in [0, n), handed out `chunk` at a time to whichever thread
 * of a team of `threads` is free (OpenMP's dynamic schedule): for items of uneven work.
 * `thread` (0 to the team's size - 1) names the calling thread, so that it can use its own
 * scratch (PerThread). Which thread runs an item depends on the timing: its result must not.
 */
template <typename Body>
void ParallelForDynamic(std::int64_t n, int threads, Body&& body, int chunk = 1)
{
  RegionFailure failure;
#pragma omp parallel num_threads(ResolveThreads(threads))
  {
    const int thread = omp_get_thread_num();
#pragma omp for schedule(dynamic, chunk)
    for (std::int64_t i = 0; i < n; ++i)
    {
      failure.Run([&] { body(i, thread); });
    }
  }
  failure.Rethrow();
}

/// `value` += `add` as one atomic step, from any thread of a parallel body; returns the
/// value before. Which thread gets which result depends on the timing.
template <typename T>
T FetchAdd(T& value, T add)
{
  T before;
#pragma omp atomic capture
  {
    before = value;
    value += add;
  }
  return before;
}

/**
 * body(block) for each block in [0, blocks), the blocks dealt in turn to a team of at most
 * `threads` threads (thread t takes blocks t, t + team, ...). The blocks' work is the body's;
 * a result that depends only on the blocks, not on which thread ran them, does not depend
 * on the team.
 */
template <typename Body>
void ForEachBlock(int blocks, int threads, Body&& body)
{
  const int team = std::max(1, std::min(blocks, ResolveThreads(threads)));
  RegionFailure failure;
#pragma omp parallel num_threads(team)
  {
    for (int b = omp_get_thread_num(); b < blocks; b += omp_get_num_threads())
    {
      failure.Run([&] { body(b); });
    }
  }
  failure.Rethrow();
}

/**
 * body(range) for each of the `threads` contiguous blocks of [0, n) (BlockOf), one per
 * thread: for work that streams through a range in order (non-temporal stores finished at
 * the range's end, one pass over a block's memory).
 */
template <typename Body>
void ForEachThreadBlock(std::size_t n, int threads, Body&& body)
{
  const int blocks = ResolveThreads(threads);
  ForEachBlock(blocks, blocks,
    [&](int b)
    { body(BlockOf(n, static_cast<std::size_t>(b), static_cast<std::size_t>(blocks))); });
}

/**
 * `combine` folded over body(i) for i in [begin, end): each thread of a team of `threads`
 * folds its static chunk (as ParallelFor's) from `identity` in a local, then folds that
 * into the result under a lock as it finishes. `combine` must be associative and
 * commutative and exact (counts, "any", "all"; not floating-point sums): the result then
 * does not depend on the team nor on the order the threads finish. Allocates nothing, and
 * each thread writes only its own local until the fold, so the partials of a T packed
 * several to a word (bool) never share memory.
 */
template <typename T, typename Combine, typename Body>
T ParallelReduce(
  std::int64_t begin, std::int64_t end, int threads, T identity, Combine&& combine, Body&& body)
{
  T result = identity;
  RegionFailure failure;
#pragma omp parallel num_threads(ResolveThreads(threads))
  {
    T mine = identity;
#pragma omp for schedule(static) nowait
    for (std::int64_t i = begin; i < end; ++i)
    {
      failure.Run([&] { mine = combine(mine, body(i)); });
    }
#pragma omp critical(mtpt_detail_ParallelReduce)
    result = combine(result, mine);
  }
  failure.Rethrow();
  return result;
}

/**
 * One T per thread of a team, made outside any parallel region and kept from call to call:
 * the scratch a parallel body needs (ParallelForDynamic gives the thread's index), so that
 * the region itself allocates nothing. Thread safety: Prepare on one thread, then each
 * thread touches only its own item.
 */
template <typename T>
class PerThread
{
public:
  /// At least `threads` items (<= 0: the default count); those missing are made by make().
  template <typename Make>
  void Prepare(int threads, Make&& make)
  {
    const auto count = static_cast<std::size_t>(ResolveThreads(threads));
    this->Items.reserve(count);
    while (this->Items.size() < count)
    {
      this->Items.push_back(make());
    }
  }
  T& operator[](int thread) { return this->Items[static_cast<std::size_t>(thread)]; }
  typename std::vector<T>::iterator begin() { return this->Items.begin(); }
  typename std::vector<T>::iterator end() { return this->Items.end(); }
  std::size_t size() const { return this->Items.size(); }
  void Release() { std::vector<T>().swap(this->Items); }

private:
  std::vector<T> Items;
};

/**
 * The exclusive prefix sum of counts laid out block-major (counts[block * buckets +
 * bucket]) taken in (bucket, block) order, in place: each count becomes its block's first
 * place in its bucket, so that blocks scattering in order keep a counting sort stable.
 * perBucket(bucket, first, count) is told each bucket's first place and size. Returns the
 * total. With one bucket it is the exclusive prefix sum of per-block counts: each block's
 * count becomes its offset. Serial: run it between the parallel count and scatter
 * (CountPlaceScatter).
 */
template <typename T, typename PerBucket>
std::size_t ExclusivePrefixByBucket(
  T* counts, std::size_t blocks, std::size_t buckets, PerBucket&& perBucket)
{
  std::size_t running = 0;
  for (std::size_t bucket = 0; bucket < buckets; ++bucket)
  {
    const std::size_t first = running;
    for (std::size_t b = 0; b < blocks; ++b)
    {
      T& c = counts[b * buckets + bucket];
      const std::size_t here = c;
      c = static_cast<T>(running);
      running += here;
    }
    perBucket(bucket, first, running - first);
  }
  return running;
}

/**
 * The three steps of a stable counting sort (or of any bucketing) of [0, n) cut into
 * `blocks` contiguous blocks (BlockOf): count(block, range) for every block in parallel, each
 * into its own counts; place() once on the calling thread, between the two parallel steps
 * (typically ExclusivePrefixByBucket, and sizing the output: it may allocate), returning
 * whether to scatter; scatter(block, range) for every block in parallel. With blocks
 * scattering in order from their places, the result depends only on `blocks`, not on the
 * team.
 */
template <typename Count, typename Place, typename Scatter>
void CountPlaceScatter(
  std::size_t n, int blocks, int threads, Count&& count, Place&& place, Scatter&& scatter)
{
  const auto cut = static_cast<std::size_t>(blocks);
  ForEachBlock(
    blocks, threads, [&](int b) { count(b, BlockOf(n, static_cast<std::size_t>(b), cut)); });
  if (place())
  {
    ForEachBlock(
      blocks, threads, [&](int b) { scatter(b, BlockOf(n, static_cast<std::size_t>(b), cut)); });
  }
}

/**
 * Stream compaction in input order: [0, n) is cut into one contiguous block per thread;
 * body(begin, end, out) writes the items it keeps from [begin, end) to out[0..) and returns
 * their number, with `out` = items + begin, so blocks never overlap. The blocks are then
 * closed up in order. The result is the kept items in input order, for any thread count.
 * Returns the number kept.
 */
template <typename T, typename Body>
std::size_t CompactInOrder(std::size_t n, int threads, T* items, Body&& body)
{
  const int blocks = ResolveThreads(threads);
  std::vector<std::size_t> kept(static_cast<std::size_t>(blocks), 0);
  ForEachBlock(blocks, blocks,
    [&](int b)
    {
      const IndexRange r =
        BlockOf(n, static_cast<std::size_t>(b), static_cast<std::size_t>(blocks));
      kept[static_cast<std::size_t>(b)] = body(r.begin, r.end, items + r.begin);
    });
  std::size_t total = 0;
  for (int b = 0; b < blocks; ++b)
  {
    const std::size_t begin =
      BlockOf(n, static_cast<std::size_t>(b), static_cast<std::size_t>(blocks)).begin;
    if (begin != total && kept[static_cast<std::size_t>(b)] > 0)
    {
      std::memmove(items + total, items + begin, kept[static_cast<std::size_t>(b)] * sizeof(T));
    }
    total += kept[static_cast<std::size_t>(b)];
  }
  return total;
}

/**
 * Sorts [items, items + n) ascending with operator<: `threads` blocks sorted at once
 * (std::sort), then merged pairwise (std::inplace_merge), the pairs of a round at once.
 * For keys that are all distinct the result is the one sorted order, for any thread count.
 */
template <typename T>
void ParallelSort(T* items, std::size_t n, int threads)
{
  const auto blocks = static_cast<std::size_t>(ResolveThreads(threads));
  const auto bound = [&](std::size_t b) { return items + n * std::min(b, blocks) / blocks; };
  ParallelFor(0, static_cast<std::int64_t>(blocks), threads,
    [&](std::int64_t b)
    { std::sort(bound(static_cast<std::size_t>(b)), bound(static_cast<std::size_t>(b) + 1)); });
  for (std::size_t width = 1; width < blocks; width *= 2)
  {
    const auto pairs = static_cast<std::int64_t>((blocks + 2 * width - 1) / (2 * width));
    ParallelFor(0, pairs, threads,
      [&](std::int64_t p)
      {
        const std::size_t first = 2 * width * static_cast<std::size_t>(p);
        std::inplace_merge(bound(first), bound(first + width), bound(first + 2 * width));
      });
  }
}

} // namespace detail
} // namespace mtpt

#endif
