// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Shading.h
 * @brief The vocabulary of shading that both ways to the screen share (the CPU compositor and
 * the OpenGL backend's shaders): the shading mode, and what perspective-exact interpolation
 * needs of the projection. On the lowest floor of the core, beside MeshView.h and Records.h.
 */
#ifndef mtpt_Shading_h
#define mtpt_Shading_h

#include "mtpt/MeshView.h"

namespace mtpt
{

/// How fragments are classified: VTK-compatible (each vertex classified, colour and
/// attenuation interpolated) or pre-integrated (each fragment's segment integrated through
/// the transfer function). Documentation/algorithm.md, "Shading".
enum class Shading
{
  VTKCompatible,
  PreIntegrated
};

/**
 * What perspective-exact interpolation needs of the projection (pre-integrated shading).
 * In a perspective view each triangle of the decomposition has one planar front face and
 * one planar back face (its silhouette vertices have front = back), so 1 / w (w = clip w,
 * the eye depth) of each is affine in screen space, and so is the eye-space ray direction
 * d = ((x_ndc + shiftX) * scaleX, (y_ndc + shiftY) * scaleY, -1) per unit of depth. Per
 * fragment the segment length is (w_back - w_front) |d| and the front and back scalars are
 * interpolated perspective-correctly over their faces: exact up to rounding, where
 * interpolating the vertex lengths linearly in screen space (VTK's PT) is off by up to a
 * few per cent near the eye. Orthographic views need none of it (all linear).
 */
struct PerspectiveInterpolation
{
  bool perspective = false;
  double inverseWScale = 0.0, inverseWOffset = 1.0; ///< 1 / w = scale * z_ndc + offset
  double scaleX = 0.0, shiftX = 0.0, scaleY = 0.0, shiftY = 0.0;

  /// From an OpenGL-style projection (row-major). A matrix whose last two rows depend on
  /// eye x or y (none that VTK builds) gives the orthographic (linear) default.
  static PerspectiveInterpolation FromProjection(const Matrix4& projection);
};

} // namespace mtpt

#endif
