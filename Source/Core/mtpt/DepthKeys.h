// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DepthKeys.h
 * @brief Stage 2 of a frame: one sortable depth key per tetrahedron.
 *
 * Depth (DESIGN.md section 2, step 2): orthographic views use the eye-space depth -z of the
 * centroid (the paper's dot(view direction, centroid)); perspective views use the squared
 * distance from the eye to the centroid, which orders the cells at the sides of a wide
 * view correctly where the view-direction dot product does not.
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

/**
 * The keys of the cells in `list` (listCount ascending cell ids; null: every cell), written
 * compactly in list order, leaving out with `cullFrustum` the cells whose four points are
 * usable and all beyond the same clip plane (NDC x, y or z outside [-1, 1]): such a cell
 * lies outside the view volume and cannot produce a fragment. Returns the number of keys
 * written (at most listCount). Keys are those of ComputeDepthKeys.
 *
 * Thread safety: reentrant. Determinism: identical for any thread count.
 */
std::size_t ComputeVisibleDepthKeys(const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, bool perspective,
  bool cullFrustum, SortKey* keys, int threads);

} // namespace mtpt

#endif
