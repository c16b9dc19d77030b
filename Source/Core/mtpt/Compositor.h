// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Compositor.h
 * @brief The CPU compositor: blends the decomposition's sorted triangles into a float RGBA
 * image with the per-fragment math of the OpenGL path, for machines where OpenGL is itself
 * a software rasterizer (DESIGN.md section 7).
 *
 * Conventions:
 * - Window coordinates: pixel (x, y) covers [x, x+1) x [y, y+1), y up (OpenGL), its
 *   sample point is the centre (x + 0.5, y + 0.5). NDC map to window coordinates as
 *   X = (x_ndc + 1) / 2 * width, Y = (y_ndc + 1) / 2 * height; depth = (z_ndc + 1) / 2.
 * - Coverage: a pixel belongs to a triangle if its centre is inside, or on an edge that is
 *   a top or a left edge (the top-left rule of Direct3D and of Mesa's rasterizers), so a
 *   pixel on an edge shared by two triangles is covered exactly once.
 * - Shading, exactly as the GL path's shaders, in one of two modes (Shading):
 *   VTK-compatible: each vertex is classified as the mean of the transfer function at its
 *   front and back scalars (colour rgb, attenuation a); colour, attenuation and segment
 *   length are interpolated linearly in screen space; fragment opacity =
 *   1 - exp(-a * length / unitDistance).
 *   Pre-integrated: the front scalar, back scalar and segment length are interpolated
 *   (in perspective views exactly, see PerspectiveInterpolation) and each fragment is
 *   shaded by PreIntegrationTable::Segment, so transfer-function features between the
 *   vertex scalars are not missed.
 * - Threads: the image is cut into one band of rows per thread, balanced by the number of
 *   tetrahedra starting in each row; each thread streams through all slots in order,
 *   rejects whole tetrahedra by their bounding box, and rasterizes into its own rows.
 * - Blending, as glBlendFuncSeparate(SRC_ALPHA, ONE_MINUS_SRC_ALPHA, ONE,
 *   ONE_MINUS_SRC_ALPHA) starting from a transparent image: the result is premultiplied
 *   colour and coverage alpha, to be composited over the framebuffer with (ONE,
 *   ONE_MINUS_SRC_ALPHA). Slots are drawn in buffer order (back to front).
 * - Depth: with an opaque depth image, a fragment is kept if its depth is <= the opaque
 *   depth at that pixel (GL_LEQUAL, no depth writes).
 */
#ifndef mtpt_Compositor_h
#define mtpt_Compositor_h

#include "mtpt/Decompose.h"
#include "mtpt/MeshView.h"
#include "mtpt/TransferFunctionTable.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/// How fragments are classified (see the file comment).
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

struct CompositeSettings
{
  int width = 0, height = 0;
  TransferFunctionTable transferFunction;
  Shading shading = Shading::VTKCompatible;
  /// Integral functions of `transferFunction`, required for Shading::PreIntegrated.
  const PreIntegrationTable* preIntegration = nullptr;
  double unitDistance = 1.0;
  /// Optional window depth of opaque geometry in [0, 1], width * height floats, row 0 at
  /// the bottom. Null: no occlusion.
  const float* opaqueDepth = nullptr;
  /// Blend over the image already in `rgba` (same size) instead of clearing it: a frame
  /// drawn in batches composites batch after batch, back to front.
  bool accumulate = false;
  /// Pre-integrated shading in perspective views: see PerspectiveInterpolation.
  PerspectiveInterpolation interpolation;

  /// Switches to pre-integrated shading with `table` (the integral functions of
  /// transferFunction, kept alive by the caller) and the view's `interpolation`.
  void UsePreIntegration(const PreIntegrationTable& table, const PerspectiveInterpolation& view)
  {
    this->shading = Shading::PreIntegrated;
    this->preIntegration = &table;
    this->interpolation = view;
  }
};

/**
 * Composites slots [0, count) of the decomposition buffers into `rgba` (4 * width *
 * height floats, premultiplied, row 0 at the bottom), which it resizes and clears unless
 * settings.accumulate is set and it already has that size.
 *
 * Thread safety: reentrant. Determinism: every pixel is blended by one thread in slot
 * order, so the image is bit-identical for any thread count.
 */
class Compositor
{
public:
  void Composite(const TetVertex* vertices, const std::uint32_t* indices, std::size_t count,
    const CompositeSettings& settings, std::vector<float>& rgba, int threads);

  /// (Triangle, band) pairs that covered at least one pixel centre in the last Composite.
  std::size_t RasterizedTriangles() const { return this->Rasterized; }

private:
  std::vector<std::uint32_t> RowCounts; ///< per thread: slots by their first pixel row
  std::size_t Rasterized = 0;
};

} // namespace mtpt

#endif
