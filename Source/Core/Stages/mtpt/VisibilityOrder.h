// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file VisibilityOrder.h
 * @brief Stage 4 of a frame: sort the depth keys into back-to-front visibility order.
 *
 * Every implementation sorts SortKey values (DepthKeys.h) ascending. Because a key holds
 * its cell id, all keys are distinct and the sorted sequence is unique: every
 * implementation, every thread count and every run return the same permutation.
 */
#ifndef mtpt_VisibilityOrder_h
#define mtpt_VisibilityOrder_h

#include "mtpt/DepthKeys.h"
#include "mtpt/LargeBuffer.h"
#include "mtpt/NearPlane.h"
#include "mtpt/Stage.h"

#include <array>
#include <cstddef>
#include <cstdint>
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
  void Sort(SortKey* keys, std::size_t count, int threads)
  {
    this->Sort(keys, count, threads, this->OwnScratch);
  }
  /**
   * The same with `scratch` as the sort's working memory, grown to `count` keys where the
   * method needs it (the radix sort) and left holding no particular values: a caller that
   * has a buffer of keys of its own for other work lends it instead of holding two.
   */
  virtual void Sort(
    SortKey* keys, std::size_t count, int threads, LargeVector<SortKey>& scratch) = 0;
  /// Bytes of scratch memory the object holds.
  virtual std::size_t MemoryBytes() const { return this->OwnScratch.capacity() * sizeof(SortKey); }

private:
  LargeVector<SortKey> OwnScratch; ///< the scratch of Sort without one lent
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

/**
 * The inverse of a visibility order: rank[c] = k where order[k] holds cell c, and
 * NotInOrder for the cells of [0, cellCount) that the order leaves out. With `candidates`
 * (the ascending list of `candidateCount` mesh cells the order was made from, and every id
 * from `meshCells` on), only those ids are written: the ranks of other cells are left as
 * they were, for readers that visit the candidates only (DecomposeInput::cellList).
 * Thread safety: reentrant; `threads` OpenMP threads. Determinism: a pure function.
 */
void InvertOrder(const SortKey* order, std::size_t count, std::size_t cellCount,
  std::uint32_t* rank, int threads, const std::uint32_t* candidates = nullptr,
  std::size_t candidateCount = 0, std::size_t meshCells = 0);

enum class OrderMutation
{
  None,     ///< the visibility order (default)
  Reversed, ///< front to back instead of back to front
  Storage,  ///< the cells in storage order: not sorted at all
};

/**
 * Stage 4 as a stage of FramePipeline (Stage.h): the depth keys the near plane keeps, sorted
 * back to front, with the pieces of cut cells merged in, and the order's inverse (rank per
 * cell id) that the decomposition visits the cells by. Kept until the keys, the pieces, the
 * method or the testing mutation change.
 *
 * After a small rotation (below NearlySortedMaxAngle) with the same cells in play (the same
 * data and visible cells; nothing culled by frustum or pixel coverage and nothing cut by the
 * near plane, in this frame and the previous one), the new keys are placed in the previous
 * order and SortNearlySorted finishes; it gives up past a move budget and the full sort runs.
 */
/// What the order depends on: OrderStage's key.
struct OrderKey
{
  std::uint64_t keys = 0;      ///< DepthKeyStage::Version()
  std::uint64_t nearPlane = 0; ///< NearPlaneStage::Version()
  OrderMethod method = OrderMethod::RadixSort;
  std::size_t maxSubArraySize = DefaultMaxSubArraySize;
  OrderMutation mutation = OrderMutation::None;
  /// False: the blend mode reduces fragments in any order (BlendMode), so the keys are kept
  /// in cell order and nothing is sorted.
  bool sorted = true;
  bool operator==(const OrderKey& o) const
  {
    return keys == o.keys && nearPlane == o.nearPlane && method == o.method &&
      maxSubArraySize == o.maxSubArraySize && mutation == o.mutation && sorted == o.sorted;
  }
};

/**
 * Deliberately wrong visibility orders, for testing that tests can see the order (a test
 * suite that passes with a reversed or unsorted order does not check it). Never for use.
 */
class OrderStage : public StageOf<OrderKey>
{
public:
  /**
   * Which cells an order holds, for sorting the next one from it: every visible cell of the
   * same data (`whole`), seen the same way, from a view direction (unit, model space).
   */
  struct Cells
  {
    MeshKey mesh;
    std::uint64_t points = 0;  ///< TransformStage::Version(): a new one is a moved view
    std::uint64_t visible = 0; ///< CellSelectionStage::Version()
    bool perspective = false;
    bool whole = false; ///< nothing culled by frustum or pixel coverage, nothing cut
    std::array<double, 3> direction{};
  };

  /// A nearly-sorted re-sort is tried only after a rotation of the view direction below
  /// this many radians (larger ones move too many cells to beat the full sort).
  static constexpr double NearlySortedMaxAngle = 0.01;

  OrderStage();

  /// Sorts unless the order was made from `key`; true when it sorted. `fromPrevious`:
  /// whether sorting from the previous order may be tried (reuse is on). When it sorts it
  /// consumes `keys` (DepthKeyStage::Consume), which must not be consumed already: it takes
  /// the keys and sorts in their buffer.
  bool Update(const Key& key, const Cells& cells, bool fromPrevious, DepthKeyStage& keys,
    const NearPlaneStage& nearPlane, int threads);
  /// The inverse of the order over `ranked` cell ids (the mesh's cells and the pieces); with
  /// `candidates`, over those and the pieces only (InvertOrder).
  void Invert(std::size_t ranked, int threads, const std::uint32_t* candidates = nullptr,
    std::size_t candidateCount = 0, std::size_t meshCells = 0);

  /**
   * Groups the ranked cells of the mesh by rank, once per order, into `storage` (the depth
   * keys' buffer, DepthKeyStage::Consume, which the order no longer needs), each entry a
   * cell id in the high 32 bits and its rank in the low: group g holds the cells ranked in
   * [g * size, (g + 1) * size), ascending, where size is `ranksPerGroup` (the first window's
   * length: the batch size) or, at least, a 256th of the order. A window of the order
   * smaller than the whole (a batch) then visits the cells of the groups it overlaps
   * (CellsOfRanks), not every candidate: the frame's batches together read each cell about
   * once, not once per batch, a batch that is one group reads its cells in one ascending
   * sweep, and no rank array. `candidates` as for Invert (null: cells [0, meshCells)).
   */
  void Group(std::size_t ranksPerGroup, std::size_t meshCells, const std::uint32_t* candidates,
    std::size_t candidateCount, LargeVector<SortKey>& storage, int threads);
  /// The entries of Group's `storage` for the groups that overlap ranks
  /// [first, first + count), and their number.
  const SortKey* CellsOfRanks(std::size_t first, std::size_t count,
    const LargeVector<SortKey>& storage, std::size_t& cells) const;
  /// The most groups an order is split into.
  static constexpr std::size_t MaxGroups = 256;

  /// The order: Count() keys, back to front.
  const LargeVector<SortKey>& Keys() const { return this->Sorted; }
  std::size_t Count() const { return this->Sorted.size(); }
  /// Rank of each cell id in the order (NotInOrder for cells left out), after Invert.
  const std::uint32_t* Rank() const { return this->Ranks.data(); }
  /// Whether the last Update sorted from the previous order.
  bool FromPrevious() const { return this->SortedFromPrevious; }
  OrderMethod Method() const { return this->Sorter->Method(); }
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  bool SortFromPrevious(LargeVector<SortKey>& scratch, int threads);
  void Mutate(OrderMutation mutation);

  std::unique_ptr<VisibilityOrder> Sorter;
  std::size_t SorterMaxSubArraySize = DefaultMaxSubArraySize;
  Cells Held; ///< the cells of the held order
  LargeVector<SortKey> Sorted;
  LargeVector<std::uint32_t> Ranks;
  /// Group's first entry of each group (and the end), the counts that place them, and the
  /// order's version they were made for (0: none).
  std::vector<std::size_t> GroupStarts, GroupCounts;
  std::size_t GroupRanks = 1; ///< ranks per group
  std::uint64_t GroupedVersion = 0;
  bool SortedFromPrevious = false;
};

} // namespace mtpt

#endif
