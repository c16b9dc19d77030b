// SPDX-License-Identifier: BSD-3-Clause
// Numerical hard cases (far from the origin, tiny and huge scales, a wide perspective view,
// saturated and vanishing attenuation, cells thin against their depth, non-convex meshes,
// huge cells beside tiny ones, edge-on faces, stacked vertices, slivers), each against an
// expected image: the exact reference (ReferenceRenderer.h) or the same scene without the
// difficulty. MTPT renders through the whole CPU path (FramePipeline + Compositor) in
// pre-integrated shading, whose perspective interpolation is exact, so the remaining
// differences are rounding and rasterization.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/ReferenceRenderer.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace
{

using mtpt::test::Vec3;

using Mesh = mtpt::test::DoubleMesh;

/// Camera, transfer functions and image size of a scene.
struct View
{
  int size = 64;
  mtpt::Matrix4 modelView = mtpt::IdentityMatrix();
  mtpt::Matrix4 projection = mtpt::IdentityMatrix();
  bool perspective = true;
  std::vector<mtpt::ColorNode> color = { { -1.0, 0.2, 0.3, 0.9 }, { 1.0, 0.95, 0.9, 0.5 },
    { 3.0, 0.9, 0.2, 0.1 } };
  std::vector<mtpt::OpacityNode> opacity = { { -1.0, 0.1 }, { 3.0, 1.5 } };
  double unitDistance = 1.0;
  double background[3] = { 0.1, 0.1, 0.2 };

  static View LookingAt(const Vec3& eye, double fovy, double nearPlane, double farPlane)
  {
    View v;
    v.modelView = mtpt::test::LookAt(eye, { 0, 0, 0 }, { 0, 1, 0 });
    v.projection = mtpt::test::Perspective(fovy, 1.0, nearPlane, farPlane);
    return v;
  }
};

/// The table MTPT samples from the nodes (as the mapper does from VTK's functions).
std::vector<float> Table(const View& v, double low, double high, int n = 4096)
{
  auto eval = [](double s, auto nodes, auto value)
  {
    std::sort(nodes.begin(), nodes.end(), [](auto& a, auto& b) { return a.scalar < b.scalar; });
    if (s <= nodes.front().scalar)
      return value(nodes.front(), nodes.front(), 0.0);
    for (std::size_t i = 1; i < nodes.size(); ++i)
    {
      if (s <= nodes[i].scalar)
      {
        const double f = (s - nodes[i - 1].scalar) / (nodes[i].scalar - nodes[i - 1].scalar);
        return value(nodes[i - 1], nodes[i], f);
      }
    }
    return value(nodes.back(), nodes.back(), 0.0);
  };
  std::vector<float> table(4 * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    const double s = low + (high - low) * i / (n - 1);
    for (int c = 0; c < 3; ++c)
    {
      table[4 * i + c] = static_cast<float>(eval(s, v.color,
        [c](const mtpt::ColorNode& a, const mtpt::ColorNode& b, double f)
        {
          const double x[3] = { a.r, a.g, a.b }, y[3] = { b.r, b.g, b.b };
          return x[c] + f * (y[c] - x[c]);
        }));
    }
    table[4 * i + 3] = static_cast<float>(eval(s, v.opacity,
      [](const mtpt::OpacityNode& a, const mtpt::OpacityNode& b, double f)
      { return a.opacity + f * (b.opacity - a.opacity); }));
  }
  return table;
}

/// How MTPT's CPU path draws a frame: the slot entry point's triangles, or the fans of the
/// CPU backend (one batch, binned into tiles).
enum class Path
{
  Slots,
  Fans
};

/// MTPT's image (linear RGB over the background, 3 doubles per pixel).
std::vector<double> RenderMTPT(
  const Mesh& mesh, const View& v, bool preIntegrated = true, Path path = Path::Slots)
{
  const auto range = std::minmax_element(mesh.scalars.begin(), mesh.scalars.end());
  const double low = *range.first, high = *range.second > low ? *range.second : low + 1;
  const std::vector<float> table = Table(v, low, high);
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = mesh.Scalars();
  input.modelView = v.modelView;
  input.projection = v.projection;
  input.perspective = v.perspective;
  input.imageSize = { v.size, v.size };
  mtpt::FramePipeline pipeline;
  EXPECT_TRUE(pipeline.Run(input, 2));
  mtpt::CompositeSettings settings;
  settings.width = settings.height = v.size;
  settings.transferFunction = { table.data(), static_cast<int>(table.size() / 4), low, high };
  settings.unitDistance = v.unitDistance;
  mtpt::PreIntegrationTable pre;
  if (preIntegrated)
  {
    pre.Build(settings.transferFunction);
    settings.UsePreIntegration(pre, mtpt::PerspectiveInterpolation::FromProjection(v.projection));
  }
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  if (path == Path::Slots)
  {
    compositor.Composite(pipeline.Vertices().data(), pipeline.Indices().data(),
      pipeline.TetrahedronCount(), settings, rgba, 2);
  }
  else
  {
    pipeline.DecomposeFans(0, pipeline.SortedCount(), 2);
    compositor.Begin(settings);
    compositor.Composite(pipeline.Fans().data(), pipeline.FanCount(), 2);
    rgba.resize(4 * static_cast<std::size_t>(v.size) * v.size);
    compositor.Resolve({ 0, 0, v.size, v.size }, nullptr, rgba.data(), 2);
  }
  std::vector<double> rgb(3 * static_cast<std::size_t>(v.size) * v.size);
  for (std::size_t p = 0; p < rgb.size() / 3; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgb[3 * p + c] = rgba[4 * p + c] + (1.0 - rgba[4 * p + 3]) * v.background[c];
    }
  }
  return rgb;
}

std::vector<double> RenderExact(const Mesh& mesh, const View& v)
{
  mtpt::ReferenceSettings s;
  s.width = s.height = v.size;
  s.modelView = v.modelView;
  s.projection = v.projection;
  s.color = v.color;
  s.opacity = v.opacity;
  s.unitDistance = v.unitDistance;
  std::copy(v.background, v.background + 3, s.background);
  std::vector<double> rgb;
  std::string error;
  EXPECT_TRUE(mtpt::RenderReference(mesh.Points(), mesh.Cells(), mesh.Scalars(), s, rgb, 2, &error))
    << error;
  return rgb;
}

bool AllFinite(const std::vector<double>& image)
{
  return std::all_of(image.begin(), image.end(), [](double x) { return std::isfinite(x); });
}

/// Compares, prints and returns the error of `image` against `expected`.
mtpt::ImageError Check(
  const char* name, const std::vector<double>& image, const std::vector<double>& expected)
{
  EXPECT_TRUE(AllFinite(image)) << name;
  EXPECT_EQ(image.size(), expected.size()) << name;
  const mtpt::ImageError e = mtpt::CompareImages(image.data(), expected.data(), image.size() / 3);
  std::printf("%-44s RMSE %.2e  max %.2e\n", name, e.rmse, e.maxAbs);
  return e;
}

Mesh Grid(int n = 6)
{
  return Mesh(mtpt::test::JitteredGrid(n, 5));
}

TEST(HardCases, FarFromTheOriginTheImageIsUnchanged)
{
  const Mesh base = Grid();
  const View view = View::LookingAt({ 1.5, 1.2, 3.5 }, 45, 0.5, 20);
  const std::vector<double> expected = RenderMTPT(base, view);
  for (double offset : { 1e6, 1e7 })
  {
    Mesh shifted = base;
    const Vec3 t = { offset, -0.7 * offset, 0.3 * offset };
    shifted.Transform(1.0, t);
    View v = view;
    // The same camera moved with the mesh: view matrix * translation by -t.
    v.modelView = mtpt::Multiply(
      view.modelView, { 1, 0, 0, -t[0], 0, 1, 0, -t[1], 0, 0, 1, -t[2], 0, 0, 0, 1 });
    char name[64];
    std::snprintf(name, sizeof(name), "offset %.0e vs unshifted", offset);
    EXPECT_LT(Check(name, RenderMTPT(shifted, v), expected).rmse, 1e-6);
  }
}

TEST(HardCases, TinyAndHugeScalesGiveTheSameImage)
{
  const Mesh base = Grid();
  const View view = View::LookingAt({ 1.5, 1.2, 3.5 }, 45, 0.5, 20);
  const std::vector<double> expected = RenderMTPT(base, view);
  for (double scale : { 1e-6, 1e6 })
  {
    Mesh scaled = base;
    scaled.Transform(scale, { 0, 0, 0 });
    View v =
      View::LookingAt({ 1.5 * scale, 1.2 * scale, 3.5 * scale }, 45, 0.5 * scale, 20 * scale);
    v.unitDistance = scale;
    char name[64];
    std::snprintf(name, sizeof(name), "scale %.0e vs scale 1", scale);
    EXPECT_LT(Check(name, RenderMTPT(scaled, v), expected).rmse, 1e-6);
  }
}

TEST(HardCases, WidePerspectiveMatchesTheReference)
{
  const Mesh mesh = Grid();
  const View v = View::LookingAt({ 0.8, 0.6, 1.9 }, 120, 0.05, 10);
  const std::vector<double> exact = RenderExact(mesh, v);
  EXPECT_LT(Check("120-degree perspective, pre-integrated", RenderMTPT(mesh, v), exact).rmse, 5e-4);
  EXPECT_LT(
    Check("120-degree perspective, VTK-compatible", RenderMTPT(mesh, v, false), exact).rmse, 0.015);
}

TEST(HardCases, SaturatedAndVanishingAttenuation)
{
  const Mesh mesh = Grid();
  View v = View::LookingAt({ 1.5, 1.2, 3.5 }, 45, 0.5, 20);
  v.opacity = { { -1.0, 1e4 }, { 3.0, 1e5 } }; // opaque within a hair of the surface
  std::vector<double> image = RenderMTPT(mesh, v);
  // Silhouette pixels differ by coverage; the rest is a surface colour.
  EXPECT_LT(Check("opaque (attenuation 1e4..1e5)", image, RenderExact(mesh, v)).rmse, 0.02);
  v.opacity = { { -1.0, 1e-9 }, { 3.0, 1e-8 } }; // all but transparent
  image = RenderMTPT(mesh, v);
  const mtpt::ImageError e =
    Check("transparent (attenuation 1e-9..1e-8)", image, RenderExact(mesh, v));
  EXPECT_LT(e.maxAbs, 1e-6);
}

TEST(HardCases, PerspectiveSegmentsThinAgainstTheirDepth)
{
  // The grid seen from 10^6 times its size through a narrow perspective view that it fills,
  // its cells dense enough that each of the 6 along a ray takes about a third of the light:
  // a cell's back face differs from its front face in the seventh digit of 1 / w. The
  // segments' lengths must come from that difference formed per vertex, not from the two
  // faces' 1 / w subtracted per fragment, which leaves a length of a few units in the last
  // place of a float (there: RMSE 0.008 through the slots and 0.016 through the fans, 0.18
  // in the worst pixel). On every instruction set, through the triangles of the slot entry
  // point and through the fans.
  const Mesh mesh = Grid();
  const double distance = 1e6;
  View v = View::LookingAt({ 0, 0, distance }, 2.0 * std::atan(1.3 / distance) * 180.0 / M_PI,
    distance - 3.0, distance + 3.0);
  v.opacity = { { -1.0, 1.0 }, { 3.0, 1.5 } };
  const std::vector<double> exact = RenderExact(mesh, v);
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets())
  {
    hwy::SetSupportedTargetsForTest(target);
    for (const Path path : { Path::Slots, Path::Fans })
    {
      char name[64];
      std::snprintf(name, sizeof(name), "10^6 away, %s, %s", hwy::TargetName(target),
        path == Path::Slots ? "slots" : "fans");
      const mtpt::ImageError e = Check(name, RenderMTPT(mesh, v, true, path), exact);
      EXPECT_LT(e.rmse, 5e-4) << name;
      EXPECT_LT(e.maxAbs, 0.02) << name;
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(HardCases, NonConvexMeshesMatchTheReference)
{
  // Two blocks one behind the other, and a U: rays leave and re-enter the mesh.
  Mesh mesh = Grid(4);
  Mesh second = Grid(4);
  second.Transform(0.5, { 0.4, 0.2, -2.6 });
  const auto base = static_cast<std::int64_t>(mesh.scalars.size());
  mesh.points.insert(mesh.points.end(), second.points.begin(), second.points.end());
  mesh.scalars.insert(mesh.scalars.end(), second.scalars.begin(), second.scalars.end());
  for (std::size_t c = 0; c < second.CellCount(); ++c)
  {
    const std::int64_t* ids = second.connectivity.data() + second.offsets[c];
    mesh.AddTetrahedron(base + ids[0], base + ids[1], base + ids[2], base + ids[3]);
  }
  View v = View::LookingAt({ 0.9, 0.7, 3.0 }, 50, 0.5, 20);
  EXPECT_LT(
    Check("two blocks along the view", RenderMTPT(mesh, v), RenderExact(mesh, v)).rmse, 1e-3);
}

TEST(HardCases, HugeCellsBesideTinyOnes)
{
  // The grid plus one tetrahedron 1000 times larger than its cells and one 1000 times
  // smaller, each separate from the grid.
  Mesh mesh = Grid();
  const std::int64_t a = mesh.AddPoint(-40, -30, -60, 0.0f), b = mesh.AddPoint(40, -30, -60, 2.0f),
                     c = mesh.AddPoint(0, 40, -60, 1.0f), d = mesh.AddPoint(0, 0, -130, 3.0f);
  mesh.AddTetrahedron(a, b, c, d);
  const std::int64_t e = mesh.AddPoint(1.2, 0, 0, 0.0f), f = mesh.AddPoint(1.2003, 0, 0, 1.0f),
                     g = mesh.AddPoint(1.2, 0.0003, 0, 2.0f),
                     h = mesh.AddPoint(1.2, 0, 0.0003, 3.0f);
  mesh.AddTetrahedron(e, f, g, h);
  View v = View::LookingAt({ 1.5, 1.2, 3.5 }, 45, 0.5, 400);
  v.opacity = { { -1.0, 0.02 }, { 3.0, 0.4 } };
  EXPECT_LT(Check("huge and tiny cells", RenderMTPT(mesh, v), RenderExact(mesh, v)).rmse, 5e-4);
}

TEST(HardCases, EdgeOnFacesAndStackedVertices)
{
  // An unjittered grid seen along an axis: every vertical face is edge-on and the points
  // of each column project onto one another (classes 3 and 4 everywhere).
  Mesh mesh(mtpt::test::JitteredGrid(5, 1));
  // JitteredGrid jitters interior points only; flatten them back onto the lattice.
  const double h = 2.0 / 5;
  for (double& x : mesh.points)
  {
    x = -1 + h * std::round((x + 1) / h);
  }
  View v;
  v.modelView = mtpt::test::LookAt({ 0, 0, 4 }, { 0, 0, 0 }, { 0, 1, 0 });
  v.projection = mtpt::test::Ortho(-1.3, 1.3, -1.3, 1.3, 1, 10);
  v.perspective = false;
  const std::vector<double> exact = RenderExact(mesh, v);
  const mtpt::ImageError e = Check("axis-aligned grid, orthographic", RenderMTPT(mesh, v), exact);
  EXPECT_LT(e.rmse, 1e-4);
  v.perspective = true;
  v.projection = mtpt::test::Perspective(40, 1.0, 1, 10);
  EXPECT_LT(
    Check("axis-aligned grid, perspective", RenderMTPT(mesh, v), RenderExact(mesh, v)).rmse, 1e-3);
}

TEST(HardCases, SliversAndZeroVolumeCellsChangeNothing)
{
  const Mesh base = Grid();
  const View v = View::LookingAt({ 1.5, 1.2, 3.5 }, 45, 0.5, 20);
  const std::vector<double> expected = RenderMTPT(base, v);
  Mesh mesh = base;
  // Zero volume: a repeated point, four coplanar points, four collinear points; slivers:
  // a tetrahedron 1e-7 thick, and a needle.
  const std::int64_t p = mesh.AddPoint(0.3, 0.2, 0.1, 1.0f), q = mesh.AddPoint(0.5, 0.2, 0.1, 2.0f),
                     r = mesh.AddPoint(0.3, 0.5, 0.1, 0.0f), s = mesh.AddPoint(0.5, 0.5, 0.1, 1.5f),
                     t = mesh.AddPoint(0.4, 0.35, 0.1 + 1e-7, 3.0f),
                     u = mesh.AddPoint(0.7, 0.2, 0.1, 1.0f), w = mesh.AddPoint(0.9, 0.2, 0.1, 1.0f),
                     x = mesh.AddPoint(1.1, 0.2, 0.1, 1.0f),
                     y = mesh.AddPoint(0.7, 0.2 + 1e-6, 0.1 + 1e-6, 1.0f);
  mesh.AddTetrahedron(p, p, q, r);
  mesh.AddTetrahedron(p, q, r, s);
  mesh.AddTetrahedron(p, u, w, x);
  mesh.AddTetrahedron(p, q, r, t);
  mesh.AddTetrahedron(u, w, x, y);
  const mtpt::ImageError e =
    Check("slivers and zero-volume cells added", RenderMTPT(mesh, v), expected);
  EXPECT_LT(e.maxAbs, 1e-5);
}

} // namespace
