// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DepthKeys.h
 * @brief Stage 2 of a frame: one sortable depth key per tetrahedron.
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

#include "mtpt/MeshView.h"
#include "mtpt/Transform.h"

#include <cstddef>
#include <cstdint>

namespace mtpt
{

using SortKey = std::uint64_t;

/**
 * The 32-bit code of a depth whose ascending order is descending depth. NaN and the
 * infinities map to the code of +infinity (drawn first; such cells are not drawable
 * anyway) and -0 maps to the code of +0, so equal depths always give equal codes.
 */
std::uint32_t EncodeDepth(float depth);

/// The sort key of `cell` at `depth`: EncodeDepth(depth) in the high 32 bits, cell id low.
inline SortKey MakeSortKey(float depth, std::uint32_t cell)
{
  return (static_cast<SortKey>(EncodeDepth(depth)) << 32) | cell;
}

/// The cell id held in a sort key.
inline std::uint32_t CellOfKey(SortKey key)
{
  return static_cast<std::uint32_t>(key & 0xffffffffu);
}

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
  /// When both are > 0: cells whose four points are usable and whose window-space bounding
  /// box holds no pixel centre of this viewport (detail/PixelCoverage.h); they produce no
  /// fragment where every pixel is sampled at its centre only.
  int viewportWidth = 0, viewportHeight = 0;
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

} // namespace mtpt

#endif
