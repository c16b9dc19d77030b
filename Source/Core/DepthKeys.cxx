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

template<typename Access>
void KeysFor(const Access& mesh,
  std::size_t cellCount,
  const Matrix4& mv,
  bool perspective,
  SortKey* keys,
  int threads)
{
  const auto count = static_cast<std::int64_t>(cellCount);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t c = 0; c < count; ++c)
  {
    std::int64_t ids[4];
    float depth = std::numeric_limits<float>::infinity();
    if (mesh.TetrahedronPoints(static_cast<std::size_t>(c), ids))
    {
      double centroid[3] = { 0, 0, 0 };
      for (int i = 0; i < 4; ++i)
      {
        double p[3];
        mesh.Point(ids[i], p);
        centroid[0] += p[0];
        centroid[1] += p[1];
        centroid[2] += p[2];
      }
      const double x = 0.25 * centroid[0], y = 0.25 * centroid[1], z = 0.25 * centroid[2];
      const double ez = mv[8] * x + mv[9] * y + mv[10] * z + mv[11];
      if (perspective)
      {
        const double ex = mv[0] * x + mv[1] * y + mv[2] * z + mv[3];
        const double ey = mv[4] * x + mv[5] * y + mv[6] * z + mv[7];
        depth = static_cast<float>(ex * ex + ey * ey + ez * ez);
      }
      else
      {
        depth = static_cast<float>(-ez); // the camera looks down -z: depth grows with -z
      }
    }
    keys[c] = MakeSortKey(depth, static_cast<std::uint32_t>(c));
  }
}

} // namespace

void ComputeDepthKeys(const PointsView& points,
  const CellsView& cells,
  const Matrix4& modelView,
  bool perspective,
  SortKey* keys,
  int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchMesh(points,
    cells,
    [&](const auto& mesh)
    { KeysFor(mesh, cells.cellCount, modelView, perspective, keys, nthreads); });
}

} // namespace mtpt
