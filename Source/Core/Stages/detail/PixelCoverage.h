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

/**
 * The pixels of the image (width x height) whose centres the window-space bounding box of
 * the corners contains, clamped to the image: columns [x0, x1], rows [y0, y1], empty when
 * x0 > x1 or y0 > y1 (or a bound is not a number). Conservative by 1/256 pixel: rasterizers
 * snap vertices to a 1/256-pixel grid (the CPU compositor, Mesa), which moves a vertex by up
 * to 1/512 pixel, so no pixel centre outside the box is covered after snapping either.
 */
struct PixelBox
{
  double x0, x1, y0, y1;

  PixelBox(const ProjectedPoint* const c[4], int width, int height)
  {
    double minX, maxX, minY, maxY;
    CornerBounds(c, minX, maxX, minY, maxY);
    constexpr double Margin = 1.0 / 256;
    // Pixel centres x + 0.5 for x in [0, width): window x = (ndc + 1) / 2 * width.
    x0 = std::max(0.0, std::ceil((minX + 1.0) * 0.5 * width - 0.5 - Margin));
    x1 = std::min(width - 1.0, std::floor((maxX + 1.0) * 0.5 * width - 0.5 + Margin));
    y0 = std::max(0.0, std::ceil((minY + 1.0) * 0.5 * height - 0.5 - Margin));
    y1 = std::min(height - 1.0, std::floor((maxY + 1.0) * 0.5 * height - 0.5 + Margin));
  }

  /// Whether the box holds a pixel centre (false for a bound that is not a number).
  bool Holds() const { return x0 <= x1 && y0 <= y1; }
};

/// Whether the window-space bounding box of the corners contains a pixel centre of the
/// image (PixelBox).
inline bool CoversPixelCentre(const ProjectedPoint* const c[4], const ImageSize& image)
{
  return PixelBox(c, image.width, image.height).Holds();
}

/**
 * PixelBox's pixels along one axis of `size` pixels, for the box [low, high] (NDC), as ints:
 * [first, last], clamped to [-1, size] before rounding so that every conversion is exact
 * (the clamp keeps an empty box empty). Integer rounding instead of std::ceil and
 * std::floor, which the baseline instruction set has no instruction for.
 */
inline void PixelSpan(double low, double high, int size, int& first, int& last)
{
  constexpr double Margin = 1.0 / 256;
  const double s = size;
  const double lo = std::min(std::max((low + 1.0) * 0.5 * s - 0.5 - Margin, -1.0), s);
  const double hi = std::min(std::max((high + 1.0) * 0.5 * s - 0.5 + Margin, -1.0), s);
  const int l = static_cast<int>(lo), h = static_cast<int>(hi); // towards zero
  first = l + (lo > l ? 1 : 0);                                 // ceil
  last = h - (hi < h ? 1 : 0);                                  // floor
}

/**
 * Whether every pixel centre the projection of the corners (usable: finite, ProjectedPoint)
 * can cover is opaque in `opaque`: its PixelBox in that image holds a pixel and each pixel
 * of the box is opaque. Such a tetrahedron, drawn behind those pixels, changes none of them.
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
