// SPDX-License-Identifier: BSD-3-Clause
// How many pixel centres each fan covers, for measurements (mtpt_bench_compositor
// --coverage; Documentation/compositor.md, "Where a small fan's time goes"): the
// rasterizer's own coverage, fan by fan over the whole image.
#ifndef mtpt_bench_FanCoverage_h
#define mtpt_bench_FanCoverage_h

#include "mtpt/Records.h"

#include <cstddef>

namespace mtpt
{
namespace bench
{

/// Bins of CountCoveredCentres: 0 to CoverageBins - 2 centres, and the last for more.
constexpr int CoverageBins = 12;

/// Fans by the pixel centres each covers (CountCoveredCentres).
struct CoverageHistogram
{
  std::size_t fans[CoverageBins] = {}; ///< fans[c]: the fans covering c centres
  /// Of fans[c], those whose silhouette has four corners (a quadrilateral projection): a
  /// record that keeps the corners' values needs more room for them.
  std::size_t quadrilaterals[CoverageBins] = {};
  std::size_t centres = 0; ///< the centres covered in all

  void Add(const CoverageHistogram& other)
  {
    for (int c = 0; c < CoverageBins; ++c)
    {
      this->fans[c] += other.fans[c];
      this->quadrilaterals[c] += other.quadrilaterals[c];
    }
    this->centres += other.centres;
  }
};

/**
 * Counts in `histogram` each fan of fans[0, count) that has something to draw (Fan::count
 * at least 2) by c, the pixel centres of a width x height image its triangles cover by the
 * rasterizer's rule (1/256-pixel snapping, the top-left rule), the last bin for
 * CoverageBins - 1 or more, and adds the centres covered. A fan that covers a centre with
 * two triangles (a projection folded over) counts it twice, as the compositor draws it.
 */
void CountCoveredCentres(
  const Fan* fans, std::size_t count, int width, int height, CoverageHistogram& histogram);

} // namespace bench
} // namespace mtpt

#endif
