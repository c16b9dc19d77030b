// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DepthKeys.h
 * @brief Stage 3 of a frame: one sortable depth key per tetrahedron.
 *
 * Depth (Documentation/algorithm.md, "Depth keys"): orthographic views use the eye-space
 * depth -z of the centroid (the paper's dot(view direction, centroid)); perspective views
 * use the squared distance from the eye to the centroid, which orders the cells at the
 * sides of a wide view correctly where the view-direction dot product does not.
 *
 * A sort key packs the depth and the cell id into one 64-bit integer so that ascending
 * key order is the visibility order: back to front (farthest first), and among equal
 * depths ascending cell id. Any correct sort of the keys therefore yields one and the
 * same permutation, whatever the algorithm or the thread count.
 */
#ifndef mtpt_DepthKeys_h
#define mtpt_DepthKeys_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/Records.h"
#include "mtpt/Stage.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/**
 * Writes keys[c] = MakeSortKey(depth of cell c, c) for every cell, from the eye
 * coordinates of the projected points (ProjectPoints; pointCount records): the centroid is
 * the mean of the four eye positions, in double precision. A cell that is not a
 * tetrahedron (other than 4 points) or that names a point id outside [0, pointCount) gets
 * the depth +infinity. Requires cells.cellCount < 2^32.
 *
 * Thread safety: reentrant; `threads` OpenMP threads (<= 0: all available).
 * Determinism: identical for any thread count.
 */
void ComputeDepthKeys(const ProjectedPoint* points, std::size_t pointCount, const CellsView& cells,
  bool perspective, SortKey* keys, int threads);

/// What ComputeVisibleDepthKeys leaves out.
struct KeyCulling
{
  /// Cells whose four points are usable and all beyond the same clip plane (NDC x, y or z
  /// outside [-1, 1]): they lie outside the view volume and cannot produce a fragment.
  bool frustum = false;
  /// When set: cells whose four points are usable and whose window-space bounding box holds
  /// no pixel centre of the composited image (detail/PixelCoverage.h); they produce no
  /// fragment where every pixel is sampled at its centre only.
  ImageSize imageSize;
};

/// How many keys ComputeVisibleDepthKeys wrote and how many cells it left out, and why.
struct KeyCounts
{
  std::size_t kept = 0, frustumCulled = 0, pixelCulled = 0;
};

/**
 * The keys of the cells in `list` (listCount ascending cell ids; null: every cell), written
 * compactly in list order, leaving out the cells `culling` asks for. Keys are those of
 * ComputeDepthKeys. Cells with a point that is not usable (behind the eye, non-finite) are
 * never culled here: the near-plane stage decides about them.
 *
 * Thread safety: reentrant. Determinism: identical for any thread count.
 */
KeyCounts ComputeVisibleDepthKeys(const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, bool perspective,
  const KeyCulling& culling, SortKey* keys, int threads);

/// What the depth keys depend on: DepthKeyStage's key.
struct DepthKeyStageKey
{
  std::uint64_t points = 0;  ///< TransformStage::Version()
  std::uint64_t visible = 0; ///< CellSelectionStage::Version()
  bool perspective = false;
  KeyCulling culling;
  bool operator==(const DepthKeyStageKey& o) const
  {
    return points == o.points && visible == o.visible && perspective == o.perspective &&
      culling.frustum == o.culling.frustum && culling.imageSize == o.culling.imageSize;
  }
};

/**
 * Stage 3 as a stage of FramePipeline (Stage.h): the keys of the cells left by culling and
 * by ComputeVisibleDepthKeys, in ascending cell id order, kept until the projected points,
 * the visible cells or the culling settings change.
 *
 * The order stage takes the keys and sorts in their buffer (Consume), so that a frame holds
 * the mesh's keys twice, not three or four times. The result stays valid for the stages
 * that hold what they made from it; a stage that must read the keys again while they are
 * consumed has them computed anew (FramePipeline::UpdateOrder forgets this stage).
 */
class DepthKeyStage : public StageOf<DepthKeyStageKey>
{
public:
  /// Computes the keys of `list` (null: every cell) unless they were computed with `key`;
  /// true when it computed.
  bool Update(const Key& key, const ProjectedPoint* points, std::size_t pointCount,
    const CellsView& cells, const std::uint32_t* list, std::size_t listCount, int threads);

  /// The keys; not to be read while Consumed().
  const LargeVector<SortKey>& Keys() const { return this->Kept; }
  /**
   * The keys' buffer, to move the keys out of and to use as scratch: it holds no particular
   * values afterwards, and Consumed() is true until the keys are computed again.
   */
  LargeVector<SortKey>& Consume()
  {
    this->Used = true;
    return this->Kept;
  }
  bool Consumed() const { return this->Used; }
  /// How many cells the keys left out, and why.
  const KeyCounts& Counts() const { return this->Count; }
  void Release() override;
  std::size_t MemoryBytes() const override { return this->Kept.capacity() * sizeof(SortKey); }

private:
  LargeVector<SortKey> Kept;
  KeyCounts Count;
  bool Used = false; ///< Consume was called since the keys were computed
};

} // namespace mtpt

#endif
