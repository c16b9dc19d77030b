// SPDX-License-Identifier: BSD-3-Clause
// Internal: the threading layer. Stage math stays in plain functions, written once and
// testable alone; only the loops that call it know about OpenMP (no scheduling inside the
// per-cell math).
#ifndef mtpt_detail_Parallel_h
#define mtpt_detail_Parallel_h

#include "mtpt/Threads.h"
#include "mtpt/Timing.h"

#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
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
  const int nthreads = threads > 0 ? threads : 1;
  std::vector<std::size_t> kept(static_cast<std::size_t>(nthreads), 0);
#pragma omp parallel num_threads(nthreads)
  {
    const auto t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t blocks = static_cast<std::size_t>(omp_get_num_threads());
    for (std::size_t b = t; b < static_cast<std::size_t>(nthreads); b += blocks)
    {
      const std::size_t begin = n * b / nthreads, end = n * (b + 1) / nthreads;
      kept[b] = body(begin, end, items + begin);
    }
  }
  std::size_t total = 0;
  for (int b = 0; b < nthreads; ++b)
  {
    const std::size_t begin = n * b / nthreads;
    if (begin != total && kept[b] > 0)
    {
      std::memmove(items + total, items + begin, kept[b] * sizeof(T));
    }
    total += kept[b];
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
  const std::size_t blocks = static_cast<std::size_t>(threads > 1 ? threads : 1);
  const auto bound = [&](std::size_t b) { return items + n * std::min(b, blocks) / blocks; };
  const auto count = static_cast<std::int64_t>(blocks);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t b = 0; b < count; ++b)
  {
    std::sort(bound(static_cast<std::size_t>(b)), bound(static_cast<std::size_t>(b) + 1));
  }
  for (std::size_t width = 1; width < blocks; width *= 2)
  {
    const auto pairs = static_cast<std::int64_t>((blocks + 2 * width - 1) / (2 * width));
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::int64_t p = 0; p < pairs; ++p)
    {
      const std::size_t first = 2 * width * static_cast<std::size_t>(p);
      std::inplace_merge(bound(first), bound(first + width), bound(first + 2 * width));
    }
  }
}

} // namespace detail
} // namespace mtpt

#endif
