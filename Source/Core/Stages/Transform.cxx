// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Transform.h"
#include "mtpt/Faults.h"

#include "detail/Parallel.h"

#include <cmath>
#include <cstdint>

namespace mtpt
{
namespace
{

template <typename PointT>
void ProjectAll(const PointT* xyz, const float* pointScalars, std::int64_t count, const Matrix4& mv,
  const Matrix4& p, ProjectedPoint* out, int threads)
{
  detail::ParallelFor(0, count, threads,
    [&](std::int64_t i)
    {
      const double x = static_cast<double>(xyz[3 * i + 0]);
      const double y = static_cast<double>(xyz[3 * i + 1]);
      const double z = static_cast<double>(xyz[3 * i + 2]);
      // Eye coordinates first, then the projection of those: the same two steps as GL.
      const double ex = mv[0] * x + mv[1] * y + mv[2] * z + mv[3];
      const double ey = mv[4] * x + mv[5] * y + mv[6] * z + mv[7];
      const double ez = mv[8] * x + mv[9] * y + mv[10] * z + mv[11];
      const double ew = mv[12] * x + mv[13] * y + mv[14] * z + mv[15];
      const double cx = p[0] * ex + p[1] * ey + p[2] * ez + p[3] * ew;
      const double cy = p[4] * ex + p[5] * ey + p[6] * ez + p[7] * ew;
      const double cz = p[8] * ex + p[9] * ey + p[10] * ez + p[11] * ew;
      const double cw = p[12] * ex + p[13] * ey + p[14] * ez + p[15] * ew;
      // The divisions are done even for unusable points (IEEE division never traps); the
      // flag below keeps them out of every cell.
      const double inverseW = 1.0 / cw;
      const double invEye = 1.0 / ew; // 1 for affine model-view matrices
      ProjectedPoint& r = out[i];
      r.x = cx * inverseW;
      r.y = cy * inverseW;
      r.z = cz * inverseW;
      r.inverseW = inverseW;
      r.eyeX = ex * invEye;
      r.eyeY = ey * invEye;
      r.eyeZ = ez * invEye;
      r.scalar = pointScalars ? pointScalars[i] : 0.0f;
      // Comparisons with NaN are false, so NaN fails every test.
      const bool bounded = cw > 0.0 && cw < CoordinateLimit && std::fabs(r.x) < CoordinateLimit &&
        std::fabs(r.y) < CoordinateLimit && std::fabs(r.z) < CoordinateLimit &&
        std::fabs(r.eyeX) < CoordinateLimit && std::fabs(r.eyeY) < CoordinateLimit &&
        std::fabs(r.eyeZ) < CoordinateLimit && std::isfinite(r.scalar);
      r.usable = bounded ? 1 : 0;
    });
}

} // namespace

void ProjectPoints(const PointsView& points, const ScalarsView& scalars, const Matrix4& modelView,
  const Matrix4& projection, ProjectedPoint* out, int threads)
{
  const float* pointScalars =
    scalars.association == ScalarsView::Association::Points ? scalars.values : nullptr;
  if (points.parts)
  {
    // Part after part, into one array: the points of part k follow those of parts 0..k-1,
    // and so do their scalars.
    std::size_t first = 0;
    for (std::size_t k = 0; k < points.partCount; ++k)
    {
      const PointsView& part = points.parts[k].points;
      const Matrix4* model = points.parts[k].model;
      ProjectPoints(part, { pointScalars ? pointScalars + first : nullptr, scalars.association },
        model ? Multiply(modelView, *model) : modelView, projection, out + first, threads);
      first += part.count;
    }
    return;
  }
  const int nthreads = detail::ResolveThreads(threads);
  const auto count = static_cast<std::int64_t>(points.count);
  if (points.type == PointsView::Type::Float32)
  {
    ProjectAll(static_cast<const float*>(points.data), pointScalars, count, modelView, projection,
      out, nthreads);
  }
  else
  {
    ProjectAll(static_cast<const double*>(points.data), pointScalars, count, modelView, projection,
      out, nthreads);
  }
}

bool TransformStage::Update(
  const Key& key, const PointsView& points, const ScalarsView& scalars, int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  AllocationPoint(AllocationSite::Transform);
  if (this->Projected.size() < points.count)
  {
    this->Projected.resize(points.count); // grow-only: frames that shrink keep the memory
  }
  ProjectPoints(points, scalars, key.modelView, key.projection, this->Projected.data(), threads);
  this->Record.Store(key);
  return true;
}

void TransformStage::Release()
{
  LargeVector<ProjectedPoint>().swap(this->Projected);
  this->Record.Forget();
}

} // namespace mtpt
