// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/VisibilityOrder.h"
#include "mtpt/Faults.h"

#include "detail/Parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace mtpt
{

const char* ToString(OrderMethod method)
{
  switch (method)
  {
    case OrderMethod::PartitionSort:
      return "partition";
    case OrderMethod::RadixSort:
      return "radix";
  }
  return "unknown";
}

namespace
{

/// Below this size a plain std::sort beats any parallel set-up; the result is the same
/// unique ascending order.
constexpr std::size_t SmallInput = 4096;

/**
 * Fan et al. 2021, Algorithm 1 ("partial sort" + "global sort"). The partition phase is
 * sequential as published; it is the Amdahl bottleneck this class exists to measure.
 */
class PartitionSortOrder final : public VisibilityOrder
{
public:
  explicit PartitionSortOrder(std::size_t maxSubArraySize)
    : MaxSubArraySize(std::max<std::size_t>(16, maxSubArraySize))
  {
  }

  OrderMethod Method() const override { return OrderMethod::PartitionSort; }

  using VisibilityOrder::Sort;
  void Sort(SortKey* keys, std::size_t count, int threads, LargeVector<SortKey>&) override
  {
    if (count < SmallInput)
    {
      std::sort(keys, keys + count);
      return;
    }
    // Partial sort: split until every sub-array is shorter than MAX. The pivots are random
    // (fixed seed, so runs are repeatable) to keep the expected depth logarithmic on the
    // nearly sorted key arrays that consecutive frames produce.
    this->SubArrays.clear();
    std::vector<std::pair<std::size_t, std::size_t>> pending{ { 0, count } };
    std::mt19937_64 random(0x6d747074u);
    while (!pending.empty())
    {
      const auto [lo, hi] = pending.back();
      pending.pop_back();
      if (hi - lo < this->MaxSubArraySize)
      {
        this->SubArrays.emplace_back(lo, hi);
        continue;
      }
      const std::size_t split = HoarePartition(keys, lo, hi, lo + random() % (hi - lo));
      pending.emplace_back(lo, split);
      pending.emplace_back(split, hi);
    }
    // Global sort: the sub-arrays cover disjoint key ranges, so sorting each in place
    // completes the order. Dynamic scheduling absorbs their unequal sizes.
    const auto n = static_cast<std::int64_t>(this->SubArrays.size());
    const int nthreads = detail::ResolveThreads(threads);
    detail::ParallelForDynamic(n, nthreads,
      [&](std::int64_t s, int)
      { std::sort(keys + this->SubArrays[s].first, keys + this->SubArrays[s].second); });
  }

private:
  /// Hoare's partition of [lo, hi) around the value at `pivotIndex`, scanning from both
  /// ends. Returns split with lo < split < hi, [lo, split) <= pivot <= [split, hi).
  /// All keys are distinct (they hold their cell id), so both parts are never empty.
  static std::size_t HoarePartition(
    SortKey* a, std::size_t lo, std::size_t hi, std::size_t pivotIndex)
  {
    std::swap(a[lo], a[pivotIndex]);
    const SortKey pivot = a[lo];
    std::size_t i = lo - 1; // wraps for lo == 0; the first ++i brings it back
    std::size_t j = hi;
    for (;;)
    {
      do
      {
        ++i;
      } while (a[i] < pivot);
      do
      {
        --j;
      } while (a[j] > pivot);
      if (i >= j)
      {
        return j + 1;
      }
      std::swap(a[i], a[j]);
    }
  }

  std::size_t MaxSubArraySize;
  std::vector<std::pair<std::size_t, std::size_t>> SubArrays;
};

/**
 * Parallel LSD radix sort, 8-bit digits (256 buckets): 4 passes over the depth bits 32-63
 * when the cell ids arrive ascending, else 8 passes over all 64 bits. Each pass: every
 * thread counts the digits of its contiguous block, an exclusive prefix over (digit, thread)
 * gives every thread its own output ranges, and every thread scatters its block stably. A
 * pass whose digit is the same for all keys is skipped (typically the top byte, the sign and
 * high exponent bits of the depth).
 */
class RadixSortOrder final : public VisibilityOrder
{
public:
  OrderMethod Method() const override { return OrderMethod::RadixSort; }

  using VisibilityOrder::Sort;
  void Sort(SortKey* keys, std::size_t count, int threads, LargeVector<SortKey>& scratch) override
  {
    if (count < SmallInput)
    {
      std::sort(keys, keys + count);
      return;
    }
    const int nthreads = detail::ResolveThreads(threads);
    if (scratch.size() < count)
    {
      scratch.resize(count);
    }
    // ComputeDepthKeys writes keys in ascending cell-id order; a stable sort of the depth
    // bits then completes the order. Any other input also needs its id bits sorted first.
    const bool idsAscending = IdsAscending(keys, count, nthreads);
    SortKey* source = keys;
    SortKey* target = scratch.data();
    const int firstShift = idsAscending ? 32 : 0;
    for (int shift = firstShift; shift < 64; shift += 8)
    {
      if (this->Pass(source, target, count, shift, nthreads))
      {
        std::swap(source, target);
      }
    }
    if (source != keys)
    {
      const auto n = static_cast<std::int64_t>(count);
      detail::ParallelFor(0, n, nthreads, [&](std::int64_t i) { keys[i] = source[i]; });
    }
  }

private:
  static bool IdsAscending(const SortKey* keys, std::size_t count, int nthreads)
  {
    const auto n = static_cast<std::int64_t>(count);
    return detail::ParallelReduce(
      1, n, nthreads, true, [](bool a, bool b) { return a && b; },
      [&](std::int64_t i) { return CellOfKey(keys[i - 1]) < CellOfKey(keys[i]); });
  }

  /// One stable counting pass on the digit at `shift`. Returns false if it was skipped
  /// (all keys share the digit), in which case `target` is untouched.
  bool Pass(const SortKey* source, SortKey* target, std::size_t count, int shift, int nthreads)
  {
    constexpr std::size_t Buckets = 256;
    this->Counts.assign(static_cast<std::size_t>(nthreads) * Buckets, 0);
    bool skip = false;
    detail::CountPlaceScatter(
      count, nthreads, nthreads,
      [&](int b, detail::IndexRange r)
      {
        std::size_t* mine = this->Counts.data() + static_cast<std::size_t>(b) * Buckets;
        for (std::size_t i = r.begin; i < r.end; ++i)
        {
          ++mine[(source[i] >> shift) & 0xff];
        }
      },
      [&]
      {
        // Places in (digit, block) order: digit-major keeps the pass stable. A digit that
        // every key shares skips the pass.
        detail::ExclusivePrefixByBucket(this->Counts.data(), static_cast<std::size_t>(nthreads),
          Buckets,
          [&](std::size_t, std::size_t, std::size_t size) { skip = skip || size == count; });
        return !skip;
      },
      [&](int b, detail::IndexRange r)
      {
        std::size_t* mine = this->Counts.data() + static_cast<std::size_t>(b) * Buckets;
        for (std::size_t i = r.begin; i < r.end; ++i)
        {
          const SortKey k = source[i];
          target[mine[(k >> shift) & 0xff]++] = k;
        }
      });
    return !skip;
  }

  std::size_t MemoryBytes() const override
  {
    return VisibilityOrder::MemoryBytes() + this->Counts.capacity() * sizeof(std::size_t);
  }

  std::vector<std::size_t> Counts;
};

} // namespace

std::unique_ptr<VisibilityOrder> MakeVisibilityOrder(
  OrderMethod method, std::size_t maxSubArraySize)
{
  switch (method)
  {
    case OrderMethod::PartitionSort:
      return std::make_unique<PartitionSortOrder>(maxSubArraySize);
    case OrderMethod::RadixSort:
      return std::make_unique<RadixSortOrder>();
  }
  return nullptr;
}

} // namespace mtpt

namespace mtpt
{

bool SortNearlySorted(SortKey* keys, std::size_t count, std::size_t moveBudget, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const int blocks = count < SmallInput ? 1 : nthreads;
  const std::size_t blockBudget = moveBudget / static_cast<std::size_t>(blocks) + 1;
  // Insertion sort inside each block: the work is the number of inversions in the block.
  const bool gaveUp = detail::ParallelReduce(
    0, blocks, blocks, false, [](bool a, bool b) { return a || b; },
    [&](std::int64_t b)
    {
      const std::size_t begin = count * b / blocks, end = count * (b + 1) / blocks;
      std::size_t moves = 0;
      for (std::size_t i = begin + 1; i < end && moves <= blockBudget; ++i)
      {
        const SortKey key = keys[i];
        std::size_t j = i;
        while (j > begin && keys[j - 1] > key)
        {
          keys[j] = keys[j - 1];
          --j;
        }
        moves += i - j;
        keys[j] = key;
      }
      return moves > blockBudget;
    });
  if (gaveUp)
  {
    return false;
  }
  // Merge the sorted blocks pairwise: log2(blocks) linear passes.
  for (int width = 1; width < blocks; width *= 2)
  {
    const std::int64_t pairs = (blocks - width + 2 * width - 1) / (2 * width);
    detail::ParallelFor(0, pairs, nthreads,
      [&](std::int64_t p)
      {
        const int b = static_cast<int>(p) * 2 * width;
        const std::size_t begin = count * b / blocks;
        const std::size_t middle = count * (b + width) / blocks;
        const std::size_t end = count * std::min(b + 2 * width, blocks) / blocks;
        if (keys[middle - 1] > keys[middle]) // already in order across the seam otherwise
        {
          std::inplace_merge(keys + begin, keys + middle, keys + end);
        }
      });
  }
  return true;
}

void InvertOrder(const SortKey* order, std::size_t count, std::size_t cellCount,
  std::uint32_t* rank, int threads, const std::uint32_t* candidates, std::size_t candidateCount,
  std::size_t meshCells)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto cells = static_cast<std::int64_t>(cellCount);
  const auto n = static_cast<std::int64_t>(count);
  const auto listed = static_cast<std::int64_t>(candidateCount);
  const auto first = static_cast<std::int64_t>(std::min(meshCells, cellCount));
  if (candidates) // the candidates and the ids after the mesh's cells
  {
    detail::ParallelFor(
      0, listed, nthreads, [&](std::int64_t i) { rank[candidates[i]] = NotInOrder; });
    detail::ParallelFor(first, cells, nthreads, [&](std::int64_t c) { rank[c] = NotInOrder; });
  }
  else if (n < cells) // only a partial order leaves ranks to mark
  {
    detail::ParallelFor(0, cells, nthreads, [&](std::int64_t c) { rank[c] = NotInOrder; });
  }
  detail::ParallelFor(0, n, nthreads,
    [&](std::int64_t k) { rank[CellOfKey(order[k])] = static_cast<std::uint32_t>(k); });
}

OrderStage::OrderStage()
  : Sorter(MakeVisibilityOrder(OrderMethod::RadixSort))
{
}

bool OrderStage::Update(const Key& key, const Cells& cells, bool fromPrevious, DepthKeyStage& keys,
  const NearPlaneStage& nearPlane, int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  if (key.method != this->Sorter->Method() || key.maxSubArraySize != this->SorterMaxSubArraySize)
  {
    this->Sorter = MakeVisibilityOrder(key.method, key.maxSubArraySize);
    this->SorterMaxSubArraySize = key.maxSubArraySize;
  }
  // The keys the near plane keeps, in ascending cell id order (the radix sort's fast case),
  // taken from the key stage, whose buffer is this update's scratch from here on.
  const std::size_t previousCount = this->Sorted.size();
  LargeVector<SortKey>& scratch = keys.Consume();
  AllocationPoint(AllocationSite::Order); // the keys given to the order already
  if (!nearPlane.CutsAny())
  {
    this->Sorted.swap(scratch);
  }
  else
  {
    this->Sorted.clear();
    for (std::size_t k = 0; k < scratch.size(); ++k)
    {
      if (nearPlane.Keeps(k))
      {
        this->Sorted.push_back(scratch[k]);
      }
    }
  }
  if (!key.sorted)
  {
    // Any order serves: the cells in id order, then the near plane's pieces.
    const LargeVector<SortKey>& pieces = nearPlane.PieceKeys();
    this->Sorted.insert(this->Sorted.end(), pieces.begin(), pieces.end());
    this->SortedFromPrevious = false;
    this->Held = Cells{}; // not an order to sort the next one from
    this->Record.Store(key);
    return true;
  }
  // The same cells as the previous order after a small rotation: nearly sorted already.
  const Cells& held = this->Held;
  const double dot = cells.direction[0] * held.direction[0] +
    cells.direction[1] * held.direction[1] + cells.direction[2] * held.direction[2];
  const double angle = std::acos(std::min(1.0, std::max(-1.0, dot)));
  const bool sameCells = fromPrevious && this->Record.Valid() && held.whole && cells.whole &&
    held.mesh == cells.mesh && held.points != cells.points && held.visible == cells.visible &&
    held.perspective == cells.perspective && previousCount == this->Sorted.size() &&
    angle < NearlySortedMaxAngle && key.mutation == OrderMutation::None;
  this->SortedFromPrevious = sameCells && this->SortFromPrevious(scratch, threads);
  if (!this->SortedFromPrevious)
  {
    this->Sorter->Sort(this->Sorted.data(), this->Sorted.size(), threads, scratch);
  }
  const LargeVector<SortKey>& pieces = nearPlane.PieceKeys();
  if (!pieces.empty())
  {
    scratch.resize(this->Sorted.size() + pieces.size());
    std::merge(
      this->Sorted.begin(), this->Sorted.end(), pieces.begin(), pieces.end(), scratch.begin());
    this->Sorted.swap(scratch);
  }
  this->Mutate(key.mutation);
  this->Held = cells;
  this->Record.Store(key);
  return true;
}

bool OrderStage::SortFromPrevious(LargeVector<SortKey>& scratch, int threads)
{
  const std::size_t count = this->Sorted.size();
  scratch.resize(count);
  const auto m = static_cast<std::int64_t>(count);
  detail::ParallelFor(0, m, detail::ResolveThreads(threads),
    [&](std::int64_t i)
    {
      const SortKey key = this->Sorted[i];
      scratch[this->Ranks[CellOfKey(key)]] = key;
    });
  // Budget: about the cost of a full sort; beyond it the keys moved too far.
  if (!SortNearlySorted(scratch.data(), count, 4 * count, threads))
  {
    return false; // the keys in Sorted are as they were
  }
  this->Sorted.swap(scratch);
  return true;
}

void OrderStage::Mutate(OrderMutation mutation)
{
  if (mutation == OrderMutation::Reversed)
  {
    std::reverse(this->Sorted.begin(), this->Sorted.end());
  }
  else if (mutation == OrderMutation::Storage)
  {
    std::sort(this->Sorted.begin(), this->Sorted.end(),
      [](SortKey a, SortKey b) { return CellOfKey(a) < CellOfKey(b); });
  }
}

void OrderStage::Invert(std::size_t ranked, int threads, const std::uint32_t* candidates,
  std::size_t candidateCount, std::size_t meshCells)
{
  if (this->Ranks.size() < ranked)
  {
    this->Ranks.resize(ranked);
  }
  InvertOrder(this->Sorted.data(), this->Sorted.size(), ranked, this->Ranks.data(), threads,
    candidates, candidateCount, meshCells);
}

void OrderStage::Group(std::size_t ranksPerGroup, std::size_t meshCells,
  const std::uint32_t* candidates, std::size_t candidateCount, LargeVector<SortKey>& storage,
  int threads)
{
  if (this->Record.Valid() && this->GroupedVersion == this->Version())
  {
    return;
  }
  const std::size_t ranked = this->Sorted.size();
  this->GroupRanks =
    std::max<std::size_t>({ std::size_t(1), ranksPerGroup, (ranked + MaxGroups - 1) / MaxGroups });
  const std::size_t groups = (ranked + this->GroupRanks - 1) / this->GroupRanks;
  // Ranks and the group size fit 32 bits (MaxFrameTetrahedra): the cheaper division.
  const auto size = static_cast<std::uint32_t>(this->GroupRanks);
  const std::size_t n = candidates ? candidateCount : meshCells;
  const int nthreads = detail::ResolveThreads(threads);
  this->GroupCounts.assign(static_cast<std::size_t>(nthreads) * groups, 0);
  this->GroupStarts.assign(groups + 1, 0);
  const std::uint32_t* rank = this->Ranks.data();
  // A stable counting sort of the ranked cells by group: each block counts its cells, an
  // exclusive prefix in (group, block) order places them, and each block scatters.
  detail::CountPlaceScatter(
    n, nthreads, nthreads,
    [&](int b, detail::IndexRange r)
    {
      std::size_t* mine = this->GroupCounts.data() + static_cast<std::size_t>(b) * groups;
      for (std::size_t i = r.begin; i < r.end; ++i)
      {
        const std::uint32_t rk = rank[candidates ? candidates[i] : i];
        if (rk != NotInOrder)
        {
          ++mine[rk / size];
        }
      }
    },
    [&]
    {
      const std::size_t total = detail::ExclusivePrefixByBucket(this->GroupCounts.data(),
        static_cast<std::size_t>(nthreads), groups,
        [&](std::size_t g, std::size_t first, std::size_t) { this->GroupStarts[g] = first; });
      this->GroupStarts[groups] = total;
      storage.resize(total);
      return true;
    },
    [&](int b, detail::IndexRange r)
    {
      std::size_t* mine = this->GroupCounts.data() + static_cast<std::size_t>(b) * groups;
      for (std::size_t i = r.begin; i < r.end; ++i)
      {
        const std::size_t c = candidates ? candidates[i] : i;
        const std::uint32_t rk = rank[c];
        if (rk != NotInOrder)
        {
          storage[mine[rk / size]++] = static_cast<SortKey>(c) << 32 | rk;
        }
      }
    });
  this->GroupedVersion = this->Version();
}

const SortKey* OrderStage::CellsOfRanks(std::size_t first, std::size_t count,
  const LargeVector<SortKey>& storage, std::size_t& cells) const
{
  const std::size_t groups = this->GroupStarts.empty() ? 0 : this->GroupStarts.size() - 1;
  const std::size_t size = this->GroupRanks;
  const std::size_t g0 = std::min(groups, first / size);
  const std::size_t g1 = std::min(groups, (first + count + size - 1) / size);
  const std::size_t begin = groups ? this->GroupStarts[g0] : 0;
  cells = groups ? this->GroupStarts[g1] - begin : 0;
  return storage.data() + begin;
}

void OrderStage::Release()
{
  std::vector<std::size_t>().swap(this->GroupStarts);
  std::vector<std::size_t>().swap(this->GroupCounts);
  this->GroupedVersion = 0;
  LargeVector<SortKey>().swap(this->Sorted);
  LargeVector<std::uint32_t>().swap(this->Ranks);
  this->Sorter = MakeVisibilityOrder(this->Sorter->Method(), this->SorterMaxSubArraySize);
  this->Record.Forget();
}

std::size_t OrderStage::MemoryBytes() const
{
  return this->Sorted.capacity() * sizeof(SortKey) +
    (this->GroupStarts.capacity() + this->GroupCounts.capacity()) * sizeof(std::size_t) +
    this->Ranks.capacity() * sizeof(std::uint32_t) + this->Sorter->MemoryBytes();
}

} // namespace mtpt
