// SPDX-License-Identifier: BSD-3-Clause
// The accuracy reference (mtpt/ReferenceRenderer.h) against closed forms of the
// emission-absorption integral, against itself on refined meshes, and for determinism.
#include "TestHelpers.h"

#include "mtpt/ReferenceRenderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

namespace
{

using mtpt::ColorNode;
using mtpt::Matrix4;
using mtpt::OpacityNode;
using mtpt::ReferenceSettings;
using mtpt::test::Vec3;

using Mesh = mtpt::test::DoubleMesh;

/// A box [x0, x1] x [y0, y1] x [z0, z1] of nx * ny * nz cubes, 6 tetrahedra each (Kuhn),
/// point scalars from `field`. Appends to `mesh`.
void AddBox(Mesh& mesh, const double lo[3], const double hi[3], const int n[3],
  const std::function<double(double, double, double)>& field)
{
  const std::int64_t base = static_cast<std::int64_t>(mesh.points.size() / 3);
  for (int k = 0; k <= n[2]; ++k)
  {
    for (int j = 0; j <= n[1]; ++j)
    {
      for (int i = 0; i <= n[0]; ++i)
      {
        const double x = lo[0] + (hi[0] - lo[0]) * i / n[0];
        const double y = lo[1] + (hi[1] - lo[1]) * j / n[1];
        const double z = lo[2] + (hi[2] - lo[2]) * k / n[2];
        mesh.AddPoint(x, y, z, static_cast<float>(field(x, y, z)));
      }
    }
  }
  mtpt::test::AddKuhnTetrahedra(n, base,
    [&mesh](std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d)
    { mesh.AddTetrahedron(a, b, c, d); });
}

/// Each tetrahedron split into 8 at its edge midpoints (point scalars averaged: the same
/// piecewise-linear field when the averages are exact, as they are for dyadic values).
Mesh Refine(const Mesh& in)
{
  Mesh out;
  out.points = in.points;
  out.scalars = in.scalars;
  for (std::size_t c = 0; c < in.CellCount(); ++c)
  {
    const std::int64_t* v = in.connectivity.data() + in.offsets[c];
    std::int64_t m[4][4];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = a + 1; b < 4; ++b)
      {
        const double* p = in.points.data();
        m[a][b] = m[b][a] = out.AddPoint(0.5 * (p[3 * v[a]] + p[3 * v[b]]),
          0.5 * (p[3 * v[a] + 1] + p[3 * v[b] + 1]), 0.5 * (p[3 * v[a] + 2] + p[3 * v[b] + 2]),
          0.5f * (in.scalars[v[a]] + in.scalars[v[b]]));
      }
    }
    out.AddTetrahedron(v[0], m[0][1], m[0][2], m[0][3]);
    out.AddTetrahedron(v[1], m[0][1], m[1][2], m[1][3]);
    out.AddTetrahedron(v[2], m[0][2], m[1][2], m[2][3]);
    out.AddTetrahedron(v[3], m[0][3], m[1][3], m[2][3]);
    // The inner octahedron, split along the diagonal m02-m13.
    out.AddTetrahedron(m[0][2], m[1][3], m[0][1], m[1][2]);
    out.AddTetrahedron(m[0][2], m[1][3], m[1][2], m[2][3]);
    out.AddTetrahedron(m[0][2], m[1][3], m[2][3], m[0][3]);
    out.AddTetrahedron(m[0][2], m[1][3], m[0][3], m[0][1]);
  }
  return out;
}

std::vector<double> Render(const Mesh& mesh, const ReferenceSettings& settings, int threads = 2,
  std::size_t* segments = nullptr)
{
  std::vector<double> rgb;
  std::string error;
  mtpt::ReferenceStats stats;
  EXPECT_TRUE(mtpt::RenderReference(
    mesh.Points(), mesh.Cells(), mesh.Scalars(), settings, rgb, threads, &error, &stats))
    << error;
  if (segments)
  {
    *segments = stats.segments;
  }
  return rgb;
}

/// Window point of pixel (x, y) as the reference samples it, mapped to [l, r] x [b, t].
void SamplePoint(int x, int y, int width, int height, double l, double r, double b, double t,
  double& px, double& py)
{
  px = l + (r - l) * (x + 0.5 + mtpt::PixelOffsetX) / width;
  py = b + (t - b) * (y + 0.5 + mtpt::PixelOffsetY) / height;
}

const double Background[3] = { 0.1, 0.2, 0.3 };

ReferenceSettings OrthoDownZ(int size, double l, double r, double b, double t)
{
  ReferenceSettings s;
  s.width = s.height = size;
  // Camera at z = 10 looking down -z: eye z = model z - 10.
  s.modelView = mtpt::test::LookAt({ 0, 0, 10 }, { 0, 0, 0 }, { 0, 1, 0 });
  s.projection = mtpt::test::Ortho(l, r, b, t, 1, 30);
  for (int k = 0; k < 3; ++k)
  {
    s.background[k] = Background[k];
  }
  return s;
}

} // namespace

TEST(ReferenceRenderer, ConstantTetrahedronMatchesClosedForm)
{
  // Base triangle at z = -1, apex at the origin: the ray at (x, y) crosses the cell from
  // z = -(x + y) to z = -1, a length of 1 - x - y.
  Mesh mesh;
  mesh.cellScalars = true;
  mesh.AddPoint(0, 0, -1);
  mesh.AddPoint(1, 0, -1);
  mesh.AddPoint(0, 1, -1);
  mesh.AddPoint(0, 0, 0);
  mesh.AddTetrahedron(0, 1, 2, 3);
  mesh.scalars = { 0.5f };
  ReferenceSettings s = OrthoDownZ(40, -0.25, 1.25, -0.25, 1.25);
  s.color = { { 0, 0.9, 0.5, 0.1 } };
  s.opacity = { { 0, 3.0 } };
  s.unitDistance = 0.5; // tau = 6
  const auto image = Render(mesh, s);
  int inside = 0;
  double worst = 0;
  for (int y = 0; y < s.height; ++y)
  {
    for (int x = 0; x < s.width; ++x)
    {
      double px, py;
      SamplePoint(x, y, s.width, s.height, -0.25, 1.25, -0.25, 1.25, px, py);
      const bool hit = px > 0 && py > 0 && px + py < 1;
      inside += hit ? 1 : 0;
      const double length = hit ? 1 - px - py : 0;
      const double transmittance = std::exp(-6.0 * length);
      const double colour[3] = { 0.9, 0.5, 0.1 };
      for (int k = 0; k < 3; ++k)
      {
        const double expected = colour[k] * (1 - transmittance) + Background[k] * transmittance;
        worst = std::max(worst, std::fabs(image[3 * (y * s.width + x) + k] - expected));
      }
    }
  }
  EXPECT_GT(inside, 300);
  EXPECT_LT(worst, 1e-12);
}

TEST(ReferenceRenderer, LinearSlabMatchesClosedForm)
{
  // Slab z in [0, h], scalar s = 1 - z / h (0 at the front face), opacity k * s, colour
  // c0 + (c1 - c0) s. With a = k h / unitDistance and v the depth fraction:
  //   I = integral_0^1 c(v) a v exp(-a v^2 / 2) dv + bg exp(-a / 2)
  //     = c0 (1 - e) + (c1 - c0) (-e + sqrt(pi / (2a)) erf(sqrt(a / 2))) + bg e,  e = exp(-a/2).
  const double h = 0.75, k = 2.0, unit = 0.4;
  Mesh mesh;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, h };
  const int n[3] = { 3, 2, 4 };
  AddBox(mesh, lo, hi, n, [h](double, double, double z) { return 1 - z / h; });
  ReferenceSettings s = OrthoDownZ(32, -0.1, 1.1, -0.1, 1.1);
  const double c0[3] = { 0.2, 0.9, 0.4 }, c1[3] = { 1.0, 0.1, 0.6 };
  s.color = { { 0, c0[0], c0[1], c0[2] }, { 1, c1[0], c1[1], c1[2] } };
  s.opacity = { { 0, 0 }, { 1, k } };
  s.unitDistance = unit;
  const auto image = Render(mesh, s);
  const double a = k * h / unit, e = std::exp(-a / 2);
  const double ramp = -e + std::sqrt(M_PI / (2 * a)) * std::erf(std::sqrt(a / 2));
  double worst = 0;
  int inside = 0;
  for (int y = 0; y < s.height; ++y)
  {
    for (int x = 0; x < s.width; ++x)
    {
      double px, py;
      SamplePoint(x, y, s.width, s.height, -0.1, 1.1, -0.1, 1.1, px, py);
      const bool hit = px > 0 && px < 1 && py > 0 && py < 1;
      inside += hit ? 1 : 0;
      for (int c = 0; c < 3; ++c)
      {
        const double expected =
          hit ? c0[c] * (1 - e) + (c1[c] - c0[c]) * ramp + Background[c] * e : Background[c];
        worst = std::max(worst, std::fabs(image[3 * (y * s.width + x) + c] - expected));
      }
    }
  }
  EXPECT_GT(inside, 500);
  EXPECT_LT(worst, 1e-12);
}

TEST(ReferenceRenderer, NarrowOpacityPeakIsCapturedExactly)
{
  // Vertex scalars 0 and 1 only; the opacity is a peak of base width 1e-3 at s = 0.5 that
  // no vertex value samples. Its optical depth is 0.5 * 1e-3 * peak * h / unitDistance.
  const double h = 1.0, peak = 400.0, unit = 0.5;
  Mesh mesh;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, h };
  const int n[3] = { 2, 2, 1 };
  AddBox(mesh, lo, hi, n, [h](double, double, double z) { return 1 - z / h; });
  ReferenceSettings s = OrthoDownZ(16, 0.05, 0.95, 0.05, 0.95); // every ray inside
  s.color = { { 0, 0.3, 0.6, 0.9 } };
  s.opacity = { { 0, 0 }, { 0.4995, 0 }, { 0.5, peak }, { 0.5005, 0 }, { 1, 0 } };
  s.unitDistance = unit;
  const auto image = Render(mesh, s);
  const double depth = 0.5 * 1e-3 * peak * h / unit, e = std::exp(-depth);
  const double colour[3] = { 0.3, 0.6, 0.9 };
  double worst = 0;
  for (std::size_t p = 0; p < image.size() / 3; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      worst =
        std::max(worst, std::fabs(image[3 * p + c] - (colour[c] * (1 - e) + Background[c] * e)));
    }
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(ReferenceRenderer, RefinedMeshGivesTheSameImage)
{
  // A jittered grid (dyadic coordinates and scalars, so midpoints are exact) seen in
  // perspective from an oblique direction, with a transfer function that has a narrow
  // peak: splitting every cell into 8 leaves the piecewise-linear field, hence the image,
  // unchanged.
  Mesh mesh;
  const double lo[3] = { -1, -1, -1 }, hi[3] = { 1, 1, 1 };
  const int n[3] = { 4, 4, 4 };
  AddBox(mesh, lo, hi, n,
    [](double x, double y, double z)
    { return std::round(256 * (0.5 + 0.3 * x * y - 0.2 * z)) / 256; });
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
  {
    const double v = mesh.points[i];
    if (std::fabs(v) < 1)
    {
      mesh.points[i] = v + std::ldexp(static_cast<double>((i * 7919) % 64) - 32, -9);
    }
  }
  const Mesh refined = Refine(mesh);
  ASSERT_EQ(refined.CellCount(), 8 * mesh.CellCount());
  ReferenceSettings s;
  s.width = s.height = 48;
  s.modelView = mtpt::test::LookAt({ 2.5, 1.8, 3.2 }, { 0, 0, 0 }, { 0, 1, 0 });
  s.projection = mtpt::test::Perspective(40, 1, 0.5, 20);
  s.color = { { 0, 0.1, 0.2, 0.9 }, { 0.5, 0.9, 0.9, 0.2 }, { 1, 0.9, 0.1, 0.1 } };
  s.opacity = { { 0, 0.1 }, { 0.45, 0.3 }, { 0.452, 30 }, { 0.454, 0.3 }, { 1, 1.5 } };
  s.unitDistance = 0.3;
  std::size_t coarseSegments = 0, fineSegments = 0;
  const auto coarse = Render(mesh, s, 2, &coarseSegments);
  const auto fine = Render(refined, s, 2, &fineSegments);
  EXPECT_GT(fineSegments, 2 * coarseSegments);
  const mtpt::ImageError error = mtpt::CompareImages(coarse.data(), fine.data(), coarse.size() / 3);
  EXPECT_LT(error.maxAbs, 1e-9);
  // Not a blank image: most rays cross the grid and see the volume.
  double covered = 0;
  for (std::size_t p = 0; p < coarse.size() / 3; ++p)
  {
    covered += std::fabs(coarse[3 * p] - s.background[0]) > 0.05 ? 1 : 0;
  }
  EXPECT_GT(covered / (coarse.size() / 3), 0.3);
}

TEST(ReferenceRenderer, SeparateBlocksAreCompositedInDepthOrder)
{
  // Two blocks with constant cell scalars, B behind A and shifted in x, cells of B listed
  // first. Rays through both see A over B over the background.
  Mesh mesh;
  mesh.cellScalars = true;
  const int n[3] = { 2, 2, 2 };
  const double loB[3] = { 0.5, 0, -3 }, hiB[3] = { 1.5, 1, -2 };
  AddBox(mesh, loB, hiB, n, [](double, double, double) { return 0; });
  const std::size_t cellsB = mesh.CellCount();
  const double loA[3] = { 0, 0, 0 }, hiA[3] = { 1, 1, 1 };
  AddBox(mesh, loA, hiA, n, [](double, double, double) { return 0; });
  mesh.scalars.assign(mesh.CellCount(), 0.2f);
  for (std::size_t c = 0; c < cellsB; ++c)
  {
    mesh.scalars[c] = 0.8f;
  }
  ReferenceSettings s = OrthoDownZ(40, -0.25, 1.75, -0.5, 1.5);
  s.color = { { 0, 1, 0, 0 }, { 1, 0, 0, 1 } };
  s.opacity = { { 0, 0.5 }, { 1, 2.0 } };
  s.unitDistance = 1.0;
  const auto image = Render(mesh, s);
  auto colourAt = [](double sv, double out[3])
  {
    out[0] = 1 - sv;
    out[1] = 0;
    out[2] = sv;
  };
  double ca[3], cb[3];
  colourAt(0.2f, ca);
  colourAt(0.8f, cb);
  const double ta = std::exp(-(0.5 + 1.5 * 0.2f)), tb = std::exp(-(0.5 + 1.5 * 0.8f));
  double worst = 0;
  int both = 0;
  for (int y = 0; y < s.height; ++y)
  {
    for (int x = 0; x < s.width; ++x)
    {
      double px, py;
      SamplePoint(x, y, s.width, s.height, -0.25, 1.75, -0.5, 1.5, px, py);
      const bool inY = py > 0 && py < 1;
      const bool inA = inY && px > 0 && px < 1, inB = inY && px > 0.5 && px < 1.5;
      both += inA && inB ? 1 : 0;
      for (int c = 0; c < 3; ++c)
      {
        double value = Background[c];
        if (inB)
        {
          value = cb[c] * (1 - tb) + tb * value;
        }
        if (inA)
        {
          value = ca[c] * (1 - ta) + ta * value;
        }
        worst = std::max(worst, std::fabs(image[3 * (y * s.width + x) + c] - value));
      }
    }
  }
  EXPECT_GT(both, 100);
  EXPECT_LT(worst, 1e-12);
}

TEST(ReferenceRenderer, PerspectivePathLengthsAndNearPlane)
{
  // A constant slab z in [-1, 0] seen from the origin's side: each perspective ray crosses
  // it over its thickness times |d| / |d_z| (d its eye-space direction); orthographic rays
  // over the thickness; and a near plane inside the slab cuts the path to the part behind
  // it.
  Mesh mesh;
  mesh.cellScalars = true;
  const double lo[3] = { -4, -4, -1 }, hi[3] = { 4, 4, 0 };
  const int n[3] = { 4, 4, 2 };
  AddBox(mesh, lo, hi, n, [](double, double, double) { return 0; });
  mesh.scalars.assign(mesh.CellCount(), 0.0f);
  const double tau = 1.3, colour[3] = { 0.7, 0.4, 0.2 };
  auto expect = [&](double length, int c)
  {
    const double t = std::exp(-tau * length);
    return colour[c] * (1 - t) + Background[c] * t;
  };
  ReferenceSettings s;
  s.width = 24;
  s.height = 16;
  s.color = { { 0, colour[0], colour[1], colour[2] } };
  s.opacity = { { 0, tau } };
  for (int k = 0; k < 3; ++k)
  {
    s.background[k] = Background[k];
  }
  s.modelView = mtpt::test::LookAt({ 0, 0, 2 }, { 0, 0, 0 }, { 0, 1, 0 }); // slab at eye z -3..-2
  const double fovy = 50, aspect = 24.0 / 16.0, t = std::tan(fovy * M_PI / 360);
  s.projection = mtpt::test::Perspective(fovy, aspect, 0.5, 10);
  const auto perspective = Render(mesh, s);
  s.projection = mtpt::test::Ortho(-3, 3, -2, 2, 0.5, 10);
  const auto orthographic = Render(mesh, s);
  s.projection = mtpt::test::Ortho(-3, 3, -2, 2, 2.25, 10); // near plane at eye z = -2.25
  const auto clipped = Render(mesh, s);
  double worst[3] = { 0, 0, 0 };
  for (int y = 0; y < s.height; ++y)
  {
    for (int x = 0; x < s.width; ++x)
    {
      const double nx = 2 * (x + 0.5 + mtpt::PixelOffsetX) / s.width - 1;
      const double ny = 2 * (y + 0.5 + mtpt::PixelOffsetY) / s.height - 1;
      const double dx = nx * aspect * t, dy = ny * t; // direction (dx, dy, -1)
      const double stretch = std::sqrt(1 + dx * dx + dy * dy);
      for (int c = 0; c < 3; ++c)
      {
        const std::size_t i = 3 * (y * s.width + x) + c;
        worst[0] = std::max(worst[0], std::fabs(perspective[i] - expect(stretch, c)));
        worst[1] = std::max(worst[1], std::fabs(orthographic[i] - expect(1.0, c)));
        worst[2] = std::max(worst[2], std::fabs(clipped[i] - expect(0.75, c)));
      }
    }
  }
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_LT(worst[1], 1e-12);
  EXPECT_LT(worst[2], 1e-12);
}

TEST(ReferenceRenderer, FarFromTheOriginKeepsPrecision)
{
  // The same scene shifted by 1e7 (mesh and camera): eye coordinates are relative to the
  // camera and each cell's arithmetic to its first point, so the image hardly changes.
  Mesh mesh;
  const double lo[3] = { -1, -1, -1 }, hi[3] = { 1, 1, 1 };
  const int n[3] = { 5, 5, 5 };
  AddBox(mesh, lo, hi, n, [](double x, double y, double z) { return 0.5 + 0.4 * x * y * z; });
  ReferenceSettings s;
  s.width = s.height = 40;
  s.projection = mtpt::test::Perspective(35, 1, 0.5, 20);
  s.color = { { 0, 0.1, 0.2, 0.9 }, { 1, 0.9, 0.1, 0.1 } };
  s.opacity = { { 0, 0.2 }, { 0.5, 2.0 }, { 1, 0.2 } };
  s.unitDistance = 0.5;
  s.modelView = mtpt::test::LookAt({ 2.5, 1.8, 3.2 }, { 0, 0, 0 }, { 0, 1, 0 });
  const auto near = Render(mesh, s);
  const double shift = 1e7;
  Mesh far = mesh;
  for (std::size_t i = 0; i < far.points.size(); i += 3)
  {
    far.points[i] += shift;
    far.points[i + 1] -= shift;
  }
  s.modelView =
    mtpt::test::LookAt({ 2.5 + shift, 1.8 - shift, 3.2 }, { shift, -shift, 0 }, { 0, 1, 0 });
  const auto shifted = Render(far, s);
  const mtpt::ImageError error = mtpt::CompareImages(near.data(), shifted.data(), near.size() / 3);
  EXPECT_LT(error.maxAbs, 1e-6);
}

TEST(ReferenceRenderer, IdenticalForAnyThreadCountAndBanding)
{
  Mesh mesh;
  const double lo[3] = { -1, -1, -1 }, hi[3] = { 1, 1, 1 };
  const int n[3] = { 6, 5, 4 };
  AddBox(mesh, lo, hi, n,
    [](double x, double y, double z) { return 0.5 + 0.5 * std::sin(3 * x + y - z); });
  ReferenceSettings s;
  s.width = 50;
  s.height = 40;
  s.modelView = mtpt::test::LookAt({ -2.0, 2.5, 3.0 }, { 0, 0, 0 }, { 0, 1, 0 });
  s.projection = mtpt::test::Perspective(40, 1.25, 0.5, 20);
  s.color = { { 0, 0.1, 0.2, 0.9 }, { 1, 0.9, 0.1, 0.1 } };
  s.opacity = { { 0, 0.1 }, { 1, 3.0 } };
  const auto one = Render(mesh, s, 1);
  const auto two = Render(mesh, s, 2);
  s.maxSegmentsPerPass = 500; // many bands of rows
  std::vector<double> banded;
  mtpt::ReferenceStats stats;
  ASSERT_TRUE(mtpt::RenderReference(
    mesh.Points(), mesh.Cells(), mesh.Scalars(), s, banded, 3, nullptr, &stats));
  EXPECT_GT(stats.passes, 5u);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(one.data(), banded.data(), one.size() * sizeof(double)), 0);
}

TEST(ReferenceRenderer, RejectsBadInput)
{
  Mesh mesh;
  mesh.AddPoint(0, 0, 0);
  ReferenceSettings s;
  std::vector<double> rgb;
  std::string error;
  EXPECT_FALSE(
    mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 1, &error));
  EXPECT_FALSE(error.empty());
  s.width = s.height = 4;
  s.projection = Matrix4{};
  EXPECT_FALSE(
    mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 1, &error));
  s.projection = mtpt::IdentityMatrix();
  s.unitDistance = 0;
  EXPECT_FALSE(
    mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 1, &error));
  s.unitDistance = 1;
  s.opacity = { { 0, std::nan("") } };
  EXPECT_FALSE(
    mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 1, &error));
  s.opacity.clear();
  EXPECT_TRUE(
    mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 1, &error));
  EXPECT_EQ(rgb.size(), 48u);
}

TEST(ReferenceRenderer, CompareImagesMetrics)
{
  const std::vector<double> a = { 0, 0, 0, 1, 1, 1 }, b = { 0, 0, 0.3, 1, 1, 1 };
  const mtpt::ImageError e = mtpt::CompareImages(a.data(), b.data(), 2);
  EXPECT_NEAR(e.rmse, std::sqrt(0.09 / 6), 1e-15);
  EXPECT_NEAR(e.psnr, -20 * std::log10(std::sqrt(0.09 / 6)), 1e-12);
  EXPECT_NEAR(e.maxAbs, 0.3, 1e-15);
  EXPECT_EQ(e.worstPixel, 0u);
  EXPECT_TRUE(std::isinf(mtpt::CompareImages(a.data(), a.data(), 2).psnr));
}

namespace
{

/// The reference image of `mesh` with `values` (`channels` per point) under `mapping`.
std::vector<double> RenderMapped(const Mesh& mesh, const std::vector<float>& values,
  ReferenceSettings settings, mtpt::ScalarMapping mapping)
{
  settings.mapping = mapping;
  std::vector<double> rgb;
  std::string error;
  EXPECT_TRUE(mtpt::RenderReference(mesh.Points(), mesh.Cells(),
    { values.data(), mtpt::ScalarsView::Association::Points }, settings, rgb, 2, &error))
    << error;
  return rgb;
}

double LargestDifference(const std::vector<double>& a, const std::vector<double>& b)
{
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    worst = std::max(worst, std::fabs(a[i] - b[i]));
  }
  return worst;
}

} // namespace

TEST(ReferenceRenderer, DependentColoursIntegrateLinearColourAndAttenuation)
{
  // Colours given per point (dependent components, four channels) that equal a linear
  // transfer function of the scalar: the integral along every ray is the same function.
  const double unit = 0.4, k = 0.9;
  const double c0[3] = { 0.2, 0.9, 0.4 }, c1[3] = { 1.0, 0.1, 0.6 };
  Mesh mesh;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, 0.75 };
  const int n[3] = { 3, 2, 4 };
  AddBox(mesh, lo, hi, n,
    [](double x, double y, double z) { return 0.5 + 0.3 * std::sin(3 * x + 2 * y) * (1 - z); });
  ReferenceSettings s = OrthoDownZ(24, -0.1, 1.1, -0.1, 1.1);
  s.modelView = mtpt::test::LookAt({ 1.5, 2.0, 9.0 }, { 0.5, 0.5, 0.4 }, { 0, 1, 0 });
  s.unitDistance = unit;
  s.color = { { 0, c0[0], c0[1], c0[2] }, { 1, c1[0], c1[1], c1[2] } };
  s.opacity = { { 0, 0 }, { 1, k } };
  std::vector<float> rgba;
  for (float v : mesh.scalars)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgba.push_back(static_cast<float>(c0[c] + (c1[c] - c0[c]) * v));
    }
    rgba.push_back(static_cast<float>(k * v));
  }
  // The float colours are the scalar's function up to float rounding.
  const auto expected = Render(mesh, s);
  const auto colours = RenderMapped(mesh, rgba, s, mtpt::ScalarMapping::Colours);
  EXPECT_LT(LargestDifference(colours, expected), 1e-6);
  EXPECT_GT(LargestDifference(expected, Render(Mesh(), s)), 0.1) << "the slab is visible";
}

TEST(ReferenceRenderer, ColourAndOpacityScalarsDriveTheirOwnFunctions)
{
  Mesh mesh;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, 0.75 };
  const int n[3] = { 3, 3, 3 };
  AddBox(mesh, lo, hi, n, [](double x, double y, double z) { return x + 0.5 * y - 0.3 * z; });
  ReferenceSettings s = OrthoDownZ(24, -0.1, 1.1, -0.1, 1.1);
  s.unitDistance = 0.5;
  s.color = { { -0.3, 0.1, 0.2, 0.9 }, { 0.4, 1.0, 0.9, 0.2 }, { 1.5, 0.8, 0.1, 0.1 } };
  s.opacity = { { 0, 0.1 }, { 0.5, 3.0 }, { 1, 0.4 } };
  // Both channels the scalar: the one-scalar integral, whose cuts are the union of both
  // functions' nodes.
  std::vector<float> same, constantOpacity;
  for (float v : mesh.scalars)
  {
    same.insert(same.end(), { v, v });
    constantOpacity.insert(constantOpacity.end(), { v, 0.75f });
  }
  const auto expected = Render(mesh, s);
  EXPECT_LT(LargestDifference(
              RenderMapped(mesh, same, s, mtpt::ScalarMapping::ColourAndOpacityScalars), expected),
    1e-12);
  // A constant opacity scalar: the colour function of the first channel under the constant
  // opacity the opacity function gives at 0.75 (3.0 + 0.5 * (0.4 - 3.0)).
  ReferenceSettings constant = s;
  constant.opacity = { { 0, 1.7 } };
  EXPECT_LT(LargestDifference(
              RenderMapped(mesh, constantOpacity, s, mtpt::ScalarMapping::ColourAndOpacityScalars),
              Render(mesh, constant)),
    1e-12);
}

TEST(ReferenceRenderer, TranslucentSurfacesAreCompositedAtTheirDepth)
{
  // A constant slab z in [0, h] (colour cv, extinction tau) and a translucent square
  // (colour cs, opacity a) across every ray, in front of, inside (at mid-depth) and behind
  // the slab. With e = exp(-tau h / 2) for half the slab:
  //   front:  a cs + (1 - a) (cv (1 - e^2) + e^2 bg)
  //   inside: cv (1 - e) + e (a cs + (1 - a) (cv (1 - e) + e bg))
  //   behind: cv (1 - e^2) + e^2 (a cs + (1 - a) bg)
  const double h = 0.6, tau = 3.0, a = 0.35;
  const double cv[3] = { 0.9, 0.5, 0.1 }, cs[3] = { 0.1, 0.3, 0.95 };
  Mesh mesh;
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 1, 1, h };
  const int n[3] = { 2, 2, 3 };
  AddBox(mesh, lo, hi, n, [](double, double, double) { return 0.5; });
  ReferenceSettings s = OrthoDownZ(16, 0.05, 0.95, 0.05, 0.95); // every ray inside
  s.color = { { 0, cv[0], cv[1], cv[2] } };
  s.opacity = { { 0, tau * 0.5 } };
  s.unitDistance = 0.5; // extinction tau
  const double e = std::exp(-tau * h / 2);
  for (int where = 0; where < 3; ++where)
  {
    const double z = (where == 0 ? h + 0.2 : (where == 1 ? h / 2 : -0.2)) - 10.0; // eye z
    s.triangles.clear();
    s.triangles.push_back(
      { { { -1, -1, z }, { 2, -1, z }, { 2, 2, z } }, { cs[0], cs[1], cs[2] }, a });
    s.triangles.push_back(
      { { { -1, -1, z }, { 2, 2, z }, { -1, 2, z } }, { cs[0], cs[1], cs[2] }, a });
    const auto image = Render(mesh, s);
    double worst = 0;
    for (std::size_t p = 0; p < image.size() / 3; ++p)
    {
      for (int k = 0; k < 3; ++k)
      {
        const double bg = Background[k], surface = a * cs[k];
        const double expected = where == 0
          ? surface + (1 - a) * (cv[k] * (1 - e * e) + e * e * bg)
          : (where == 1 ? cv[k] * (1 - e) + e * (surface + (1 - a) * (cv[k] * (1 - e) + e * bg))
                        : cv[k] * (1 - e * e) + e * e * (surface + (1 - a) * bg));
        worst = std::max(worst, std::fabs(image[3 * p + k] - expected));
      }
    }
    EXPECT_LT(worst, 1e-12) << "surface "
                            << (where == 0 ? "in front" : (where == 1 ? "inside" : "behind"));
  }
}
