// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Gradients.h"

#include "mtpt/Lighting.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace mtpt
{
namespace
{

/// The model coordinates of every point, as doubles (a mesh of parts part after part).
std::vector<double> ModelCoordinates(const PointsView& points)
{
  std::vector<double> xyz(3 * points.count);
  std::size_t first = 0;
  for (std::size_t k = 0; k < (points.parts ? points.partCount : 1); ++k)
  {
    const PointsView& part = points.parts ? points.parts[k].points : points;
    for (std::size_t i = 0; i < 3 * part.count; ++i)
    {
      xyz[3 * first + i] = part.type == PointsView::Type::Float32
        ? static_cast<const float*>(part.data)[i]
        : static_cast<const double*>(part.data)[i];
    }
    first += part.count;
  }
  return xyz;
}

/**
 * A tetrahedron's volume times its gradient (weighted[0..2]) and its volume (weighted[3]):
 * with edges e_k = p_k - p_0 and differences d_k = s_k - s_0, the gradient is
 * (d_1 e_2 x e_3 + d_2 e_3 x e_1 + d_3 e_1 x e_2) / det and the volume |det| / 6, so no
 * division is needed. False (nothing counts) for a flat or non-finite cell.
 */
bool WeightedGradient(
  const double* xyz, const float* scalars, const std::int64_t ids[4], double weighted[4])
{
  double e[3][3], d[3];
  const double* p0 = xyz + 3 * ids[0];
  for (int k = 0; k < 3; ++k)
  {
    const double* p = xyz + 3 * ids[k + 1];
    for (int c = 0; c < 3; ++c)
    {
      e[k][c] = p[c] - p0[c];
    }
    d[k] = static_cast<double>(scalars[ids[k + 1]]) - scalars[ids[0]];
  }
  double c23[3], c31[3], c12[3];
  Cross3(e[1], e[2], c23);
  Cross3(e[2], e[0], c31);
  Cross3(e[0], e[1], c12);
  const double det = Dot3(e[0], c23);
  if (!(det != 0) || !std::isfinite(det))
  {
    return false;
  }
  const double sign = det > 0 ? 1.0 : -1.0;
  for (int c = 0; c < 3; ++c)
  {
    weighted[c] = sign / 6.0 * (d[0] * c23[c] + d[1] * c31[c] + d[2] * c12[c]);
  }
  weighted[3] = std::fabs(det) / 6.0;
  return std::isfinite(weighted[0]) && std::isfinite(weighted[1]) && std::isfinite(weighted[2]);
}

} // namespace

void PointGradients(const PointsView& points, const CellsView& cells, const ScalarsView& scalars,
  std::vector<float>& gradients, int threads)
{
  gradients.assign(3 * points.count, 0.0f);
  if (!scalars.values || scalars.association != ScalarsView::Association::Points)
  {
    return;
  }
  const std::vector<double> xyz = ModelCoordinates(points);
  const std::size_t cellCount = cells.cellCount;
  // Each cell's weighted gradient in parallel; the sums per point in cell order, so that the
  // result does not depend on the thread count.
  std::vector<double> weighted(4 * cellCount, 0.0);
  std::vector<std::int64_t> ids(4 * cellCount, -1);
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(cells, points.count,
    [&](const auto& access)
    {
      const auto count = static_cast<std::int64_t>(cellCount);
      detail::ParallelFor(0, count, nthreads,
        [&](std::int64_t c)
        {
          std::int64_t* cellIds = ids.data() + 4 * c;
          if (!access.TetrahedronPoints(static_cast<std::size_t>(c), cellIds) ||
            !WeightedGradient(xyz.data(), scalars.values, cellIds, weighted.data() + 4 * c))
          {
            cellIds[0] = -1;
          }
        });
    });
  std::vector<double> sums(4 * points.count, 0.0);
  for (std::size_t c = 0; c < cellCount; ++c)
  {
    if (ids[4 * c] < 0)
    {
      continue;
    }
    for (int i = 0; i < 4; ++i)
    {
      double* sum = sums.data() + 4 * ids[4 * c + i];
      for (int k = 0; k < 4; ++k)
      {
        sum[k] += weighted[4 * c + k];
      }
    }
  }
  for (std::size_t p = 0; p < points.count; ++p)
  {
    const double* sum = sums.data() + 4 * p;
    if (!(sum[3] > 0))
    {
      continue;
    }
    const double g[3] = { sum[0] / sum[3], sum[1] / sum[3], sum[2] / sum[3] };
    // Beyond float's range (cells far smaller than their scalar steps) the direction is kept
    // at a magnitude of 1e30: shading reads only the direction.
    const double largest = std::max({ std::fabs(g[0]), std::fabs(g[1]), std::fabs(g[2]) });
    const double scale = largest > 1e30 && std::isfinite(largest) ? 1e30 / largest : 1.0;
    for (int k = 0; k < 3; ++k)
    {
      const double v = g[k] * scale;
      gradients[3 * p + k] = std::isfinite(v) ? static_cast<float>(v) : 0.0f;
    }
  }
}

void CellNormals(const CellsView& cells, std::size_t pointCount,
  const std::vector<float>& gradients, std::vector<float>& normals, int threads)
{
  normals.assign(3 * cells.cellCount, 0.0f);
  if (gradients.size() < 3 * pointCount)
  {
    return;
  }
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      const auto count = static_cast<std::int64_t>(cells.cellCount);
      detail::ParallelFor(0, count, nthreads,
        [&](std::int64_t c)
        {
          std::int64_t ids[4];
          if (!access.TetrahedronPoints(static_cast<std::size_t>(c), ids))
          {
            return;
          }
          double mean[3] = { 0, 0, 0 };
          for (int i = 0; i < 4; ++i)
          {
            for (int k = 0; k < 3; ++k)
            {
              mean[k] += gradients[3 * ids[i] + k];
            }
          }
          if (Normalize3(mean))
          {
            for (int k = 0; k < 3; ++k)
            {
              normals[3 * c + k] = static_cast<float>(mean[k]);
            }
          }
        });
    });
}

} // namespace mtpt
