// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Transform.h
 * @brief Stage 1 of a frame: every mesh point to normalized device coordinates.
 *
 * Conventions: see MeshView.h (row-major matrices on column vectors, OpenGL NDC).
 * The transform runs and stores its results in double precision. Decomposition classifies
 * and measures with these values: with float NDC the thickness at a thick vertex near a
 * silhouette edge would carry an absolute error of about 1e-7 of the cell's projected size
 * (tens of percent for thin segments), and meshes far from the origin would lose their
 * relative precision. Only the records handed to the rasterizer are rounded to float.
 */
#ifndef mtpt_Transform_h
#define mtpt_Transform_h

#include "mtpt/MeshView.h"

namespace mtpt
{

/**
 * A point after projection. x, y, z are NDC (clip coordinates divided by w); w is the
 * clip-space w (1 for orthographic projections, the distance along the view axis for
 * perspective ones). w <= 0 marks a point at or behind the eye plane: its x, y, z are then
 * meaningless and decomposition treats any cell using it as not drawable.
 */
struct NdcPoint
{
  double x, y, z, w;
};

/**
 * Projects `points` with `modelViewProjection` (projection * view * model) into `out`
 * (points.count entries).
 *
 * Thread safety: reentrant; runs on `threads` OpenMP threads (<= 0: all available).
 * Determinism: each output depends only on its own input point: identical for any
 * thread count.
 */
void TransformToNDC(const PointsView& points,
  const Matrix4& modelViewProjection,
  NdcPoint* out,
  int threads);

} // namespace mtpt

#endif
