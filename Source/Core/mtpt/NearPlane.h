// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file NearPlane.h
 * @brief Cells that cross the near plane are cut by it and their visible part drawn, where
 * VTK's PT drops the whole cell (holes when the camera is near or inside the mesh;
 * Documentation/algorithm.md, "Near-plane clipping").
 *
 * The cutting plane is NDC z = NearPlaneNdcZ, a hair behind the near plane, so that the
 * rasterizer's own near clipping (z < -1) never removes a fragment of a piece. The plane
 * is written in eye coordinates as d(e) = (row 2 - NearPlaneNdcZ * row 3 of the
 * projection) . (e, 1): d >= 0 on the visible side. d is linear in eye coordinates, so a
 * cell's edge meets the plane at t = d_a / (d_a - d_b), where position and scalar are
 * interpolated linearly (exact: both are linear inside a tetrahedron). The visible part of
 * a tetrahedron is a tetrahedron (one corner visible) or a triangular prism (two or three
 * visible), cut into 3 tetrahedra. Pieces are drawn like cells: each gets its own depth
 * key and slot, so the fixed-stride buffers and the thread-count independence hold.
 */
#ifndef mtpt_NearPlane_h
#define mtpt_NearPlane_h

#include "mtpt/MeshView.h"
#include "mtpt/Transform.h"

#include <vector>

namespace mtpt
{

/// NDC z of the cutting plane.
constexpr double NearPlaneNdcZ = -1.0 + 1e-6;

/// The cutting plane in eye coordinates: d(e) = c[0] ex + c[1] ey + c[2] ez + c[3].
struct NearPlane
{
  double c[4];

  explicit NearPlane(const Matrix4& projection);
  /// Signed distance of a point (its eye coordinates); NaN for non-finite points.
  double Distance(const ProjectedPoint& p) const
  {
    return c[0] * p.eyeX + c[1] * p.eyeY + c[2] * p.eyeZ + c[3];
  }
};

/// True if the point's eye coordinates and scalar are finite and bounded (whether or not
/// it can be projected): such a point can be cut against the plane.
bool HasFiniteEyeCoordinates(const ProjectedPoint& p);

/// One piece of a cut tetrahedron: its 4 corners, projected, their scalars and, for
/// dependent components, their colours (zero otherwise).
struct NearPiece
{
  ProjectedPoint corners[4];
  float scalars[4];
  float colours[4][4];
};

/**
 * Appends to `pieces` the part of the tetrahedron `corners` (with `scalars`, one per
 * corner, and `colours`, an RGBA per corner or null) on the visible side of `plane`:
 * nothing if no corner is on it, the tetrahedron unchanged if all are, else 1 or 3 pieces
 * whose new corners lie on the plane and are projected with `projection`, their scalars
 * and colours interpolated linearly. Returns the number of pieces appended. Every corner
 * must satisfy HasFiniteEyeCoordinates. Thread safety: pure function of its arguments.
 */
int CutTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  const NearPlane& plane, const Matrix4& projection, std::vector<NearPiece>& pieces,
  const float* const* colours = nullptr);

} // namespace mtpt

#endif
