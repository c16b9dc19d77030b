// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/DepthKeys.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace mtpt
{

std::uint32_t EncodeDepth(float depth)
{
  if (!std::isfinite(depth))
  {
    depth = std::numeric_limits<float>::infinity();
  }
  depth += 0.0f; // -0 + +0 == +0: equal depths get equal bits
  std::uint32_t bits;
  std::memcpy(&bits, &depth, sizeof(bits));
  // IEEE-754 to an unsigned code that ascends with the float: flip all bits of negatives,
  // only the sign bit of positives. Complementing it makes ascending codes descending
  // depth, i.e. back to front.
  const std::uint32_t ascending = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  return ~ascending;
}

namespace
{

template <typename Access>
void KeysFor(const Access& cells, const ProjectedPoint* points, std::size_t cellCount,
  bool perspective, SortKey* keys, int threads)
{
  const auto count = static_cast<std::int64_t>(cellCount);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t c = 0; c < count; ++c)
  {
    std::int64_t ids[4];
    float depth = std::numeric_limits<float>::infinity();
    if (cells.TetrahedronPoints(static_cast<std::size_t>(c), ids))
    {
      double x = 0, y = 0, z = 0;
      for (int i = 0; i < 4; ++i)
      {
        const ProjectedPoint& p = points[ids[i]];
        x += p.eyeX;
        y += p.eyeY;
        z += p.eyeZ;
      }
      x *= 0.25;
      y *= 0.25;
      z *= 0.25;
      // Perspective: squared distance from the eye (at the eye-space origin). Orthographic:
      // distance along the view axis; the camera looks down -z.
      depth = static_cast<float>(perspective ? x * x + y * y + z * z : -z);
    }
    keys[c] = MakeSortKey(depth, static_cast<std::uint32_t>(c));
  }
}

} // namespace

void ComputeDepthKeys(const ProjectedPoint* points, std::size_t pointCount, const CellsView& cells,
  bool perspective, SortKey* keys, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    { KeysFor(access, points, cells.cellCount, perspective, keys, nthreads); });
}

} // namespace mtpt
