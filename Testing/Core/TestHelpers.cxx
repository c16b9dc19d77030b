// SPDX-License-Identifier: BSD-3-Clause
#include "TestHelpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace mtpt
{
namespace test
{

Matrix4 Inverse(const Matrix4& m)
{
  // Laplace expansion by 2x2 sub-determinants.
  const double s0 = m[0] * m[5] - m[4] * m[1], s1 = m[0] * m[6] - m[4] * m[2];
  const double s2 = m[0] * m[7] - m[4] * m[3], s3 = m[1] * m[6] - m[5] * m[2];
  const double s4 = m[1] * m[7] - m[5] * m[3], s5 = m[2] * m[7] - m[6] * m[3];
  const double c5 = m[10] * m[15] - m[14] * m[11], c4 = m[9] * m[15] - m[13] * m[11];
  const double c3 = m[9] * m[14] - m[13] * m[10], c2 = m[8] * m[15] - m[12] * m[11];
  const double c1 = m[8] * m[14] - m[12] * m[10], c0 = m[8] * m[13] - m[12] * m[9];
  const double det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0;
  const double k = 1.0 / det;
  return { (m[5] * c5 - m[6] * c4 + m[7] * c3) * k, (-m[1] * c5 + m[2] * c4 - m[3] * c3) * k,
    (m[13] * s5 - m[14] * s4 + m[15] * s3) * k, (-m[9] * s5 + m[10] * s4 - m[11] * s3) * k,
    (-m[4] * c5 + m[6] * c2 - m[7] * c1) * k, (m[0] * c5 - m[2] * c2 + m[3] * c1) * k,
    (-m[12] * s5 + m[14] * s2 - m[15] * s1) * k, (m[8] * s5 - m[10] * s2 + m[11] * s1) * k,
    (m[4] * c4 - m[5] * c2 + m[7] * c0) * k, (-m[0] * c4 + m[1] * c2 - m[3] * c0) * k,
    (m[12] * s4 - m[13] * s2 + m[15] * s0) * k, (-m[8] * s4 + m[9] * s2 - m[11] * s0) * k,
    (-m[4] * c3 + m[5] * c1 - m[6] * c0) * k, (m[0] * c3 - m[1] * c1 + m[2] * c0) * k,
    (-m[12] * s3 + m[13] * s1 - m[14] * s0) * k, (m[8] * s3 - m[9] * s1 + m[10] * s0) * k };
}

TetMesh LatticeTetrahedra(std::size_t cells, unsigned seed)
{
  TetMesh mesh;
  for (int i = 0; i < 27; ++i)
  {
    mesh.points.insert(
      mesh.points.end(), { float(i % 3 - 1), float(i / 3 % 3 - 1), float(i / 9 - 1) });
  }
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> coordinate(-1.5f, 1.5f);
  for (int i = 0; i < 40; ++i)
  {
    mesh.points.insert(mesh.points.end(),
      { coordinate(random), coordinate(random),
        i % 10 == 0 ? 1e-7f * coordinate(random) : coordinate(random) });
  }
  mesh.points.insert(mesh.points.end(), { NAN, 0.0f, 0.0f }); // unusable
  const auto points = static_cast<std::int64_t>(mesh.points.size() / 3);
  for (std::int64_t p = 0; p < points; ++p)
  {
    mesh.scalars.push_back(p == 5 ? NAN : 0.1f * static_cast<float>(p % 17));
  }
  std::uniform_int_distribution<std::int64_t> lattice(0, 26), any(0, points - 1);
  for (std::size_t c = 0; c < cells; ++c)
  {
    std::int64_t ids[4];
    for (auto& id : ids)
    {
      id = c % 4 == 0 ? any(random) : lattice(random);
    }
    mesh.AddTetrahedron(ids[0], ids[1], ids[2], ids[3]);
  }
  return mesh;
}

std::vector<double> TableReference(const TetMesh& mesh, const std::vector<float>& table,
  double low, double high, ReferenceSettings settings)
{
  const std::size_t n = table.size() / 4;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double scalar = low + (high - low) * static_cast<double>(i) / static_cast<double>(n - 1);
    const float* e = table.data() + 4 * i;
    settings.color.push_back({ scalar, e[0], e[1], e[2] });
    settings.opacity.push_back({ scalar, e[3] });
  }
  std::vector<double> rgb;
  std::string error;
  EXPECT_TRUE(RenderReference(mesh.Points(), mesh.Cells(),
    { mesh.scalars.data(), ScalarsView::Association::Points }, settings, rgb, 2, &error))
    << error;
  return rgb;
}

TetMesh JitteredGrid(int n, unsigned seed)
{
  TetMesh mesh;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double h = 2.0 / n;
  for (int k = 0; k <= n; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        const bool interior = i > 0 && j > 0 && k > 0 && i < n && j < n && k < n;
        const double x = -1 + h * (i + (interior ? jitter(random) : 0));
        const double y = -1 + h * (j + (interior ? jitter(random) : 0));
        const double z = -1 + h * (k + (interior ? jitter(random) : 0));
        mesh.points.insert(mesh.points.end(),
          { static_cast<float>(x), static_cast<float>(y), static_cast<float>(z) });
        mesh.scalars.push_back(static_cast<float>(std::sin(2 * x) + std::cos(3 * y) + z * z));
      }
    }
  }
  const int cubes[3] = { n, n, n };
  AddKuhnTetrahedra(cubes, 0,
    [&mesh](std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d)
    { mesh.AddTetrahedron(a, b, c, d); });
  return mesh;
}

void AddKuhnTetrahedra(const int n[3], std::int64_t base,
  const std::function<void(std::int64_t, std::int64_t, std::int64_t, std::int64_t)>& add)
{
  auto id = [&](const int c[3])
  { return base + static_cast<std::int64_t>((c[2] * (n[1] + 1) + c[1]) * (n[0] + 1) + c[0]); };
  // The 6 paths from corner 000 to 111, always conforming across cubes.
  static const int paths[6][3] = { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 }, { 1, 2, 0 }, { 2, 0, 1 },
    { 2, 1, 0 } };
  for (int k = 0; k < n[2]; ++k)
  {
    for (int j = 0; j < n[1]; ++j)
    {
      for (int i = 0; i < n[0]; ++i)
      {
        for (const auto& path : paths)
        {
          int c[3] = { i, j, k };
          std::int64_t v[4];
          v[0] = id(c);
          for (int s = 0; s < 3; ++s)
          {
            ++c[path[s]];
            v[s + 1] = id(c);
          }
          add(v[0], v[1], v[2], v[3]);
        }
      }
    }
  }
}

double ChordLength(
  const Vec3 p[4], const Vec3& origin, const Vec3& direction, double* tEnter, double* tExit)
{
  double t0 = -std::numeric_limits<double>::infinity();
  double t1 = std::numeric_limits<double>::infinity();
  static const int faces[4][4] = { { 1, 2, 3, 0 }, { 0, 2, 3, 1 }, { 0, 1, 3, 2 }, { 0, 1, 2, 3 } };
  for (const auto& f : faces)
  {
    Vec3 normal = Cross(Sub(p[f[1]], p[f[0]]), Sub(p[f[2]], p[f[0]]));
    // Orient the normal away from the opposite vertex: inside is Dot(normal, x - p) <= 0.
    if (Dot(normal, Sub(p[f[3]], p[f[0]])) > 0)
    {
      normal = { -normal[0], -normal[1], -normal[2] };
    }
    const double start = Dot(normal, Sub(origin, p[f[0]]));
    const double rate = Dot(normal, direction);
    if (rate == 0)
    {
      if (start > 0)
      {
        return 0;
      }
      continue;
    }
    const double t = -start / rate;
    if (rate > 0)
    {
      t1 = std::min(t1, t);
    }
    else
    {
      t0 = std::max(t0, t);
    }
  }
  if (!(t1 > t0))
  {
    return 0;
  }
  if (tEnter)
  {
    *tEnter = t0;
  }
  if (tExit)
  {
    *tExit = t1;
  }
  return (t1 - t0) * std::sqrt(Dot(direction, direction));
}

} // namespace test
} // namespace mtpt
