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

#include <cmath>

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
 * How the fragments along a ray become a pixel, with the values of vtkVolumeMapper's blend
 * modes (Documentation/blend-modes.md). Composite blends them in visibility order; the
 * others reduce them, in any order, to one value per pixel, each as VTK's GPU ray caster
 * defines it with the scalar s and its normalized value x (0 at the transfer-function
 * table's low end, 1 at its high end):
 * - MaximumIntensity, MinimumIntensity: the largest (smallest) scalar along the ray, through
 *   the transfer function: colour c(s) premultiplied by opacity o(s);
 * - AverageIntensity: the mean of o(s) x along the stretches of the ray whose scalar lies
 *   in a range, as grey, opaque;
 * - Additive: the integral of o(s) x along the ray per unit distance, clamped to 1, as
 *   grey, opaque.
 * Each is computed exactly over each fragment's segment, along which the scalar is linear.
 */
enum class BlendMode
{
  Composite = 0,
  MaximumIntensity = 1,
  MinimumIntensity = 2,
  AverageIntensity = 3,
  Additive = 4
};

/// Whether `mode` reduces fragments in any order instead of blending them in order.
inline bool ReducesInAnyOrder(BlendMode mode)
{
  return mode != BlendMode::Composite;
}

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

/**
 * Depth peeling (Documentation/algorithm.md, "Translucent geometry and depth peeling"): a
 * fragment contributes only the part of its ray segment between two window depths. Along
 * one ray, eye depth (the distance along the view axis) is linear in the distance travelled,
 * so the part is found in eye depth: window depth z_win maps to NDC z = 2 z_win - 1 and to
 * eye depth D by 1 / D = a z_ndc + b in a perspective view and D = a z_ndc + b in an
 * orthographic one; a segment of eye length L starting at eye depth D runs to
 * D + L / |d|, with |d| the ray's eye length per unit of depth (PerspectiveInterpolation;
 * 1 in orthographic views).
 */
struct DepthClipping
{
  bool perspective = false;
  double a = 1.0, b = 0.0;
  PerspectiveInterpolation ray; ///< the eye ray per unit depth at a pixel (perspective)
  /// Orthographic: eye x = (x_ndc + shiftX) * scaleX, and y alike.
  double scaleX = 1.0, shiftX = 0.0, scaleY = 1.0, shiftY = 0.0;

  /// From an OpenGL-style projection (row-major), perspective or orthographic.
  static DepthClipping FromProjection(const Matrix4& projection);

  /// Eye depth at window depth `windowDepth`.
  double EyeDepth(double windowDepth) const
  {
    const double ndc = 2.0 * windowDepth - 1.0;
    return this->perspective ? 1.0 / (this->a * ndc + this->b) : this->a * ndc + this->b;
  }

  /// The eye-space point at eye depth `depth` on the ray through NDC (x, y).
  void EyePoint(double x, double y, double depth, double e[3]) const
  {
    if (this->perspective)
    {
      e[0] = depth * (x + this->ray.shiftX) * this->ray.scaleX;
      e[1] = depth * (y + this->ray.shiftY) * this->ray.scaleY;
    }
    else
    {
      e[0] = (x + this->shiftX) * this->scaleX;
      e[1] = (y + this->shiftY) * this->scaleY;
    }
    e[2] = -depth;
  }

  /// The eye length per unit of eye depth of the ray through NDC (x, y).
  double RayLength(double x, double y) const
  {
    if (!this->perspective)
    {
      return 1.0;
    }
    const double rx = (x + this->ray.shiftX) * this->ray.scaleX;
    const double ry = (y + this->ray.shiftY) * this->ray.scaleY;
    return std::sqrt(1.0 + rx * rx + ry * ry);
  }

  /**
   * The part [t0, t1] (fractions of the segment, 0 at its front) of a segment from eye depth
   * `front` to `back` that lies between window depths `nearDepth` and `farDepth`; false
   * when no part of positive length does.
   */
  bool Part(
    double front, double back, float nearDepth, float farDepth, double& t0, double& t1) const
  {
    const double span = back - front;
    if (!(span > 0.0) || !(nearDepth <= farDepth))
    {
      return false;
    }
    const double from = (this->EyeDepth(nearDepth) - front) / span;
    const double to = (this->EyeDepth(farDepth) - front) / span;
    t0 = from > 0.0 ? (from < 1.0 ? from : 1.0) : 0.0;
    t1 = to > 0.0 ? (to < 1.0 ? to : 1.0) : 0.0;
    return t1 > t0;
  }
};

/**
 * Clipping planes (vtkAbstractMapper's, Documentation/clipping-planes.md) in eye coordinates:
 * plane i keeps the half-space n . e + d >= 0 of plane[i] = (n, d), as VTK's mappers keep
 * the side a vtkPlane's normal points to; where a distance is not a number (a plane or a
 * point that is not finite) the plane cuts nothing, as in VTK's GPU ray caster. Each
 * fragment's ray segment is cut exactly where it leaves a kept half-space: along a ray, the
 * distance to a plane is affine in the distance travelled, so the cut is found from its two
 * ends.
 */
struct ClipPlanes
{
  /// As many as VTK's GPU ray caster takes.
  static constexpr int Max = 8;
  int count = 0;
  double plane[Max][4] = {};

  bool operator==(const ClipPlanes& o) const
  {
    for (int i = 0; i < this->count && i < o.count; ++i)
    {
      for (int k = 0; k < 4; ++k)
      {
        if (this->plane[i][k] != o.plane[i][k])
        {
          return false;
        }
      }
    }
    return this->count == o.count;
  }

  /// Signed distance (times the normal's length) of eye point e to plane i.
  double Distance(int i, const double e[3]) const
  {
    const double* p = this->plane[i];
    return p[0] * e[0] + p[1] * e[1] + p[2] * e[2] + p[3];
  }

  /**
   * Narrows [t0, t1] (fractions of a segment from eye point `front`, 0, to `back`, 1) to the
   * part every plane keeps; false when no part of positive length is left.
   */
  bool Narrow(const double front[3], const double back[3], double& t0, double& t1) const
  {
    for (int i = 0; i < this->count; ++i)
    {
      const double f0 = this->Distance(i, front), f1 = this->Distance(i, back);
      if (std::isnan(f0) || std::isnan(f1))
      {
        continue; // a plane (or an end) that is not a number cuts nothing, as in VTK
      }
      if (f0 >= 0.0 && f1 >= 0.0)
      {
        continue;
      }
      if (f0 < 0.0 && f1 < 0.0)
      {
        return false; // wholly clipped
      }
      const double cut = f0 / (f0 - f1); // where the distance is 0, in (0, 1]
      if (f0 < 0.0)
      {
        t0 = cut > t0 ? cut : t0;
      }
      else
      {
        t1 = cut < t1 ? cut : t1;
      }
    }
    return t1 > t0;
  }
};

} // namespace mtpt

#endif
