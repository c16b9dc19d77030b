// SPDX-License-Identifier: BSD-3-Clause
// Internal: whether a projected tetrahedron can produce a fragment in an image sampled at
// pixel centres. Shared by the key stage (cells culled before the sort) and the
// decomposition (near-plane pieces), so both cull by one rule.
#ifndef mtpt_detail_PixelCoverage_h
#define mtpt_detail_PixelCoverage_h

#include "mtpt/Records.h"

#include <algorithm>
#include <cmath>

namespace mtpt
{
namespace detail
{

/**
 * Whether the window-space bounding box of the corners contains a pixel centre of the
 * image. Conservative by 1/256 pixel: rasterizers snap vertices to a
 * 1/256-pixel grid (the CPU compositor, Mesa), which moves a vertex by up to 1/512 pixel,
 * so a cell this rejects covers no pixel centre after snapping either.
 */
inline bool CoversPixelCentre(const ProjectedPoint* const c[4], const ImageSize& image)
{
  const int width = image.width, height = image.height;
  double minX = c[0]->x, maxX = c[0]->x, minY = c[0]->y, maxY = c[0]->y;
  for (int i = 1; i < 4; ++i)
  {
    minX = std::min(minX, c[i]->x);
    maxX = std::max(maxX, c[i]->x);
    minY = std::min(minY, c[i]->y);
    maxY = std::max(maxY, c[i]->y);
  }
  constexpr double Margin = 1.0 / 256;
  // Pixel centres x + 0.5 for x in [0, width): window x = (ndc + 1) / 2 * width.
  const double x0 = std::max(0.0, std::ceil((minX + 1.0) * 0.5 * width - 0.5 - Margin));
  const double x1 = std::min(width - 1.0, std::floor((maxX + 1.0) * 0.5 * width - 0.5 + Margin));
  const double y0 = std::max(0.0, std::ceil((minY + 1.0) * 0.5 * height - 0.5 - Margin));
  const double y1 = std::min(height - 1.0, std::floor((maxY + 1.0) * 0.5 * height - 0.5 + Margin));
  return x0 <= x1 && y0 <= y1;
}

} // namespace detail
} // namespace mtpt

#endif
