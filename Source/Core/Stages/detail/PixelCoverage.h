// SPDX-License-Identifier: BSD-3-Clause
// Internal: whether a projected tetrahedron can produce a fragment in an image sampled at
// pixel centres, and whether what it could produce is hidden. Shared by the key stage
// (cells culled before the sort) and the decomposition (near-plane pieces; cells behind
// opaque pixels), so all cull by one rule.
#ifndef mtpt_detail_PixelCoverage_h
#define mtpt_detail_PixelCoverage_h

#include "mtpt/OpaquePixels.h"
#include "mtpt/Records.h"

#include <algorithm>
#include <cmath>

namespace mtpt
{
namespace detail
{

/// The NDC bounding box of the corners' projections.
inline void CornerBounds(
  const ProjectedPoint* const c[4], double& minX, double& maxX, double& minY, double& maxY)
{
  minX = maxX = c[0]->x;
  minY = maxY = c[0]->y;
  for (int i = 1; i < 4; ++i)
  {
    minX = std::min(minX, c[i]->x);
    maxX = std::max(maxX, c[i]->x);
    minY = std::min(minY, c[i]->y);
    maxY = std::max(maxY, c[i]->y);
  }
}

/// How far beyond the corners' box a pixel centre may still be covered: rasterizers snap
/// vertices to a 1/256-pixel grid (the CPU compositor, Mesa), which moves a vertex by up to
/// 1/512 pixel.
constexpr double SnapMargin = 1.0 / 256;

/**
 * Whether the window-space bounding box of the corners contains a pixel centre of the
 * image. Conservative by SnapMargin, so a cell this rejects covers no pixel centre after
 * snapping either.
 */
inline bool CoversPixelCentre(const ProjectedPoint* const c[4], const ImageSize& image)
{
  const int width = image.width, height = image.height;
  double minX, maxX, minY, maxY;
  CornerBounds(c, minX, maxX, minY, maxY);
  // Pixel centres x + 0.5 for x in [0, width): window x = (ndc + 1) / 2 * width.
  const double x0 = std::max(0.0, std::ceil((minX + 1.0) * 0.5 * width - 0.5 - SnapMargin));
  const double x1 =
    std::min(width - 1.0, std::floor((maxX + 1.0) * 0.5 * width - 0.5 + SnapMargin));
  const double y0 = std::max(0.0, std::ceil((minY + 1.0) * 0.5 * height - 0.5 - SnapMargin));
  const double y1 =
    std::min(height - 1.0, std::floor((maxY + 1.0) * 0.5 * height - 0.5 + SnapMargin));
  return x0 <= x1 && y0 <= y1;
}

/**
 * The pixels along one axis of `size` pixels whose centres the box [low, high] (NDC) holds,
 * widened by SnapMargin, as CoversPixelCentre finds them but as ints: [first, last], the
 * bounds clamped to [-1, size] before rounding so that every conversion is exact (the clamp
 * keeps an empty span empty). Integer rounding instead of std::ceil and std::floor, which the
 * baseline instruction set has no instruction for.
 */
inline void PixelSpan(double low, double high, int size, int& first, int& last)
{
  const double s = size;
  const double lo = std::min(std::max((low + 1.0) * 0.5 * s - 0.5 - SnapMargin, -1.0), s);
  const double hi = std::min(std::max((high + 1.0) * 0.5 * s - 0.5 + SnapMargin, -1.0), s);
  const int l = static_cast<int>(lo), h = static_cast<int>(hi); // towards zero
  first = l + (lo > l ? 1 : 0);                                 // ceil
  last = h - (hi < h ? 1 : 0);                                  // floor
}

/**
 * Whether every pixel centre the projection of the corners (usable: finite, ProjectedPoint)
 * can cover is opaque in `opaque`: their box (PixelSpan) in that image holds a pixel and
 * each pixel of the box is opaque. Such a tetrahedron, drawn behind those pixels, changes
 * none of them.
 */
inline bool HiddenBehind(const ProjectedPoint* const c[4], const OpaquePixels& opaque)
{
  double minX, maxX, minY, maxY;
  CornerBounds(c, minX, maxX, minY, maxY);
  int x0, x1, y0, y1;
  PixelSpan(minX, maxX, opaque.Width(), x0, x1);
  PixelSpan(minY, maxY, opaque.Height(), y0, y1);
  return opaque.Hides(x0, x1, y0, y1); // clamps to the image; an empty box hides nothing
}

} // namespace detail
} // namespace mtpt

#endif
