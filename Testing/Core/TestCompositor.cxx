// SPDX-License-Identifier: BSD-3-Clause
// The CPU compositor: coverage rule, fragment math, occlusion, and determinism. The tests
// of the per-pixel code run once for every instruction set it is compiled for and this
// processor has (CompositorSimd), each chosen in turn through Highway's test hook.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"

#include "detail/TileRaster.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace
{

using mtpt::TetVertex;

/// A constant transfer function: colour (r, g, b), attenuation a.
std::vector<float> ConstantTable(float r, float g, float b, float a)
{
  return { r, g, b, a, r, g, b, a };
}

mtpt::CompositeSettings Settings(int w, int h, const std::vector<float>& table)
{
  mtpt::CompositeSettings s;
  s.width = w;
  s.height = h;
  s.transferFunction = { table.data(), static_cast<int>(table.size() / 4), 0.0, 1.0 };
  s.unitDistance = 1.0;
  return s;
}

/// NDC of window coordinate `p` in a window of `size` pixels.
float Ndc(double p, int size)
{
  return static_cast<float>(2.0 * p / size - 1.0);
}

/// One slot holding a square split along a diagonal into two triangles, with a constant
/// segment length (so every covered pixel gets the same opacity).
void SquareSlot(double x0, double y0, double x1, double y1, int w, int h, float length,
  TetVertex vertices[5], std::uint32_t indices[12], std::uint32_t base)
{
  const double xs[4] = { x0, x1, x1, x0 }, ys[4] = { y0, y0, y1, y1 };
  for (int i = 0; i < 4; ++i)
  {
    vertices[i] = TetVertex{ Ndc(xs[i], w), Ndc(ys[i], h), 0.0f, 0.5f, 0.5f, length };
  }
  vertices[4] = vertices[0];
  const std::uint32_t local[12] = { 0, 1, 2, 0, 2, 3, 4, 4, 4, 4, 4, 4 };
  for (int i = 0; i < 12; ++i)
  {
    indices[i] = base + local[i];
  }
}

/// The tests of the fragment loops, run with each instruction set in turn.
class CompositorSimd : public ::testing::TestWithParam<std::int64_t>
{
protected:
  void SetUp() override { hwy::SetSupportedTargetsForTest(this->GetParam()); }
  void TearDown() override { hwy::SetSupportedTargetsForTest(0); }
};

TEST_P(CompositorSimd, SharedEdgesAreCoveredExactlyOnce)
{
  const int w = 16, h = 12;
  const auto table = ConstantTable(1.0f, 0.5f, 0.25f, 1.0f);
  // Two squares sharing the edge x = 6.5, every edge and the diagonals through pixel
  // centres: the worst case for a coverage rule.
  TetVertex vertices[10];
  std::uint32_t indices[24];
  SquareSlot(0.5, 1.5, 6.5, 7.5, w, h, 0.3f, vertices, indices, 0);
  SquareSlot(6.5, 1.5, 12.5, 7.5, w, h, 0.3f, vertices + 5, indices + 12, 5);
  for (int threads : { 1, 3, 5 })
  {
    mtpt::Compositor compositor;
    std::vector<float> rgba;
    compositor.Composite(vertices, indices, 2, Settings(w, h, table), rgba, threads);
    const float once = 1.0f - std::exp(-0.3f);
    int covered = 0;
    for (int y = 0; y < h; ++y)
    {
      for (int x = 0; x < w; ++x)
      {
        const float alpha = rgba[4 * (y * w + x) + 3];
        // Top-left rule, y up: the left edge x = 0.5 and the top edge y = 7.5 own their
        // centres; the right edge x = 12.5 and the bottom edge y = 1.5 do not.
        const bool inside = x >= 0 && x <= 11 && y >= 2 && y <= 7;
        if (inside)
        {
          ++covered;
          ASSERT_FLOAT_EQ(alpha, once) << x << "," << y;
          ASSERT_FLOAT_EQ(rgba[4 * (y * w + x)], once * 1.0f);
        }
        else
        {
          ASSERT_EQ(alpha, 0.0f) << x << "," << y;
        }
      }
    }
    EXPECT_EQ(covered, 12 * 6);
  }
}

TEST_P(CompositorSimd, VertexColoursDrawOnlyWithVTKCompatibleShading)
{
  // Records with the data's colours (dependent components) are drawn VTK-compatibly; the
  // frame's plan never asks for them pre-integrated, and the compositor draws nothing when
  // asked (it takes no decision of its own).
  const int w = 8, h = 8;
  const auto table = ConstantTable(1.0f, 0.5f, 0.25f, 1.0f);
  TetVertex vertices[5];
  std::uint32_t indices[12];
  SquareSlot(0.5, 0.5, 7.5, 7.5, w, h, 0.5f, vertices, indices, 0);
  const float colour[4] = { 0.25f, 0.5f, 1.0f, 1.0f };
  for (TetVertex& v : vertices)
  {
    mtpt::StoreVertexColour(v, colour);
  }
  mtpt::PreIntegrationTable integrals;
  auto settings = Settings(w, h, table);
  integrals.Build(settings.transferFunction);
  settings.vertexColours = true;
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  compositor.Composite(vertices, indices, 1, settings, rgba, 2);
  EXPECT_GT(rgba[4 * (4 * w + 4) + 3], 0.0f); // drawn, with the colours' attenuation
  EXPECT_NEAR(rgba[4 * (4 * w + 4) + 2] / rgba[4 * (4 * w + 4) + 3], 1.0f, 1e-3f);
  settings.UsePreIntegration(integrals, mtpt::PerspectiveInterpolation{});
  compositor.Composite(vertices, indices, 1, settings, rgba, 2);
  EXPECT_TRUE(std::all_of(rgba.begin(), rgba.end(), [](float v) { return v == 0.0f; }));
}

TEST_P(CompositorSimd, FragmentMathMatchesTheShader)
{
  // One triangle with different attributes at its vertices; check one pixel by hand.
  const int w = 8, h = 8;
  std::vector<float> table = { 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 0.0f, 0.0f, 2.0f }; // 2 entries
  TetVertex v[5] = { { Ndc(0, w), Ndc(0, h), 0.0f, 0.0f, 0.0f, 0.0f },
    { Ndc(8, w), Ndc(0, h), 0.0f, 1.0f, 1.0f, 0.0f },
    { Ndc(0, w), Ndc(8, h), 0.0f, 0.0f, 1.0f, 2.0f }, // thick: front 0, back 1, length 2
    {}, {} };
  const std::uint32_t idx[12] = { 0, 1, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3 };
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  auto settings = Settings(w, h, table);
  settings.unitDistance = 0.5;
  compositor.Composite(v, idx, 1, settings, rgba, 2);
  // Pixel (1, 2): centre (1.5, 2.5); barycentrics l1 = 1.5/8, l2 = 2.5/8, l0 = 0.5.
  const double l0 = 0.5, l1 = 1.5 / 8, l2 = 2.5 / 8;
  // Vertex classification: mean of the table at front and back scalars.
  const double c0[4] = { 0, 0, 1, 0 }, c1[4] = { 1, 0, 0, 2 }, c2[4] = { 0.5, 0, 0.5, 1 };
  double f[4];
  for (int c = 0; c < 4; ++c)
  {
    f[c] = l0 * c0[c] + l1 * c1[c] + l2 * c2[c];
  }
  const double length = l2 * 2.0;
  const double opacity = 1.0 - std::exp(-f[3] * length / 0.5);
  const float* p = rgba.data() + 4 * (2 * w + 1);
  EXPECT_NEAR(p[3], opacity, 1e-6);
  EXPECT_NEAR(p[0], opacity * f[0], 1e-6);
  EXPECT_NEAR(p[2], opacity * f[2], 1e-6);
  // Outside the triangle nothing is drawn.
  EXPECT_EQ(rgba[4 * (7 * w + 7) + 3], 0.0f);
}

TEST_P(CompositorSimd, BlendsBackToFrontInSlotOrder)
{
  const int w = 4, h = 4;
  // Slot 0 red behind, slot 1 blue in front, both covering the whole window.
  std::vector<float> table = { 1, 0, 0, 1, 0, 0, 1, 1 }; // scalar 0 red, 1 blue
  TetVertex v[10];
  std::uint32_t idx[24];
  SquareSlot(-1, -1, 5, 5, w, h, 0.5f, v, idx, 0);
  SquareSlot(-1, -1, 5, 5, w, h, 0.5f, v + 5, idx + 12, 5);
  for (int i = 0; i < 5; ++i)
  {
    v[i].scalarFront = v[i].scalarBack = 0.0f;
    v[5 + i].scalarFront = v[5 + i].scalarBack = 1.0f;
  }
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  compositor.Composite(v, idx, 2, Settings(w, h, table), rgba, 2);
  const float a = 1.0f - std::exp(-0.5f);
  EXPECT_NEAR(rgba[0], (1 - a) * a, 1e-6); // red, seen through the blue layer
  EXPECT_NEAR(rgba[2], a, 1e-6);
  EXPECT_NEAR(rgba[3], a + (1 - a) * a, 1e-6);
}

TEST_P(CompositorSimd, OverlappingTrianglesOfAFanBlendInSlotOrder)
{
  // A degenerate projection can put a fan's centre outside its silhouette: its triangles
  // (boundary[i], boundary[i + 1], centre) then overlap. OpenGL blends a slot's triangles over
  // one another in index order; the CPU compositor, compositing front to back, must give
  // that image, for the fan and for the slot's triangles drawn as fans of one. Here the
  // centre C lies above B2, inside triangle (B0, B1, C): the other two lie on top of it.
  const int w = 10, h = 10;
  const std::vector<float> table = { 1, 0, 0, 1, 0, 0, 1, 1 }; // scalar 0 red, 1 blue
  const double xs[4] = { 1, 9, 5, 5 }, ys[4] = { 1, 1, 4, 9 }; // B0, B1, B2, C (pixels)
  const float scalars[4] = { 0.0f, 1.0f, 1.0f, 0.5f };
  TetVertex corner[4];
  for (int i = 0; i < 4; ++i)
  {
    corner[i] = TetVertex{ Ndc(xs[i], w), Ndc(ys[i], h), 0.0f, scalars[i], scalars[i], 0.7f };
  }
  mtpt::Fan fan{};
  fan.boundary[0] = corner[0];
  fan.boundary[1] = corner[1];
  fan.boundary[2] = corner[2];
  fan.centre = corner[3];
  fan.count = 3;
  fan.closed = 1;
  const mtpt::CompositeSettings settings = Settings(w, h, table);
  mtpt::Compositor compositor;
  compositor.Begin(settings);
  compositor.Composite(&fan, 1, 2);
  std::vector<float> fanImage(4 * w * h);
  compositor.Resolve({ 0, 0, w, h }, nullptr, fanImage.data(), 2);

  const TetVertex slot[5] = { corner[0], corner[1], corner[2], corner[2], corner[3] };
  const std::uint32_t inOrder[12] = { 0, 1, 4, 1, 2, 4, 2, 0, 4, 4, 4, 4 };
  const std::uint32_t reversed[12] = { 2, 0, 4, 1, 2, 4, 0, 1, 4, 4, 4, 4 };
  std::vector<float> slotImage, reversedImage;
  compositor.Composite(slot, inOrder, 1, settings, slotImage, 2);
  compositor.Composite(slot, reversed, 1, settings, reversedImage, 2);
  ASSERT_EQ(slotImage.size(), fanImage.size());
  double worst = 0, orderMatters = 0;
  for (std::size_t i = 0; i < fanImage.size(); ++i)
  {
    worst = std::max(worst, static_cast<double>(std::fabs(fanImage[i] - slotImage[i])));
    orderMatters =
      std::max(orderMatters, static_cast<double>(std::fabs(slotImage[i] - reversedImage[i])));
  }
  EXPECT_LE(worst, 1e-6) << mtpt::detail::RasterTargetName();
  EXPECT_GT(orderMatters, 0.05) << "the triangles overlap with different colours";
  // Over one another in index order: at B2's pixel triangle 0 first, then 1 and 2 over it.
  const std::size_t p = 4 * (4 * w + 5);
  EXPECT_GT(slotImage[p + 3], 1.0f - std::exp(-0.7f) + 0.05f) << "two layers or more";
}

TEST_P(CompositorSimd, PixelsGoneOpaqueSkipOnlyWhatCannotShow)
{
  // Fans are drawn front to back, and a pixel whose alpha reached OpaqueAlpha (1 - 2^-11)
  // skips the fragments behind it. Sixteen layers over the whole window, red and green in
  // turn, each of opacity 1 - exp(-0.6): the front thirteen make the pixels opaque, the three
  // behind must change them by no more than 2^-11. Against the layers composited back to front in
  // double precision; and composited in two batches (the front one drawn on its own and composited
  // over the back one), the same.
  const int w = 8, h = 8, layers = 16;
  std::vector<float> table = { 1, 0, 0, 1, 0, 1, 0, 1 }; // scalar 0 red, 1 green
  std::vector<TetVertex> v(5 * layers);
  std::vector<std::uint32_t> idx(12 * layers);
  double expected[4] = { 0, 0, 0, 0 };
  const double a = 1.0 - std::exp(-0.6);
  for (int k = 0; k < layers; ++k) // back to front
  {
    SquareSlot(-1, -1, 9, 9, w, h, 0.6f, v.data() + 5 * k, idx.data() + 12 * k, 5 * k);
    for (int i = 0; i < 5; ++i)
    {
      v[5 * k + i].scalarFront = v[5 * k + i].scalarBack = static_cast<float>(k % 2);
    }
    const double colour[4] = { k % 2 ? 0.0 : 1.0, k % 2 ? 1.0 : 0.0, 0.0, 1.0 };
    for (int c = 0; c < 4; ++c)
    {
      expected[c] = a * colour[c] + (1 - a) * expected[c];
    }
  }
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  compositor.Composite(v.data(), idx.data(), layers, Settings(w, h, table), rgba, 2);
  for (int c = 0; c < 4; ++c)
  {
    EXPECT_NEAR(rgba[c], expected[c], 1.0 / 2048 + 1e-6) << "channel " << c;
  }
  EXPECT_GT(rgba[3], 1.0f - 1.0f / 2048) << "opaque";
  // Two batches: the back 6 layers, then the front 10 over them.
  mtpt::Compositor batches;
  batches.Begin(Settings(w, h, table));
  std::vector<mtpt::Fan> fans;
  for (int k = 0; k < layers; ++k)
  {
    for (int t = 0; t < 2; ++t)
    {
      const std::uint32_t* tri = idx.data() + 12 * k + 3 * t;
      mtpt::Fan fan{};
      fan.boundary[0] = v[tri[0]];
      fan.boundary[1] = v[tri[1]];
      fan.centre = v[tri[2]];
      fan.count = 2;
      fans.push_back(fan);
    }
  }
  batches.Composite(fans.data(), 12, 2);
  batches.Composite(fans.data() + 12, fans.size() - 12, 2);
  std::vector<float> split(4 * w * h);
  batches.Resolve({ 0, 0, w, h }, nullptr, split.data(), 2);
  for (int c = 0; c < 4; ++c)
  {
    EXPECT_NEAR(split[c], expected[c], 1.0 / 2048 + 1e-6) << "channel " << c << ", batches";
  }
}

TEST_P(CompositorSimd, OpaqueDepthOccludesFragmentsBehindIt)
{
  const int w = 8, h = 8;
  const auto table = ConstantTable(1, 1, 1, 1);
  TetVertex v[5];
  std::uint32_t idx[12];
  SquareSlot(-1, -1, 9, 9, w, h, 1.0f, v, idx, 0); // NDC z 0: window depth 0.5
  std::vector<float> depth(w * h, 1.0f);
  for (int x = 0; x < w; ++x)
  {
    depth[x] = 0.25f;    // row 0: an opaque surface in front of the volume
    depth[w + x] = 0.5f; // row 1: at exactly the same depth (GL_LEQUAL keeps it)
  }
  auto settings = Settings(w, h, table);
  settings.opaqueDepth = depth.data();
  mtpt::Compositor compositor;
  std::vector<float> rgba;
  compositor.Composite(v, idx, 1, settings, rgba, 2);
  for (int x = 0; x < w; ++x)
  {
    EXPECT_EQ(rgba[4 * x + 3], 0.0f);
    EXPECT_GT(rgba[4 * (w + x) + 3], 0.0f);
    EXPECT_GT(rgba[4 * (5 * w + x) + 3], 0.0f);
  }
}

TEST(Compositor, TransferFunctionLookupInterpolatesAndClamps)
{
  const std::vector<float> table = { 0, 0, 0, 0, 1, 2, 3, 4, 3, 2, 1, 0 };
  const mtpt::TransferFunctionTable tf{ table.data(), 3, 10.0, 20.0 };
  float rgba[4];
  tf.Lookup(12.5f, rgba); // halfway between entries 0 and 1
  EXPECT_FLOAT_EQ(rgba[0], 0.5f);
  EXPECT_FLOAT_EQ(rgba[3], 2.0f);
  tf.Lookup(17.5f, rgba);
  EXPECT_FLOAT_EQ(rgba[0], 2.0f);
  tf.Lookup(-100.0f, rgba);
  EXPECT_FLOAT_EQ(rgba[1], 0.0f);
  tf.Lookup(1e9f, rgba);
  EXPECT_FLOAT_EQ(rgba[2], 1.0f);
}

TEST(Compositor, BitIdenticalForEveryThreadCount)
{
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(12, 21);
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  input.modelView = mtpt::test::LookAt({ 1.0, 1.5, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 });
  input.projection = mtpt::test::Perspective(45, 1.25, 1, 10);
  input.perspective = true;
  mtpt::FramePipeline pipeline;
  ASSERT_TRUE(pipeline.Run(input, 2));
  std::vector<float> table;
  for (int i = 0; i < 64; ++i)
  {
    const float t = i / 63.0f;
    table.insert(table.end(), { t, 1 - t, 0.5f, 2.0f * t });
  }
  auto settings = Settings(100, 80, table);
  settings.transferFunction.low = -2.0;
  settings.transferFunction.high = 3.0;
  settings.unitDistance = 0.2;
  mtpt::Compositor compositor;
  std::vector<float> reference;
  compositor.Composite(pipeline.Vertices().data(), pipeline.Indices().data(),
    pipeline.TetrahedronCount(), settings, reference, 1);
  float maxAlpha = 0;
  for (std::size_t i = 3; i < reference.size(); i += 4)
  {
    ASSERT_TRUE(std::isfinite(reference[i]));
    maxAlpha = std::max(maxAlpha, reference[i]);
  }
  EXPECT_GT(maxAlpha, 0.3f); // something substantial was drawn
  // More threads than rows too: bands are at least one row.
  for (int threads : { 2, 3, 8, 100 })
  {
    std::vector<float> image;
    compositor.Composite(pipeline.Vertices().data(), pipeline.Indices().data(),
      pipeline.TetrahedronCount(), settings, image, threads);
    ASSERT_EQ(0, std::memcmp(image.data(), reference.data(), image.size() * sizeof(float)))
      << threads << " threads";
  }
}

TEST(Compositor, CullingCellsThatCoverNoPixelChangesNothing)
{
  // A fine mesh in a small image: most cells are sub-pixel. Culling them before the sort
  // must leave the composited image bit-identical, and count each culled cell once.
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(16, 5); // 24,576 tetrahedra
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  input.modelView = mtpt::test::LookAt({ 0.8, 1.2, 3.5 }, { 0.4, 0, 0 }, { 0, 1, 0 });
  input.projection = mtpt::test::Perspective(40, 1.0, 1, 10);
  input.perspective = true;
  input.cullFrustum = false;
  std::vector<float> table;
  for (int i = 0; i < 32; ++i)
  {
    const float t = i / 31.0f;
    table.insert(table.end(), { t, 0.3f, 1 - t, 3.0f * t });
  }
  for (int size : { 9, 24, 64 })
  {
    mtpt::FramePipeline full, culled;
    ASSERT_TRUE(full.Run(input, 2));
    input.imageSize = { size, size };
    ASSERT_TRUE(culled.Run(input, 2));
    input.imageSize = {};
    const mtpt::FrameStats& stats = culled.Stats();
    EXPECT_EQ(full.SortedCount(), mesh.CellCount());
    EXPECT_EQ(stats.sorted + stats.pixelCulled, mesh.CellCount());
    EXPECT_EQ(culled.SortedCount(), stats.sorted);
    auto settings = Settings(size, size, table);
    settings.transferFunction.low = -2.0;
    settings.transferFunction.high = 3.0;
    settings.unitDistance = 0.3;
    mtpt::Compositor compositor;
    std::vector<float> fromFull, fromCulled;
    compositor.Composite(full.Vertices().data(), full.Indices().data(), full.TetrahedronCount(),
      settings, fromFull, 2);
    compositor.Composite(culled.Vertices().data(), culled.Indices().data(),
      culled.TetrahedronCount(), settings, fromCulled, 2);
    ASSERT_EQ(0, std::memcmp(fromFull.data(), fromCulled.data(), fromFull.size() * sizeof(float)))
      << size << " px";
    if (size == 9)
    {
      EXPECT_GT(stats.pixelCulled, mesh.CellCount() / 2); // most cells are sub-pixel here
    }
    EXPECT_GT(stats.pixelCulled, 0u);
  }
}

/// A jittered grid composited through fans with `settings` (its image: premultiplied RGBA).
std::vector<float> CompositeFans(mtpt::FramePipeline& pipeline, const mtpt::CompositeSettings& s)
{
  pipeline.DecomposeFans(0, pipeline.SortedCount(), 2);
  mtpt::Compositor compositor;
  compositor.Begin(s);
  compositor.Composite(pipeline.Fans().data(), pipeline.FanCount(), 2);
  std::vector<float> rgba(4 * static_cast<std::size_t>(s.width) * s.height);
  compositor.Resolve(
    { 0, 0, s.width, s.height }, static_cast<const float*>(nullptr), rgba.data(), 2);
  return rgba;
}

/**
 * A frame drawn in batches front to back (FramePlan::frontToBack), the decomposition of each
 * batch leaving out the cells behind the pixels the earlier batches made opaque
 * (Compositor::Opaque): its premultiplied image, and the cells left out. With `garbage`,
 * every fan the decomposition left unwritten is overwritten by a fan over the whole image
 * first: the compositor must not read it (its class says so).
 */
std::vector<float> CompositeFrontToBack(mtpt::FramePipeline& pipeline,
  const mtpt::CompositeSettings& s, std::size_t batch, bool garbage, std::size_t& hidden)
{
  mtpt::FramePlan plan;
  plan.target = mtpt::BatchTarget::Fans;
  plan.batchSize = batch;
  plan.frontToBack = true;
  plan.threads = 2;
  mtpt::Compositor compositor;
  compositor.Begin(s);
  std::vector<mtpt::Fan> fans;
  pipeline.DrawBatches(
    plan,
    [&](const mtpt::Batch& b)
    {
      fans.assign(b.fans, b.fans + b.count);
      for (std::size_t k = 0; k < b.count && garbage; ++k)
      {
        if (b.classes[k] == mtpt::ProjectionClass::Hidden)
        {
          mtpt::Fan& f = fans[k];
          f = mtpt::Fan{};
          f.centre = TetVertex{ 0.0f, -0.2f, 0.0f, 0.5f, 0.5f, 2.0f };
          f.boundary[0] = TetVertex{ -1.0f, -1.0f, 0.0f, 0.5f, 0.5f, 0.0f };
          f.boundary[1] = TetVertex{ 1.0f, -1.0f, 0.0f, 0.5f, 0.5f, 0.0f };
          f.boundary[2] = TetVertex{ 0.0f, 1.0f, 0.0f, 0.5f, 0.5f, 0.0f };
          f.count = 3;
          f.closed = 1;
        }
      }
      compositor.CompositeBehind(fans.data(), b.count, 2, nullptr, b.classes);
      return true;
    },
    &compositor.Opaque());
  hidden = pipeline.Stats().hidden;
  std::vector<float> rgba(4 * static_cast<std::size_t>(s.width) * s.height);
  compositor.Resolve(
    { 0, 0, s.width, s.height }, static_cast<const float*>(nullptr), rgba.data(), 2);
  return rgba;
}

TEST_P(CompositorSimd, BatchesFrontToBackGiveTheOneBatchImageAndSkipWhatIsHidden)
{
  // A mesh that turns most of its pixels opaque halfway through, seen obliquely; batches of
  // a few hundred cells. Drawn front to back the batches continue each tile's blending, so
  // the image is the one batch's bit for bit; the cells behind what turned opaque are not
  // decomposed, and their fans, left unwritten, are never read.
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(12, 7); // 10,368 tetrahedra
  std::vector<float> table;
  for (int i = 0; i < 64; ++i)
  {
    const float t = i / 63.0f;
    table.insert(table.end(), { t, 1 - t, 0.5f, 12.0f * (0.2f + t) });
  }
  mtpt::PreIntegrationTable integrals;
  for (const bool perspective : { false, true })
  {
    for (const mtpt::Shading shading :
      { mtpt::Shading::VTKCompatible, mtpt::Shading::PreIntegrated })
    {
      mtpt::FrameInput input;
      input.points = mesh.Points();
      input.cells = mesh.Cells();
      input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
      mtpt::test::ObliqueView(input, perspective);
      input.imageSize = { 90, 75 };
      auto s = Settings(90, 75, table);
      s.transferFunction.low = -1.0;
      s.transferFunction.high = 2.0;
      s.unitDistance = 0.5;
      integrals.Build(s.transferFunction);
      if (shading == mtpt::Shading::PreIntegrated)
      {
        s.UsePreIntegration(
          integrals, mtpt::PerspectiveInterpolation::FromProjection(input.projection));
      }
      const std::string what = std::string(perspective ? "perspective" : "orthographic") +
        (shading == mtpt::Shading::PreIntegrated ? ", pre-integrated" : ", VTK-compatible");
      mtpt::FramePipeline pipeline;
      ASSERT_TRUE(pipeline.Prepare(input, 2));
      const std::vector<float> whole = CompositeFans(pipeline, s);
      std::size_t opaque = 0;
      for (std::size_t i = 3; i < whole.size(); i += 4)
      {
        opaque += whole[i] >= mtpt::OpaqueAlpha ? 1 : 0;
      }
      ASSERT_GT(opaque, whole.size() / 4 / 3) << what; // a third of the pixels turn opaque
      for (const std::size_t batch : { std::size_t{ 300 }, std::size_t{ 2000 } })
      {
        std::size_t hidden = 0;
        const std::vector<float> batches = CompositeFrontToBack(pipeline, s, batch, true, hidden);
        EXPECT_EQ(0, std::memcmp(batches.data(), whole.data(), whole.size() * sizeof(float)))
          << what << ", batches of " << batch;
        EXPECT_GT(hidden, pipeline.SortedCount() / 10) << what << ", batches of " << batch;
      }
    }
  }
}

/// The scene of the tests that split segments (by depth ranges, by planes): a jittered
/// grid with a steep transfer function, seen from one point, in perspective or not.
struct SplitScene
{
  static constexpr int Width = 72, Height = 60;
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(10, 9);
  std::vector<float> table;
  mtpt::FrameInput input;
  mtpt::FramePipeline pipeline;
  mtpt::PreIntegrationTable integrals;

  explicit SplitScene(bool perspective)
  {
    for (int i = 0; i < 64; ++i)
    {
      const float t = i / 63.0f;
      this->table.insert(this->table.end(), { t, 1 - t, 0.5f, 3.0f * t * t });
    }
    this->input.points = this->mesh.Points();
    this->input.cells = this->mesh.Cells();
    this->input.scalars = { this->mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    mtpt::test::ObliqueView(this->input, perspective);
  }

  /// The compositor's settings for `shading`, without ranges or planes.
  mtpt::CompositeSettings SettingsFor(mtpt::Shading shading)
  {
    auto s = Settings(Width, Height, this->table);
    s.transferFunction.low = -1.0;
    s.transferFunction.high = 2.0;
    s.unitDistance = 0.5;
    this->integrals.Build(s.transferFunction);
    if (shading == mtpt::Shading::PreIntegrated)
    {
      s.UsePreIntegration(
        this->integrals, mtpt::PerspectiveInterpolation::FromProjection(this->input.projection));
    }
    return s;
  }
};

TEST(Compositor, DepthRangesSplitSegmentsExactly)
{
  // Depth peeling composites the volume between two window depths per pixel. The whole
  // range [0, 1] must give the unclipped image, and the part in front of a depth composited
  // over the part behind it must give it too: segments are cut where the depth crosses them,
  // with the length (and in pre-integrated shading the scalars) of each part.
  const int w = SplitScene::Width, h = SplitScene::Height;
  for (bool perspective : { false, true })
  {
    SplitScene scene(perspective);
    ASSERT_TRUE(scene.pipeline.Prepare(scene.input, 2));
    const mtpt::FrameInput& input = scene.input;
    mtpt::FramePipeline& pipeline = scene.pipeline;
    for (auto shading : { mtpt::Shading::VTKCompatible, mtpt::Shading::PreIntegrated })
    {
      SCOPED_TRACE(::testing::Message()
        << (perspective ? "perspective" : "orthographic")
        << (shading == mtpt::Shading::PreIntegrated ? ", pre-integrated" : ""));
      auto s = scene.SettingsFor(shading);
      const std::vector<float> whole = CompositeFans(pipeline, s);
      s.clipping = mtpt::DepthClipping::FromProjection(input.projection);
      // The window depth of the mesh's centre splits it in two.
      const double eyeZ = -mtpt::test::Apply(input.modelView, { 0, 0, 0 })[2];
      const mtpt::test::Vec3 centre = mtpt::test::Apply(input.projection, { 0, 0, -eyeZ });
      const float middle = static_cast<float>(0.5 * (centre[2] + 1.0));
      std::vector<float> ranges(2 * w * h), front, back, all, none;
      auto fill = [&](float nearDepth, float farDepth)
      {
        for (int i = 0; i < w * h; ++i)
        {
          ranges[2 * i] = nearDepth;
          ranges[2 * i + 1] = farDepth;
        }
        s.depthRange = ranges.data();
        return CompositeFans(pipeline, s);
      };
      all = fill(0.0f, 1.0f);
      front = fill(0.0f, middle);
      back = fill(middle, 1.0f);
      none = fill(1.0f, 0.0f);
      // Ranges asked only left of column 40: the pixels asked are the whole image's, the
      // others and the tile right of column 64, where none is asked, stay empty.
      for (int i = 0; i < w * h; ++i)
      {
        ranges[2 * i] = i % w < 40 ? 0.0f : 1.0f;
        ranges[2 * i + 1] = i % w < 40 ? 1.0f : 0.0f;
      }
      const std::vector<float> left = CompositeFans(pipeline, s);
      for (int i = 0; i < w * h; ++i)
      {
        for (int c = 0; c < 4; ++c)
        {
          ASSERT_NEAR(left[4 * i + c], i % w < 40 ? all[4 * i + c] : 0.0f, 1e-6f)
            << "pixel " << i % w << ", " << i / w;
        }
      }
      double worstAll = 0, worstSplit = 0, frontAlpha = 0, backAlpha = 0, wholeAlpha = 0;
      for (int i = 0; i < w * h; ++i)
      {
        for (int c = 0; c < 4; ++c)
        {
          const float over = front[4 * i + c] + (1.0f - front[4 * i + 3]) * back[4 * i + c];
          worstAll = std::max(worstAll, std::fabs(double(all[4 * i + c]) - whole[4 * i + c]));
          worstSplit = std::max(worstSplit, std::fabs(double(over) - whole[4 * i + c]));
          ASSERT_EQ(none[4 * i + c], 0.0f);
        }
        frontAlpha = std::max(frontAlpha, double(front[4 * i + 3]));
        backAlpha = std::max(backAlpha, double(back[4 * i + 3]));
        wholeAlpha = std::max(wholeAlpha, double(whole[4 * i + 3]));
      }
      std::printf("whole range %.2g, split %.2g; largest alpha front %.2f back %.2f whole %.2f\n",
        worstAll, worstSplit, frontAlpha, backAlpha, wholeAlpha);
      EXPECT_GT(frontAlpha, 0.3);
      EXPECT_GT(backAlpha, 0.3);
      EXPECT_LT(worstAll, 2e-5);
      // Split, the two parts are blended in the exact depth order at the cut, the whole in
      // the centroid order, which is not exact for every pair of cells: measured 6.5e-4 and
      // 8e-5 (VTK-compatible), 2.2e-3 and 2.3e-3 (pre-integrated, whose steps also differ).
      EXPECT_LT(worstSplit, shading == mtpt::Shading::PreIntegrated ? 5e-3 : 2e-3);
    }
  }
}

TEST(Compositor, ClippingPlanesCutSegmentsExactly)
{
  // A clipping plane keeps the part of each fragment's segment on its normal's side. A plane
  // that keeps everything changes nothing (bit for bit), one that keeps nothing leaves the
  // image empty, and the part a plane keeps composited over the part its opposite keeps
  // gives the whole image back, as a depth range split does. In an orthographic view a
  // plane facing the eye is a depth range: the two cut alike.
  const int w = SplitScene::Width, h = SplitScene::Height;
  for (bool perspective : { false, true })
  {
    SplitScene scene(perspective);
    ASSERT_TRUE(scene.pipeline.Prepare(scene.input, 2));
    const mtpt::FrameInput& input = scene.input;
    mtpt::FramePipeline& pipeline = scene.pipeline;
    // An oblique plane through the mesh's centre, in eye coordinates, whose normal points
    // away from the eye along every ray: it keeps the far part.
    const mtpt::test::Vec3 centre = mtpt::test::Apply(input.modelView, { 0, 0, 0 });
    const double n[3] = { 0.3, -0.2, -0.93 };
    const double d = -(n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2]);
    for (auto shading : { mtpt::Shading::VTKCompatible, mtpt::Shading::PreIntegrated })
    {
      SCOPED_TRACE(::testing::Message()
        << (perspective ? "perspective" : "orthographic")
        << (shading == mtpt::Shading::PreIntegrated ? ", pre-integrated" : ""));
      auto s = scene.SettingsFor(shading);
      s.clipping = mtpt::DepthClipping::FromProjection(input.projection);
      const std::vector<float> whole = CompositeFans(pipeline, s);
      auto clipped = [&](std::initializer_list<std::array<double, 4>> planes)
      {
        mtpt::CompositeSettings c = s;
        for (const auto& plane : planes)
        {
          std::copy(plane.begin(), plane.end(), c.clipPlanes.plane[c.clipPlanes.count++]);
        }
        return CompositeFans(pipeline, c);
      };
      const std::vector<float> everything = clipped({ { n[0], n[1], n[2], d + 100.0 } });
      const std::vector<float> nothing = clipped({ { n[0], n[1], n[2], d - 100.0 } });
      const std::vector<float> far = clipped({ { n[0], n[1], n[2], d } });
      const std::vector<float> near = clipped({ { -n[0], -n[1], -n[2], -d } });
      double worstSplit = 0, nearAlpha = 0, farAlpha = 0;
      for (int i = 0; i < w * h; ++i)
      {
        for (int c = 0; c < 4; ++c)
        {
          ASSERT_EQ(everything[4 * i + c], whole[4 * i + c]) << "pixel " << i;
          ASSERT_EQ(nothing[4 * i + c], 0.0f) << "pixel " << i;
          const float over = near[4 * i + c] + (1.0f - near[4 * i + 3]) * far[4 * i + c];
          worstSplit = std::max(worstSplit, std::fabs(double(over) - whole[4 * i + c]));
        }
        nearAlpha = std::max(nearAlpha, double(near[4 * i + 3]));
        farAlpha = std::max(farAlpha, double(far[4 * i + 3]));
      }
      std::printf("split by a plane %.2g; largest alpha near %.2f far %.2f\n", worstSplit,
        nearAlpha, farAlpha);
      EXPECT_GT(nearAlpha, 0.3);
      EXPECT_GT(farAlpha, 0.3);
      // As for depth ranges: the parts are blended in the exact order at the cut, the whole in
      // the centroid order.
      EXPECT_LT(worstSplit, shading == mtpt::Shading::PreIntegrated ? 5e-3 : 2e-3);
      if (perspective)
      {
        continue;
      }
      // Facing the eye, the plane e_z = centre z keeps what a window-depth range keeps.
      const mtpt::test::Vec3 ndc = mtpt::test::Apply(input.projection, centre);
      const float middle = static_cast<float>(0.5 * (ndc[2] + 1.0));
      std::vector<float> ranges(2 * w * h);
      for (int i = 0; i < w * h; ++i)
      {
        ranges[2 * i] = 0.0f;
        ranges[2 * i + 1] = middle;
      }
      mtpt::CompositeSettings r = s;
      r.depthRange = ranges.data();
      const std::vector<float> front = CompositeFans(pipeline, r);
      const std::vector<float> facing = clipped({ { 0.0, 0.0, 1.0, -centre[2] } });
      double worstFacing = 0;
      for (std::size_t k = 0; k < front.size(); ++k)
      {
        worstFacing = std::max(worstFacing, std::fabs(double(front[k]) - facing[k]));
      }
      std::printf("plane against depth range %.2g\n", worstFacing);
      EXPECT_LT(worstFacing, 2e-5);
    }
  }
}

} // namespace

namespace
{

/// One triangle slot: vertices a, b, c (window coordinates in a w x h window), each with its
/// front and back scalar and segment length; the slot's other triangles degenerate.
void TriangleSlot(const double (&x)[3], const double (&y)[3], const float (&front)[3],
  const float (&back)[3], const float (&length)[3], int w, int h, TetVertex vertices[5],
  std::uint32_t indices[12])
{
  for (int k = 0; k < 3; ++k)
  {
    vertices[k] = TetVertex{ Ndc(x[k], w), Ndc(y[k], h), 0.0f, front[k], back[k], length[k] };
  }
  vertices[3] = vertices[4] = vertices[0];
  const std::uint32_t local[12] = { 0, 1, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3 };
  std::copy(local, local + 12, indices);
}

/// TrianglesBeyondTheFixedPointRangeAreClippedNotDropped with one vertex `far` pixels off.
void ExpectClippedAsTheNearerDescription(double far)
{
  const int w = 40, h = 30;
  std::vector<float> table = { 0.2f, 0.4f, 1.0f, 0.5f, 1.0f, 0.6f, 0.1f, 3.0f };
  const double x[3] = { 5, 35, far }, y[3] = { 4, 8, 0.6 * far };
  const float front[3] = { 0.0f, 1.0f, 0.5f }, back[3] = { 0.2f, 0.9f, 0.7f },
              length[3] = { 0.0f, 0.5f, 3.0f };
  // The nearer description: vertex 2 moved to parameter t along the edges from vertex 0
  // and 1 would change the triangle; instead cut both edges 0-2 and 1-2 at t and split
  // the quadrilateral in two, with every attribute interpolated linearly (exact: all are
  // affine over the window).
  const double t = 60.0 / far;
  auto lerp = [t](double a, double b) { return a + t * (b - a); };
  const double x02 = lerp(x[0], x[2]), y02 = lerp(y[0], y[2]);
  const double x12 = lerp(x[1], x[2]), y12 = lerp(y[1], y[2]);
  auto lerpf = [t](const float(&v)[3], int k)
  { return static_cast<float>(v[k] + t * (static_cast<double>(v[2]) - v[k])); };
  TetVertex farSlot[5], nearSlots[10];
  std::uint32_t farIndices[12], nearIndices[24];
  TriangleSlot(x, y, front, back, length, w, h, farSlot, farIndices);
  // Quadrilateral 0, 1, 12, 02 as triangles (0, 1, 12) and (0, 12, 02).
  TriangleSlot({ x[0], x[1], x12 }, { y[0], y[1], y12 }, { front[0], front[1], lerpf(front, 1) },
    { back[0], back[1], lerpf(back, 1) }, { length[0], length[1], lerpf(length, 1) }, w, h,
    nearSlots, nearIndices);
  TriangleSlot({ x[0], x12, x02 }, { y[0], y12, y02 },
    { front[0], lerpf(front, 1), lerpf(front, 0) }, { back[0], lerpf(back, 1), lerpf(back, 0) },
    { length[0], lerpf(length, 1), lerpf(length, 0) }, w, h, nearSlots + 5, nearIndices + 12);
  for (std::uint32_t& i : nearIndices)
  {
    i += &i >= nearIndices + 12 ? 5 : 0;
  }
  for (const bool preIntegrated : { false, true })
  {
    mtpt::PreIntegrationTable integrals;
    auto settings = Settings(w, h, table);
    integrals.Build(settings.transferFunction);
    if (preIntegrated)
    {
      settings.UsePreIntegration(integrals, mtpt::PerspectiveInterpolation{});
    }
    mtpt::Compositor compositor;
    std::vector<float> clipped, reference;
    compositor.Composite(farSlot, farIndices, 1, settings, clipped, 2);
    compositor.Composite(nearSlots, nearIndices, 2, settings, reference, 2);
    int covered = 0;
    double worst = 0;
    for (std::size_t i = 0; i < clipped.size(); ++i)
    {
      worst = std::max(worst, static_cast<double>(std::fabs(clipped[i] - reference[i])));
      covered += i % 4 == 3 && reference[i] > 0.0f ? 1 : 0;
    }
    EXPECT_GT(covered, 200) << "the triangle covers a good part of the window";
    EXPECT_LT(worst, 1e-5) << (preIntegrated ? "pre-integrated" : "VTK-compatible");
  }
}

} // namespace

TEST_P(CompositorSimd, TrianglesBeyondTheFixedPointRangeAreClippedNotDropped)
{
  // A triangle with one vertex 10^8 or 10^24 pixels off screen (a near-plane piece seen from
  // inside the mesh): the fixed-point rasterizer cannot hold it, so it is clipped to a guard
  // band. The same plane given by a nearer vertex on the same two edges (attributes
  // interpolated there) must draw the same pixels with the same colours. At 10^24 a crossing
  // computed from the far vertex would land 10^8 pixels off the guard band.
  for (const double far : { 1e8, 1e24 })
  {
    SCOPED_TRACE(far);
    ExpectClippedAsTheNearerDescription(far);
  }
}

TEST_P(CompositorSimd, FragmentOpacityApproximationIsWithinFourUlpOfTheExactExponential)
{
  // The SIMD fragment loop computes 1 - exp(-density) with its own reduction and polynomial
  // (OpacityOfDensity). Its error, over densities from the thinnest segments (1e-30) to
  // saturation (1e4), must stay within 4 units in the last place of the float result
  // (relative 4 * 2^-24), so that thin segments keep their tiny opacities and thick ones
  // reach 1.
  std::vector<float> density;
  for (double e = -30; e <= 4; e += 0.001)
  {
    density.push_back(static_cast<float>(std::pow(10.0, e)));
  }
  density.push_back(0.0f);
  std::vector<float> opacity(density.size());
  mtpt::detail::OpacitiesOfDensities(density.data(), opacity.data(), density.size());
  double worst = 0;
  float worstAt = 0;
  for (std::size_t i = 0; i < density.size(); ++i)
  {
    const double exact = -std::expm1(-static_cast<double>(density[i]));
    ASSERT_GE(opacity[i], 0.0f) << density[i];
    ASSERT_LE(opacity[i], 1.0f) << density[i];
    const double error = exact > 0 ? std::fabs(opacity[i] - exact) / exact : opacity[i];
    if (error > worst)
    {
      worst = error;
      worstAt = density[i];
    }
  }
  EXPECT_LE(worst, 4.0 * std::ldexp(1.0, -24)) << "at density " << worstAt;
  EXPECT_STREQ(mtpt::detail::RasterTargetName(), hwy::TargetName(GetParam()));
  std::printf("fragment opacity: worst relative error %.3g (%.2f ulp) at density %g, %s\n", worst,
    worst / std::ldexp(1.0, -24), worstAt, mtpt::detail::RasterTargetName());
}

TEST_P(CompositorSimd, PreIntegratedSegmentsMatchTheScalarIntegration)
{
  // The fragment loop shades pre-integrated fragments a vector at a time, with the formulas
  // of PreIntegrationTable::Segment in single precision. On a table with sharp peaks (the
  // attenuation jumps 80-fold within an entry), over scalars inside, at and beyond its range,
  // zero to thick lengths (1 to 8 steps), the opacity and the premultiplied colour (what a
  // pixel receives) must match the double-precision function within 5e-5: a float entry
  // coordinate is within 1e-5 entries of the double one, and the attenuation at it moves by up
  // to 40 times that on this table.
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> table(4 * 97);
  for (std::size_t i = 0; i < table.size(); ++i)
  {
    const bool peak = (i / 4) % 13 == 5;
    table[i] = i % 4 == 3 ? (peak ? 40.0f : 0.5f * unit(random)) : unit(random);
  }
  table[4 * 20 + 3] = 0.0f; // a transparent entry
  const mtpt::TransferFunctionTable tf{ table.data(), 97, -1.0, 3.0 };
  mtpt::PreIntegrationTable integrals;
  integrals.Build(tf);
  std::vector<float> front, back, length;
  const float lengths[] = { 0.0f, 1e-7f, 1e-3f, 0.05f, 0.3f, 2.0f, 50.0f, -1.0f };
  for (int i = 0; i < 4001; ++i)
  {
    front.push_back(-1.5f + 5.0f * unit(random));
    // Nearby, far, equal and out-of-range back scalars.
    const int kind = i % 4;
    back.push_back(kind == 0 ? front.back()
        : kind == 1          ? front.back() + 0.01f * unit(random)
                             : -1.5f + 5.0f * unit(random));
    length.push_back(lengths[i % 8] * (0.5f + unit(random)));
  }
  front.push_back(std::nanf(""));
  back.push_back(0.5f);
  length.push_back(1.0f);
  std::vector<float> rgba(4 * front.size());
  mtpt::detail::PreIntegratedSegments(
    tf, integrals, front.data(), back.data(), length.data(), 0.7f, rgba.data(), front.size());
  double worst = 0;
  int opaque = 0;
  for (std::size_t i = 0; i < front.size(); ++i)
  {
    float expected[4];
    integrals.Segment(tf, front[i], back[i], length[i], 0.7f, expected);
    for (int c = 0; c < 4; ++c)
    {
      ASSERT_TRUE(std::isfinite(rgba[4 * i + c])) << i;
      const double weight[2] = { c < 3 ? rgba[4 * i + 3] : 1.0f, c < 3 ? expected[3] : 1.0f };
      worst = std::max(worst, std::fabs(weight[0] * rgba[4 * i + c] - weight[1] * expected[c]));
    }
    opaque += expected[3] > 0.5f ? 1 : 0;
  }
  EXPECT_LE(worst, 5e-5) << mtpt::detail::RasterTargetName();
  EXPECT_GT(opaque, 400) << "thick segments reach high opacity";
}

TEST_P(CompositorSimd, PreIntegratedStepsOfSubnormalAttenuationStayFinite)
{
  // An attenuation below the smallest normal float (a table entry of 1e-39, or a mean that
  // rounds there): 1 / tau overflows, and a colour channel whose integral is 0 must not turn
  // NaN. Every channel finite and in [0, 1], and the premultiplied colour what the
  // double-precision function gives, for one-step and many-step segments alike.
  const float tiny = 1e-39f;
  ASSERT_LT(tiny, std::numeric_limits<float>::min());
  const std::vector<float> table = { 1.0f, 0.0f, 0.5f, tiny, 1.0f, 0.0f, 0.5f, tiny };
  const mtpt::TransferFunctionTable tf{ table.data(), 2, 0.0, 1.0 };
  mtpt::PreIntegrationTable integrals;
  integrals.Build(tf);
  std::vector<float> front, back, length;
  for (const float l : { 1e-3f, 1.0f, 1e20f, 1e30f, 1e38f })
  {
    for (const float u : { 0.0f, 0.3f, 1.0f })
    {
      front.push_back(u);
      back.push_back(1.0f - u);
      length.push_back(l);
    }
  }
  std::vector<float> rgba(4 * front.size());
  mtpt::detail::PreIntegratedSegments(
    tf, integrals, front.data(), back.data(), length.data(), 1.0f, rgba.data(), front.size());
  for (std::size_t i = 0; i < front.size(); ++i)
  {
    float expected[4];
    integrals.Segment(tf, front[i], back[i], length[i], 1.0f, expected);
    for (int c = 0; c < 4; ++c)
    {
      ASSERT_TRUE(std::isfinite(rgba[4 * i + c]) && rgba[4 * i + c] >= 0.0f &&
        rgba[4 * i + c] <= 1.0f)
        << "segment " << i << " channel " << c << ": " << rgba[4 * i + c];
      const double premultiplied = c < 3 ? rgba[4 * i + 3] * rgba[4 * i + c] : rgba[4 * i + 3];
      const double exact = c < 3 ? expected[3] * expected[c] : expected[3];
      EXPECT_NEAR(premultiplied, exact, 5e-5) << "segment " << i << " channel " << c;
    }
  }
}

TEST_P(CompositorSimd, PreIntegratedSegmentsKeepTheirDigitsOnASteepTable)
{
  // A table whose attenuation falls from 1e4 to 0 across its first entry and stays 0 (the
  // fuzzer's): a thick segment from the transparent half into the steep one sees its colour
  // in the sliver of a step where the attenuation is small, and a step inside the steep
  // entry near its end sees only small attenuation. There the means of tau and c tau must
  // not come from differences of integrals of about 5000, whose single-precision rounding
  // (3e-4) a small mean (0.06 and less) cannot absorb: that way the premultiplied colour is
  // up to 0.88 off on these segments, measured on every instruction set. The opacity and the
  // premultiplied colour must match the double-precision function within 1e-4, and red and
  // green, whose tables differ by at most 3.1e-4, within that of each other.
  const float table[] = { 0.890196085f, 0.890196085f, 0.890196085f, 1e4f, //
    0.109804399f, 0.10949707f, 1.0f, 0.0f,                                //
    1.0f, 1.0f, 0.999571085f, 0.0f };
  const mtpt::TransferFunctionTable tf{ table, 3, 0.0, 1.0 };
  mtpt::PreIntegrationTable integrals;
  integrals.Build(tf);
  std::mt19937 random(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> front, back, length;
  for (int i = 0; i < 4000; ++i)
  {
    if (i % 2 == 0)
    {
      front.push_back(0.5f + 0.5f * unit(random)); // transparent
      back.push_back(0.5f * unit(random));         // steep
    }
    else
    {
      front.push_back(0.5f - 1e-3f * unit(random)); // the steep entry's end
      back.push_back(0.5f - 1e-3f * unit(random));
    }
    length.push_back(600.0f * unit(random));
  }
  std::vector<float> rgba(4 * front.size());
  mtpt::detail::PreIntegratedSegments(
    tf, integrals, front.data(), back.data(), length.data(), 1.0f, rgba.data(), front.size());
  double worst = 0, worstRedGreen = 0;
  int opaque = 0;
  for (std::size_t i = 0; i < front.size(); ++i)
  {
    float expected[4];
    integrals.Segment(tf, front[i], back[i], length[i], 1.0f, expected);
    for (int c = 0; c < 4; ++c)
    {
      const double weight[2] = { c < 3 ? rgba[4 * i + 3] : 1.0f, c < 3 ? expected[3] : 1.0f };
      worst = std::max(worst, std::fabs(weight[0] * rgba[4 * i + c] - weight[1] * expected[c]));
    }
    worstRedGreen = std::max(worstRedGreen,
      std::fabs(static_cast<double>(rgba[4 * i]) - rgba[4 * i + 1]) * rgba[4 * i + 3]);
    opaque += expected[3] > 0.5f ? 1 : 0;
  }
  EXPECT_LE(worst, 1e-4) << mtpt::detail::RasterTargetName();
  EXPECT_LE(worstRedGreen, 3.1e-4 + 1e-4) << mtpt::detail::RasterTargetName();
  EXPECT_GT(opaque, 1000) << "thick segments reach high opacity";
  std::printf("steep table: worst %.3g against double, red and green %.3g apart, %s\n", worst,
    worstRedGreen, mtpt::detail::RasterTargetName());
}

namespace
{

/// Every tile of a width x height image drawn by detail::RasterizeTile from all of `fans`, in
/// visibility order (each tile clips them; drawn front to back, as the compositor draws
/// them), tile after tile, with an opaque depth image.
template <typename Fans>
std::vector<float> DrawTiles(const mtpt::detail::RasterFrame& frame, const Fans& fans,
  const std::vector<float>& depth, mtpt::detail::RasterCounts& counts,
  const std::vector<mtpt::LightFactors>& lights = {})
{
  constexpr int T = mtpt::TileSize;
  std::vector<float> tiles;
  for (int y0 = 0; y0 < frame.height; y0 += T)
  {
    for (int x0 = 0; x0 < frame.width; x0 += T)
    {
      std::vector<float> rgba(4 * T * T, 0.0f), tileDepth(T * T, 1.0f);
      mtpt::detail::TileTarget tile;
      tile.x0 = x0;
      tile.y0 = y0;
      tile.width = std::min(T, frame.width - x0);
      tile.height = std::min(T, frame.height - y0);
      for (int j = 0; j < tile.height; ++j)
      {
        for (int i = 0; i < tile.width; ++i)
        {
          tileDepth[j * T + i] = depth[(y0 + j) * frame.width + x0 + i];
        }
      }
      tile.rgba = rgba.data();
      tile.depth = tileDepth.data();
      const std::vector<mtpt::Fan> frontToBack(fans.rbegin(), fans.rend());
      const std::vector<mtpt::LightFactors> lit(lights.rbegin(), lights.rend());
      mtpt::detail::RasterizeTile(frame, tile, frontToBack.data(), frontToBack.size(), counts,
        lit.empty() ? nullptr : lit.data());
      tiles.insert(tiles.end(), rgba.begin(), rgba.end());
    }
  }
  return tiles;
}

} // namespace

namespace
{

/// Draws `fans` (visibility order) with the fan path and with the triangle path alone, and
/// returns the largest channel difference; the counts of each in `byFans`, `byTriangles`.
double FanAgainstTrianglePath(mtpt::detail::RasterFrame frame,
  const mtpt::LargeVector<mtpt::Fan>& fans, mtpt::detail::RasterCounts& byFans,
  mtpt::detail::RasterCounts& byTriangles, std::size_t& drawn,
  const std::vector<mtpt::LightFactors>& lights = {})
{
  std::vector<float> depth(static_cast<std::size_t>(frame.width) * frame.height);
  for (int y = 0; y < frame.height; ++y)
  {
    for (int x = 0; x < frame.width; ++x)
    {
      depth[y * frame.width + x] = 0.55f + 0.5f * static_cast<float>(x) / frame.width;
    }
  }
  frame.fanPath = true;
  const std::vector<float> fanImage = DrawTiles(frame, fans, depth, byFans, lights);
  frame.fanPath = false;
  const std::vector<float> triangleImage = DrawTiles(frame, fans, depth, byTriangles, lights);
  double worst = fanImage.size() == triangleImage.size() ? 0.0 : 1.0;
  drawn = 0;
  for (std::size_t i = 0; i < std::min(fanImage.size(), triangleImage.size()); ++i)
  {
    worst = std::max(worst, static_cast<double>(std::fabs(fanImage[i] - triangleImage[i])));
    drawn += fanImage[i] != 0.0f ? 1 : 0;
  }
  return worst;
}

} // namespace

TEST_P(CompositorSimd, FanPathDrawsTheTrianglesImage)
{
  // VTK-compatible fans are drawn whole (FanRaster-inl.h): coverage by the silhouette's edges,
  // each pixel's triangle chosen by the spokes, the triangles' planes set up together. That
  // must be the image of drawing the triangles one by one: the same pixels exactly (the same
  // fragment count), each with its own triangle's values up to the rounding of the set-up
  // (a pixel given a neighbouring triangle's planes would be off by far more). A jittered
  // grid seen in perspective from near (fans from under a pixel to over a tile, spanning
  // tile borders), at two image sizes, behind an opaque surface cutting through the volume.
  // Faint, nothing becomes opaque; dense, most pixels do, and the fan path skips fans wholly
  // behind opaque pixels (both skip the fragments there): then the images may differ by what
  // a pixel at the threshold of opacity skips (OpaqueAlpha, 2^-11).
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(9, 5);
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  input.modelView = mtpt::test::LookAt({ 0.7, 1.1, 2.6 }, { 0.1, 0, 0 }, { 0, 1, 0 });
  input.projection = mtpt::test::Perspective(50, 1.3, 0.5, 10);
  input.perspective = true;
  mtpt::FramePipeline pipeline;
  ASSERT_TRUE(pipeline.Run(input, 2));
  pipeline.DecomposeFans(0, pipeline.TetrahedronCount(), 2);
  std::vector<mtpt::LightFactors> lights(pipeline.FanCount());
  std::mt19937 random(3);
  std::uniform_real_distribution<float> factor(0.0f, 1.2f);
  for (mtpt::LightFactors& l : lights)
  {
    l = { { factor(random), factor(random), factor(random), 0 },
      { 0.3f * factor(random), 0.3f * factor(random), 0.3f * factor(random), 0 } };
  }
  for (const float density : { 0.3f, 30.0f })
  {
    std::vector<float> table;
    for (int i = 0; i < 48; ++i)
    {
      const float t = i / 47.0f;
      table.insert(table.end(), { t, 0.8f - 0.5f * t, 0.3f + 0.6f * t, density * t });
    }
    for (const auto& size : { std::make_pair(150, 115), std::make_pair(611, 470) })
    {
      mtpt::detail::RasterFrame frame;
      frame.width = size.first;
      frame.height = size.second;
      frame.transferFunction = { table.data(), 48, -2.0, 3.0 };
      frame.inverseUnit = 1.0f / 0.3f;
      mtpt::detail::RasterCounts byFans, byTriangles, litByFans, litByTriangles;
      std::size_t drawn = 0, litDrawn = 0;
      const double worst =
        FanAgainstTrianglePath(frame, pipeline.Fans(), byFans, byTriangles, drawn);
      // Lit (Lighting.h), each fan by factors of its own: the fan path lights each fragment
      // with its own fan's factors, as the triangle path does.
      const double litWorst =
        FanAgainstTrianglePath(frame, pipeline.Fans(), litByFans, litByTriangles, litDrawn, lights);
      const bool faint = density < 1;
      EXPECT_LE(litWorst, faint ? 4e-6 : 1.0 / 2048 + 4e-6);
      EXPECT_EQ(litByFans.fragments, byFans.fragments);
      EXPECT_LE(worst, faint ? 2e-6 : 1.0 / 2048 + 2e-6)
        << size.first << "x" << size.second << ", " << mtpt::detail::RasterTargetName();
      EXPECT_GT(drawn, 4 * static_cast<std::size_t>(frame.width) * frame.height / 10)
        << "a substantial part of the image is drawn";
      if (faint)
      {
        EXPECT_EQ(byFans.fragments, byTriangles.fragments);
        EXPECT_EQ(byFans.hidden, 0u);
      }
      else if (GetParam() != HWY_SCALAR) // one lane: every fan takes the triangle path
      {
        EXPECT_GT(byFans.hidden, byFans.triangles / 20) << "fans behind opaque pixels skipped";
        EXPECT_LT(byFans.fragments, byTriangles.fragments);
      }
    }
  }
}

TEST_P(CompositorSimd, FanPathReducesAsTheTrianglePath)
{
  // The blend modes other than composite take the fan path too (the scalars at the segments'
  // ends, perspective-exact in perspective views, and the segments' lengths): the same pixels
  // as the triangle path, each with its own triangle's reduction up to the rounding of the
  // set-up.
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(9, 5);
  std::vector<float> table;
  for (int i = 0; i < 48; ++i)
  {
    const float t = i / 47.0f;
    table.insert(table.end(), { t, 0.8f - 0.5f * t, 0.3f + 0.6f * t, t });
  }
  for (bool perspective : { false, true })
  {
    mtpt::FrameInput input;
    input.points = mesh.Points();
    input.cells = mesh.Cells();
    input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    mtpt::test::ObliqueView(input, perspective);
    input.ordered = false;
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Run(input, 2));
    pipeline.DecomposeFans(0, pipeline.TetrahedronCount(), 2);
    mtpt::IntensityTable intensity;
    intensity.Build({ table.data(), 48, -2.0, 3.0 });
    for (auto mode : { mtpt::BlendMode::MaximumIntensity, mtpt::BlendMode::MinimumIntensity,
           mtpt::BlendMode::AverageIntensity, mtpt::BlendMode::Additive })
    {
      mtpt::detail::RasterFrame frame;
      frame.width = 211;
      frame.height = 170;
      frame.transferFunction = { table.data(), 48, -2.0, 3.0 };
      frame.blendMode = mode;
      frame.intensity = &intensity;
      frame.averageRange[0] = 10.0; // entry coordinates
      frame.averageRange[1] = 30.0;
      frame.interpolation = mtpt::PerspectiveInterpolation::FromProjection(input.projection);
      mtpt::detail::RasterCounts byFans, byTriangles;
      std::size_t drawn = 0;
      const double worst =
        FanAgainstTrianglePath(frame, pipeline.Fans(), byFans, byTriangles, drawn);
      SCOPED_TRACE(::testing::Message()
        << (perspective ? "perspective" : "orthographic") << ", " << static_cast<int>(mode) << ", "
        << mtpt::detail::RasterTargetName());
      std::printf("mode %d, %s: worst %.3g\n", static_cast<int>(mode),
        perspective ? "perspective" : "orthographic", worst);
      // Measured: at most 1.4e-4, in entry coordinates up to 47 (maximum, minimum) or sums
      // of lengths up to about 3.
      EXPECT_LE(worst, 1e-3);
      EXPECT_GT(drawn, static_cast<std::size_t>(frame.width) * frame.height / 10);
      EXPECT_EQ(byFans.fragments, byTriangles.fragments);
      if (GetParam() != HWY_SCALAR)
      {
        // The fan path sets up a fan's triangles together, the triangle path only those that
        // cover a pixel: more set-ups show that fans were drawn whole.
        EXPECT_GT(byFans.triangles, byTriangles.triangles);
      }
    }
  }
}

TEST_P(CompositorSimd, FanPathShadesPreIntegratedAsTheTrianglePath)
{
  // Pre-integrated fans take the fan path too (the scalars at the segments' ends,
  // perspective-exact in perspective views, and the segments' lengths, each lane's segment
  // shaded by the same single-precision function as the triangle path's queued fragments):
  // the same pixels, each with its own triangle's segment up to the rounding of the set-up.
  // Where fans the fan path declines (too large, folded) come between others, the triangle
  // path's queued fragments must be blended before the next fan: else the tile's fragments
  // leave their front-to-back order (shown by drawing the queue only at the tile's end:
  // 0.024 off in the dense perspective image). Faint, nothing becomes opaque; dense, most pixels
  // do, and the two paths may differ by what a pixel at the threshold of opacity skips (2^-11).
  const mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(9, 5);
  for (bool perspective : { false, true })
  {
    mtpt::FrameInput input;
    input.points = mesh.Points();
    input.cells = mesh.Cells();
    input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    input.modelView = mtpt::test::LookAt({ 0.7, 1.1, 2.6 }, { 0.1, 0, 0 }, { 0, 1, 0 });
    input.projection = perspective ? mtpt::test::Perspective(50, 1.3, 0.5, 10)
                                   : mtpt::test::Ortho(-1.6, 1.6, -1.2, 1.2, 0.5, 10);
    input.perspective = perspective;
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Run(input, 2));
    pipeline.DecomposeFans(0, pipeline.TetrahedronCount(), 2);
    for (const float density : { 0.3f, 30.0f })
    {
      std::vector<float> table;
      for (int i = 0; i < 48; ++i)
      {
        const float t = i / 47.0f;
        table.insert(table.end(), { t, 0.8f - 0.5f * t, 0.3f + 0.6f * t, density * t * t });
      }
      mtpt::detail::RasterFrame frame;
      // Dense, larger: fans over FanExtentLimit come between the others.
      frame.width = density < 1 ? 611 : 1000;
      frame.height = density < 1 ? 470 : 770;
      frame.transferFunction = { table.data(), 48, -2.0, 3.0 };
      frame.inverseUnit = 1.0f / 0.3f;
      mtpt::PreIntegrationTable integrals;
      integrals.Build(frame.transferFunction);
      frame.preIntegration = &integrals;
      frame.interpolation = mtpt::PerspectiveInterpolation::FromProjection(input.projection);
      mtpt::detail::RasterCounts byFans, byTriangles;
      std::size_t drawn = 0;
      const double worst =
        FanAgainstTrianglePath(frame, pipeline.Fans(), byFans, byTriangles, drawn);
      SCOPED_TRACE(::testing::Message()
        << (perspective ? "perspective" : "orthographic") << ", density " << density << ", "
        << mtpt::detail::RasterTargetName());
      std::printf("%s, density %g: worst %.3g\n", perspective ? "perspective" : "orthographic",
        density, worst);
      const bool faint = density < 1;
      EXPECT_LE(worst, faint ? 2e-5 : 1.0 / 2048 + 2e-5);
      EXPECT_GT(drawn, 4 * static_cast<std::size_t>(frame.width) * frame.height / 10);
      if (GetParam() == HWY_SCALAR) // one lane: every fan takes the triangle path
      {
        continue;
      }
      if (faint)
      {
        EXPECT_EQ(byFans.fragments, byTriangles.fragments);
        // The fan path sets up a fan's triangles together, the triangle path only those that
        // cover a pixel: more set-ups show that fans were drawn whole.
        EXPECT_GT(byFans.triangles, byTriangles.triangles);
      }
      else
      {
        EXPECT_GT(byFans.hidden, 0u) << "fans behind opaque pixels skipped";
      }
    }
  }
}

TEST_P(CompositorSimd, FanPathCoversEdgesThroughPixelCentresByTheTopLeftRule)
{
  // Fans whose every corner and edge lies on pixel centres: squares of 6 x 6 pixels sharing
  // their edges (horizontal and vertical edges through centres), each a fan of 4 triangles
  // around its centre, alternately clockwise and counter-clockwise, and diamonds (diagonal
  // edges through centres) beside them. The fan path must cover every pixel of the squares'
  // union exactly once by the top-left rule (the left and top edges own their centres), and
  // cover what the triangle path covers, pixel for pixel.
  const int w = 40, h = 20;
  mtpt::detail::RasterFrame frame;
  frame.width = w;
  frame.height = h;
  const std::vector<float> table = ConstantTable(1.0f, 0.5f, 0.25f, 1.0f);
  frame.transferFunction = { table.data(), 2, 0.0, 1.0 };
  auto vertex = [&](double x, double y) {
    return TetVertex{ Ndc(x, w), Ndc(y, h), 0.0f, 0.5f, 0.5f, 0.3f };
  };
  std::vector<mtpt::Fan> fans;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 2; ++j)
    {
      const double x0 = 2.5 + 6 * i, y0 = 3.5 + 6 * j;
      mtpt::Fan fan{};
      const double xs[4] = { x0, x0 + 6, x0 + 6, x0 }, ys[4] = { y0, y0, y0 + 6, y0 + 6 };
      for (int k = 0; k < 4; ++k)
      {
        const int c = (i + j) % 2 ? 3 - k : k; // clockwise or counter-clockwise
        fan.boundary[k] = vertex(xs[c], ys[c]);
      }
      fan.centre = vertex(x0 + 3, y0 + 3);
      fan.count = 4;
      fan.closed = 1;
      fans.push_back(fan);
    }
  }
  for (const double cx : { 26.5, 33.5 }) // diamonds: corners 3 pixels from their centres
  {
    mtpt::Fan fan{};
    fan.boundary[0] = vertex(cx + 3, 10.5);
    fan.boundary[1] = vertex(cx, 13.5);
    fan.boundary[2] = vertex(cx - 3, 10.5);
    fan.boundary[3] = vertex(cx, 7.5);
    fan.centre = vertex(cx, 10.5);
    fan.count = 4;
    fan.closed = 1;
    fans.push_back(fan);
  }
  const std::vector<float> depth(w * h, 1.0f);
  mtpt::detail::RasterCounts byFans, byTriangles;
  const std::vector<float> fanImage = DrawTiles(frame, fans, depth, byFans);
  frame.fanPath = false;
  const std::vector<float> triangleImage = DrawTiles(frame, fans, depth, byTriangles);
  const float once = 1.0f - std::exp(-0.3f);
  constexpr int T = mtpt::TileSize;
  for (int y = 0; y < h; ++y)
  {
    for (int x = 0; x < w; ++x)
    {
      const std::size_t alpha = 3 * T * T + static_cast<std::size_t>(y) * T + x;
      ASSERT_EQ(fanImage[alpha], triangleImage[alpha]) << x << "," << y;
      const bool square = x >= 2 && x <= 19 && y >= 4 && y <= 15;
      if (x <= 20)
      {
        ASSERT_NEAR(fanImage[alpha], square ? once : 0.0f, 1e-6) << x << "," << y;
      }
    }
  }
  EXPECT_EQ(byFans.fragments, byTriangles.fragments);
  EXPECT_GT(byFans.fragments, 18u * 12u);
}

INSTANTIATE_TEST_SUITE_P(InstructionSets, CompositorSimd,
  ::testing::ValuesIn(hwy::SupportedAndGeneratedTargets()),
  [](const ::testing::TestParamInfo<std::int64_t>& info)
  { return std::string(hwy::TargetName(info.param)); });
