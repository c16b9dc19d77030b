// SPDX-License-Identifier: BSD-3-Clause
// Shared helpers of the core tests: cameras, a small jittered tetrahedral grid, and an
// independent ray/tetrahedron intersection used as ground truth.
#ifndef mtpt_TestHelpers_h
#define mtpt_TestHelpers_h

#include "mtpt/MeshView.h"
#include "mtpt/ReferenceRenderer.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

namespace mtpt
{
namespace test
{

using Vec3 = std::array<double, 3>;

inline Vec3 Sub(const Vec3& a, const Vec3& b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}
inline double Dot(const Vec3& a, const Vec3& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline Vec3 Cross(const Vec3& a, const Vec3& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}
inline Vec3 Normalized(const Vec3& a)
{
  const double n = std::sqrt(Dot(a, a));
  return { a[0] / n, a[1] / n, a[2] / n };
}

/// gluLookAt-style view matrix (row-major, column vectors).
inline Matrix4 LookAt(const Vec3& eye, const Vec3& target, const Vec3& up)
{
  const Vec3 f = Normalized(Sub(target, eye));
  const Vec3 s = Normalized(Cross(f, up));
  const Vec3 u = Cross(s, f);
  return { s[0], s[1], s[2], -Dot(s, eye), u[0], u[1], u[2], -Dot(u, eye), -f[0], -f[1], -f[2],
    Dot(f, eye), 0, 0, 0, 1 };
}

/// glOrtho.
inline Matrix4 Ortho(double l, double r, double b, double t, double n, double f)
{
  return { 2 / (r - l), 0, 0, -(r + l) / (r - l), 0, 2 / (t - b), 0, -(t + b) / (t - b), 0, 0,
    -2 / (f - n), -(f + n) / (f - n), 0, 0, 0, 1 };
}

/// gluPerspective (vertical field of view in degrees).
inline Matrix4 Perspective(double fovyDegrees, double aspect, double n, double f)
{
  const double c = 1.0 / std::tan(fovyDegrees * M_PI / 360.0);
  return { c / aspect, 0, 0, 0, 0, c, 0, 0, 0, 0, (f + n) / (n - f), 2 * f * n / (n - f), 0, 0, -1,
    0 };
}

inline Matrix4 Scale(double sx, double sy, double sz)
{
  return { sx, 0, 0, 0, 0, sy, 0, 0, 0, 0, sz, 0, 0, 0, 0, 1 };
}

inline Vec3 Apply(const Matrix4& m, const Vec3& p, double* wOut = nullptr)
{
  const double x = m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3];
  const double y = m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7];
  const double z = m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11];
  const double w = m[12] * p[0] + m[13] * p[1] + m[14] * p[2] + m[15];
  if (wOut)
  {
    *wOut = w;
  }
  return { x / w, y / w, z / w };
}

/// General 4x4 inverse (cofactors), for unprojecting test rays.
Matrix4 Inverse(const Matrix4& m);

/// A tetrahedral mesh in vtkCellArray layout.
struct TetMesh
{
  std::vector<float> points; // xyz
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets{ 0 };
  std::vector<float> scalars; // per point

  std::size_t CellCount() const { return offsets.size() - 1; }
  void AddTetrahedron(std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d)
  {
    connectivity.insert(connectivity.end(), { a, b, c, d });
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  PointsView Points() const { return PointsView::FromFloat(points.data(), points.size() / 3); }
  CellsView Cells() const
  {
    return CellsView::FromInt64(connectivity.data(), offsets.data(), CellCount());
  }
};

/// A tetrahedral mesh with double-precision points (so tests can move it 1e7 from the
/// origin), point or cell scalars.
struct DoubleMesh
{
  std::vector<double> points; // xyz
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets{ 0 };
  std::vector<float> scalars;
  bool cellScalars = false;

  DoubleMesh() = default;
  explicit DoubleMesh(const TetMesh& m)
    : points(m.points.begin(), m.points.end())
    , connectivity(m.connectivity)
    , offsets(m.offsets)
    , scalars(m.scalars)
  {
  }
  std::int64_t AddPoint(double x, double y, double z, float s = 0)
  {
    points.insert(points.end(), { x, y, z });
    if (!cellScalars)
    {
      scalars.push_back(s);
    }
    return static_cast<std::int64_t>(points.size() / 3 - 1);
  }
  void AddTetrahedron(std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d)
  {
    connectivity.insert(connectivity.end(), { a, b, c, d });
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  std::size_t CellCount() const { return offsets.size() - 1; }
  /// Every point p becomes scale * p + offset.
  void Transform(double scale, const Vec3& offset)
  {
    for (std::size_t i = 0; i < points.size(); ++i)
    {
      points[i] = points[i] * scale + offset[i % 3];
    }
  }
  PointsView Points() const { return PointsView::FromDouble(points.data(), points.size() / 3); }
  CellsView Cells() const
  {
    return CellsView::FromInt64(connectivity.data(), offsets.data(), CellCount());
  }
  ScalarsView Scalars() const
  {
    return { scalars.data(),
      cellScalars ? ScalarsView::Association::Cells : ScalarsView::Association::Points };
  }
};

/// Kuhn split of a lattice of n[0] x n[1] x n[2] cubes into 6 tetrahedra each (conforming
/// across cubes): calls add(a, b, c, d) with point ids base + (k (n1 + 1) + j)(n0 + 1) + i.
void AddKuhnTetrahedra(const int n[3], std::int64_t base,
  const std::function<void(std::int64_t, std::int64_t, std::int64_t, std::int64_t)>& add);

/// n^3 cubes in [-1, 1]^3, each split into 6 tetrahedra (Kuhn), interior points jittered,
/// a smooth scalar field. Deterministic for a given seed.
TetMesh JitteredGrid(int n, unsigned seed);

/// The oblique view of the tests that split or reduce segments, for a mesh in [-1, 1]^3:
/// sets the matrices of a FrameInput-like `input` (modelView, projection, perspective).
template <typename Input>
void ObliqueView(Input& input, bool perspective)
{
  input.modelView = LookAt({ 1.2, 1.5, 3.5 }, { 0, 0, 0 }, { 0, 1, 0 });
  input.projection =
    perspective ? Perspective(45, 1.2, 1.5, 6) : Ortho(-1.8, 1.8, -1.5, 1.5, 1.5, 6);
  input.perspective = perspective;
}

/**
 * The exact reference image (RGB over black) of `mesh` with its point scalars and `settings`,
 * the transfer functions' nodes the entries of `table` (RGBA, 4 floats each) evenly over
 * [low, high], as a TransferFunctionTable spans them. A failure is a gtest failure.
 */
std::vector<double> TableReference(const TetMesh& mesh, const std::vector<float>& table,
  double low, double high, ReferenceSettings settings);

/// Random tetrahedra whose corners are drawn from a 3x3x3 lattice in [-1, 1]^3 (projected by
/// an axis-aligned view, its points coincide and line up: every projection class and every
/// zero-band case occurs) and, for every fourth cell, from 40 random points (some nearly
/// coplanar) and one unusable (NaN) point. Point 5 has a NaN scalar. Deterministic per seed.
TetMesh LatticeTetrahedra(std::size_t cells, unsigned seed);

/// Length of the intersection of the line origin + t * direction (all t) with the
/// tetrahedron p[0..3]; 0 if it misses. Ground truth computed in double by clipping the
/// line against the four face planes.
double ChordLength(
  const Vec3 p[4], const Vec3& origin, const Vec3& direction, double* tEnter, double* tExit);

} // namespace test
} // namespace mtpt

#endif
