// SPDX-License-Identifier: BSD-3-Clause
/**
 * Camera matrices for the benchmarks that drive the core without VTK (mtpt_bench_core,
 * mtpt_bench_compositor): gluLookAt, glOrtho, glFrustum and gluPerspective, row-major with
 * column vectors as MeshView.h takes them.
 */
#ifndef MTPT_BENCH_CAMERA_H
#define MTPT_BENCH_CAMERA_H

#include "mtpt/MeshView.h"

#include <array>
#include <cmath>

namespace mtpt
{
namespace bench
{

using Vec3 = std::array<double, 3>;

inline Vec3 Normalized(const Vec3& v)
{
  const double length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return { v[0] / length, v[1] / length, v[2] / length };
}

inline Vec3 Cross(const Vec3& a, const Vec3& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}

inline double Dot(const Vec3& a, const Vec3& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// gluLookAt: the eye at `eye` looking at `centre`, `up` upwards.
inline Matrix4 LookAt(const Vec3& eye, const Vec3& centre, const Vec3& up)
{
  const Vec3 forward = Normalized({ centre[0] - eye[0], centre[1] - eye[1], centre[2] - eye[2] });
  const Vec3 side = Normalized(Cross(forward, up));
  const Vec3 trueUp = Cross(side, forward);
  return { side[0], side[1], side[2], -Dot(side, eye), trueUp[0], trueUp[1], trueUp[2],
    -Dot(trueUp, eye), -forward[0], -forward[1], -forward[2], Dot(forward, eye), 0, 0, 0, 1 };
}

/// glOrtho.
inline Matrix4 Ortho(double left, double right, double bottom, double top, double zNear,
  double zFar)
{
  Matrix4 m{};
  m[0] = 2 / (right - left);
  m[3] = -(right + left) / (right - left);
  m[5] = 2 / (top - bottom);
  m[7] = -(top + bottom) / (top - bottom);
  m[10] = -2 / (zFar - zNear);
  m[11] = -(zFar + zNear) / (zFar - zNear);
  m[15] = 1;
  return m;
}

/// glFrustum.
inline Matrix4 Frustum(double left, double right, double bottom, double top, double zNear,
  double zFar)
{
  Matrix4 m{};
  m[0] = 2 * zNear / (right - left);
  m[2] = (right + left) / (right - left);
  m[5] = 2 * zNear / (top - bottom);
  m[6] = (top + bottom) / (top - bottom);
  m[10] = -(zFar + zNear) / (zFar - zNear);
  m[11] = -2 * zFar * zNear / (zFar - zNear);
  m[14] = -1;
  return m;
}

/// gluPerspective: vertical field of view in degrees, width / height.
inline Matrix4 Perspective(double fovyDegrees, double aspect, double zNear, double zFar)
{
  const double top = zNear * std::tan(0.5 * fovyDegrees * 3.14159265358979323846 / 180.0);
  return Frustum(-top * aspect, top * aspect, -top, top, zNear, zFar);
}

} // namespace bench
} // namespace mtpt

#endif
