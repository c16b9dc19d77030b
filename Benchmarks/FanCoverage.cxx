// SPDX-License-Identifier: BSD-3-Clause
// How many pixel centres each fan covers (FanCoverage.h): the rasterizer's coverage
// (detail/RasterCorners-inl.h) applied triangle by triangle as the triangle path applies it,
// compiled once per instruction set as the rasterizer compiles it, so that the count is the
// rasterizer's own. Coverage is exact fixed-point arithmetic, the same on every instruction
// set; the fan path covers the same pixels (detail/FanPath-inl.h).
#include "FanCoverage.h"

#include <algorithm>
#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "FanCoverage.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

#include <hwy/highway.h>

#include "detail/RasterCorners-inl.h"

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace bench
{
namespace HWY_NAMESPACE
{
using namespace mtpt::detail::HWY_NAMESPACE;
using mtpt::detail::RasterFrame;

/// The pixel centres of the image that the triangle of corners v covers (DrawTriangle's
/// coverage, the whole image as its tile).
std::size_t TriangleCentres(const RasterFrame& f, const Corner* const v[3])
{
  const double X[3] = { v[0]->X, v[1]->X, v[2]->X }, Y[3] = { v[0]->Y, v[1]->Y, v[2]->Y };
  int x0, x1, y0, y1;
  if (!TrianglePixels(X, Y, 0, f.width - 1, 0, f.height - 1, x0, x1, y0, y1))
  {
    return 0;
  }
  std::size_t covered = 0;
  auto span = [&](int, int lo, int hi) { covered += static_cast<std::size_t>(hi - lo + 1); };
  Edges edges;
  if (!WithinFixedPoint(X, Y))
  {
    CoverGuardBand(f, X, Y, x0, x1, y0, y1, span);
  }
  else if (SetUpEdges(X, Y, edges))
  {
    CoverSpans(edges, x0, x1, y0, y1, span);
  }
  return covered;
}

void CountCoveredCentresImpl(
  const Fan* fans, std::size_t count, int width, int height, CoverageHistogram& histogram)
{
  RasterFrame f;
  f.width = width;
  f.height = height;
  for (std::size_t i = 0; i < count; ++i)
  {
    const Fan& fan = fans[i];
    const int n = fan.count;
    if (n < 2)
    {
      continue;
    }
    Corner corners[5];
    const bool finite = PlaceFanCorners(f, fan, corners);
    std::size_t covered = 0;
    const int triangles = fan.closed ? n : n - 1;
    for (int k = 0; finite && k < triangles; ++k)
    {
      const Corner* const v[3] = { &corners[k], &corners[(k + 1) % n], &corners[n] };
      covered += TriangleCentres(f, v);
    }
    const std::size_t bin = std::min<std::size_t>(covered, CoverageBins - 1);
    histogram.centres += covered;
    ++histogram.fans[bin];
    histogram.quadrilaterals[bin] += n == 4 ? 1 : 0;
  }
}

} // namespace HWY_NAMESPACE
} // namespace bench
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtpt
{
namespace bench
{

HWY_EXPORT(CountCoveredCentresImpl);

void CountCoveredCentres(
  const Fan* fans, std::size_t count, int width, int height, CoverageHistogram& histogram)
{
  HWY_DYNAMIC_DISPATCH(CountCoveredCentresImpl)(fans, count, width, height, histogram);
}

} // namespace bench
} // namespace mtpt
#endif
