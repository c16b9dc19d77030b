// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Transform.h"

#include "detail/Parallel.h"

#include <cstdint>

namespace mtpt
{
namespace
{

template<typename PointT>
void TransformPoints(const PointT* xyz,
  std::int64_t count,
  const Matrix4& m,
  NdcPoint* out,
  int threads)
{
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t i = 0; i < count; ++i)
  {
    const double x = static_cast<double>(xyz[3 * i + 0]);
    const double y = static_cast<double>(xyz[3 * i + 1]);
    const double z = static_cast<double>(xyz[3 * i + 2]);
    const double cx = m[0] * x + m[1] * y + m[2] * z + m[3];
    const double cy = m[4] * x + m[5] * y + m[6] * z + m[7];
    const double cz = m[8] * x + m[9] * y + m[10] * z + m[11];
    const double cw = m[12] * x + m[13] * y + m[14] * z + m[15];
    // The division is done even for w <= 0: decomposition rejects those points by w, and
    // IEEE division never traps, so there is no branch in this loop.
    const double inv = 1.0 / cw;
    out[i] = NdcPoint{ cx * inv, cy * inv, cz * inv, cw };
  }
}

} // namespace

void TransformToNDC(const PointsView& points,
  const Matrix4& modelViewProjection,
  NdcPoint* out,
  int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto count = static_cast<std::int64_t>(points.count);
  if (points.type == PointsView::Type::Float32)
  {
    TransformPoints(
      static_cast<const float*>(points.data), count, modelViewProjection, out, nthreads);
  }
  else
  {
    TransformPoints(
      static_cast<const double*>(points.data), count, modelViewProjection, out, nthreads);
  }
}

} // namespace mtpt
