// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Gradients.h
 * @brief Shading's data (Lighting.h): the gradient of the point scalars at every point and
 * each tetrahedron's normal, computed once per change of the data.
 */
#ifndef mtpt_Gradients_h
#define mtpt_Gradients_h

#include "mtpt/MeshView.h"

#include <cstddef>
#include <vector>

namespace mtpt
{

/**
 * The gradient of the point scalars at every point (3 floats per point, in model
 * coordinates): the mean of the constant gradients of the tetrahedra around it, each
 * weighted by its volume. Cells that are not tetrahedra, have ids out of range, no volume or
 * non-finite values count for nothing; a point no tetrahedron counts for gets zero. A linear
 * field gets its exact gradient everywhere. A gradient beyond 1e30 keeps its direction at
 * that magnitude (float's range). Requires point scalars (zero everywhere otherwise).
 * Thread safety: reentrant; `threads` OpenMP threads. Bit-identical for any thread count.
 */
void PointGradients(const PointsView& points, const CellsView& cells, const ScalarsView& scalars,
  std::vector<float>& gradients, int threads);

/**
 * Each tetrahedron's normal (3 floats per cell, model coordinates): the mean of its points'
 * `gradients` (PointGradients), normalized; zero for a cell that is not a tetrahedron, has ids
 * out of range, or whose mean gradient is zero or not finite.
 * Thread safety: reentrant; `threads` OpenMP threads.
 */
void CellNormals(const CellsView& cells, std::size_t pointCount,
  const std::vector<float>& gradients, std::vector<float>& normals, int threads);

} // namespace mtpt

#endif
