// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file VisibilityOrder.h
 * @brief Stage 3 of a frame: sort the depth keys into back-to-front visibility order.
 *
 * Every implementation sorts SortKey values (DepthKeys.h) ascending. Because a key holds
 * its cell id, all keys are distinct and the sorted sequence is unique: every
 * implementation, every thread count and every run return the same permutation.
 */
#ifndef mtpt_VisibilityOrder_h
#define mtpt_VisibilityOrder_h

#include "mtpt/DepthKeys.h"

#include <cstddef>
#include <memory>
#include <vector>

namespace mtpt
{

enum class OrderMethod
{
  /// The paper's Algorithm 1 as published (Fan et al. 2021): a sequential random-pivot
  /// Hoare partition splits the keys into sub-arrays of disjoint key ranges until each is
  /// shorter than MaxSubArraySize; then the sub-arrays are sorted in parallel.
  PartitionSort,
  /// Parallel least-significant-digit radix sort with 8-bit digits: 4 passes over the 32
  /// depth bits when the keys arrive in ascending cell-id order (as the key stage writes
  /// them), else 8 passes over all 64 bits; a pass whose digit is the same for every key is
  /// skipped. No sequential phase; stable, so the ascending cell ids of the input order
  /// survive as the tie rule.
  RadixSort,
};

/// A readable name ("partition", "radix") for tables and settings.
const char* ToString(OrderMethod method);

/**
 * Sorts keys into visibility order. Objects keep scratch memory between calls so a
 * frame allocates nothing once the mesh size is stable.
 *
 * Thread safety: one object must not be used by two threads at once; distinct objects
 * are independent. Determinism: the output is the unique ascending order of the keys.
 */
class VisibilityOrder
{
public:
  virtual ~VisibilityOrder() = default;
  virtual OrderMethod Method() const = 0;
  /// Sorts keys[0, count) ascending on `threads` OpenMP threads (<= 0: all available).
  virtual void Sort(SortKey* keys, std::size_t count, int threads) = 0;
  /// Bytes of scratch memory the object holds.
  virtual std::size_t MemoryBytes() const { return 0; }
};

/// Default sub-array threshold MAX of the partition sort.
constexpr std::size_t DefaultMaxSubArraySize = 1u << 15;

/// Creates an implementation. `maxSubArraySize` is MAX for PartitionSort (clamped to at
/// least 16) and ignored by the others.
std::unique_ptr<VisibilityOrder> MakeVisibilityOrder(
  OrderMethod method, std::size_t maxSubArraySize = DefaultMaxSubArraySize);

/**
 * Sorts keys that are already nearly in order, as this frame's keys are in the previous
 * frame's order after a small change of view: an insertion sort inside one block per
 * thread (work: the number of inversions) and pairwise merges of the blocks. Gives up once
 * about `moveBudget` element moves are spent and returns false; the keys are then a
 * permutation of the input in no particular order and must be sorted another way.
 * On success the result is the unique ascending order, as from every VisibilityOrder.
 * Thread safety: reentrant.
 */
bool SortNearlySorted(SortKey* keys, std::size_t count, std::size_t moveBudget, int threads);

} // namespace mtpt

#endif
