// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Transform.h
 * @brief Stage 1 of a frame: every mesh point to eye and normalized device coordinates.
 *
 * Conventions: see MeshView.h (row-major matrices on column vectors, OpenGL NDC, the
 * camera looking down -z in eye space).
 *
 * Each point becomes one 64-byte record holding everything the later stages read about
 * it, so a tetrahedron costs four cache-line gathers instead of a dozen scattered reads of
 * coordinates, projections and scalars. Records are double precision: decomposition
 * classifies and measures with them, and with float NDC the thickness at a thick vertex
 * near a silhouette edge would carry an absolute error of about 1e-7 of the cell's
 * projected size (large relative errors for thin segments); eye coordinates are relative
 * to the camera, so meshes far from the origin keep their precision. Only the records
 * handed to the rasterizer are rounded to float.
 */
#ifndef mtpt_Transform_h
#define mtpt_Transform_h

#include "mtpt/MeshView.h"

#include <cstdint>

namespace mtpt
{

/**
 * A point after projection. x, y, z are NDC (clip coordinates divided by w) and inverseW is
 * 1 / w, the clip-space w (1 for orthographic projections, the distance along the view axis
 * for perspective ones): decomposition interpolates perspective-correctly with it.
 * `usable` is 0 for a point that no cell may be drawn with: at or behind the eye plane
 * (w <= 0), a coordinate or scalar that is not finite, or a magnitude beyond
 * CoordinateLimit. Its other fields are then meaningless.
 */
struct alignas(64) ProjectedPoint
{
  double x, y, z, inverseW; ///< NDC and 1 / clip w
  double eyeX, eyeY, eyeZ;  ///< eye coordinates (model-view applied)
  float scalar;             ///< the point's scalar; 0 without point scalars
  std::int32_t usable;      ///< 1 if usable, 0 if not (checked once here, not per cell)
};

/// Beyond this magnitude a coordinate is unusable: it keeps every value written to the
/// float vertex records finite (float overflows near 3.4e38).
constexpr double CoordinateLimit = 1e30;

/**
 * Projects `points` into `out` (points.count records) with the model-view matrix
 * (view * model) and the projection matrix, and copies point scalars alongside.
 *
 * Thread safety: reentrant; runs on `threads` OpenMP threads (<= 0: all available).
 * Determinism: each record depends only on its own input point: identical for any
 * thread count.
 */
void ProjectPoints(const PointsView& points, const ScalarsView& scalars, const Matrix4& modelView,
  const Matrix4& projection, ProjectedPoint* out, int threads);

} // namespace mtpt

#endif
