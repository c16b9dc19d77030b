// SPDX-License-Identifier: BSD-3-Clause
// Culling (opacity, frustum), reuse of stage results across frames, nearly-sorted re-sorts
// and batched decomposition: each must leave the image exactly as the full frame draws it.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/Culling.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/ReferenceRenderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

using mtpt::TetVertex;
using mtpt::test::JitteredGrid;
using mtpt::test::LookAt;
using mtpt::test::TetMesh;

/// Opacity 0 below `edge` and a ramp above it, colour varying everywhere.
std::vector<float> EdgeTable(int size, float edge)
{
  std::vector<float> table;
  for (int i = 0; i < size; ++i)
  {
    const float t = static_cast<float>(i) / (size - 1);
    table.insert(table.end(), { t, 0.4f, 1 - t, t <= edge ? 0.0f : 4.0f * (t - edge) });
  }
  return table;
}

mtpt::FrameInput Frame(const TetMesh& mesh, double azimuth, bool perspective)
{
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  const double r = 4.0;
  input.modelView =
    LookAt({ r * std::sin(azimuth), 1.2, r * std::cos(azimuth) }, { 0, 0, 0 }, { 0, 1, 0 });
  input.projection =
    perspective ? mtpt::test::Perspective(45, 1.0, 1, 10) : mtpt::test::Ortho(-2, 2, -2, 2, 1, 10);
  input.perspective = perspective;
  input.imageSize = { 48, 48 };
  return input;
}

/// The pipeline's current frame composited with `table` over [-2, 3], in batches of
/// `batch` fans (0: one batch), as the CPU backend composites it.
std::vector<float> Composite(mtpt::FramePipeline& pipeline, const mtpt::FrameInput& input,
  const std::vector<float>& table, std::size_t batch = 0)
{
  mtpt::CompositeSettings settings;
  settings.width = input.imageSize.width;
  settings.height = input.imageSize.height;
  settings.transferFunction = { table.data(), static_cast<int>(table.size() / 4), -2.0, 3.0 };
  settings.unitDistance = 0.3;
  mtpt::Compositor compositor;
  compositor.Begin(settings);
  const std::size_t total = pipeline.SortedCount();
  const std::size_t step = batch ? batch : std::max<std::size_t>(total, 1);
  for (std::size_t first = 0; first < total; first += step)
  {
    pipeline.DecomposeFans(first, step, 2);
    compositor.Composite(pipeline.Fans().data(), pipeline.FanCount(), 2);
  }
  std::vector<float> image(4 * static_cast<std::size_t>(settings.width) * settings.height);
  compositor.Resolve({ 0, 0, settings.width, settings.height }, nullptr, image.data(), 2);
  return image;
}

bool SameImage(const std::vector<float>& a, const std::vector<float>& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(Culling, CellScalarRangesOfPointAndCellScalars)
{
  TetMesh mesh;
  mesh.points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1 };
  mesh.scalars = { 0.5f, -1.0f, 2.0f, 0.25f, std::numeric_limits<float>::quiet_NaN() };
  mesh.AddTetrahedron(0, 1, 2, 3);
  mesh.AddTetrahedron(1, 2, 3, 4); // a NaN scalar
  mesh.AddTetrahedron(0, 1, 2, 9); // id out of range
  std::vector<float> ranges(6);
  mtpt::ComputeCellScalarRanges(mesh.Cells(), 5,
    { mesh.scalars.data(), mtpt::ScalarsView::Association::Points }, ranges.data(), 2);
  EXPECT_EQ(ranges[0], -1.0f);
  EXPECT_EQ(ranges[1], 2.0f);
  for (int i = 2; i < 6; ++i)
  {
    EXPECT_TRUE(std::isnan(ranges[i])) << i;
  }
  const std::vector<float> cellScalars = { 7.0f, -3.0f, 1.0f };
  mtpt::ComputeCellScalarRanges(mesh.Cells(), 5,
    { cellScalars.data(), mtpt::ScalarsView::Association::Cells }, ranges.data(), 3);
  EXPECT_EQ(ranges[0], 7.0f);
  EXPECT_EQ(ranges[1], 7.0f);
  EXPECT_EQ(ranges[2], -3.0f);
  EXPECT_TRUE(std::isnan(ranges[4])); // the bad cell stays undrawable
}

TEST(Culling, OpacityCullingNeverHidesAVisibleScalar)
{
  // Random tables with long zero runs; for random intervals, "not visible" must mean that
  // every scalar in the interval looks up opacity exactly 0 (dense check), and intervals
  // well inside a non-zero run must be visible.
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial)
  {
    const int size = 16 + trial * 7;
    std::vector<float> table(4 * size, 0.0f);
    for (int i = 0; i < size; ++i)
    {
      table[4 * i + 3] = (i / 5) % 3 == 1 ? unit(random) + 0.01f : 0.0f;
    }
    const mtpt::TransferFunctionTable tf{ table.data(), size, -1.0, 2.0 };
    mtpt::OpacityCulling culling;
    culling.SetTable(tf);
    int hidden = 0, shown = 0;
    for (int q = 0; q < 400; ++q)
    {
      float a = -1.5f + 4.0f * unit(random), b = a + 0.3f * unit(random);
      if (culling.Visible(a, b))
      {
        ++shown;
        continue;
      }
      ++hidden;
      for (int k = 0; k <= 200; ++k)
      {
        float rgba[4];
        tf.Lookup(a + (b - a) * k / 200.0f, rgba);
        ASSERT_EQ(rgba[3], 0.0f) << "culled [" << a << ", " << b << "] reads opacity at " << k;
      }
    }
    EXPECT_GT(hidden, 0);
    EXPECT_GT(shown, 0);
  }
  // Exact expectations on a step: opacity 0 for scalars up to 0.5 of the range.
  const std::vector<float> table = EdgeTable(101, 0.5f);
  mtpt::OpacityCulling culling;
  culling.SetTable({ table.data(), 101, 0.0, 1.0 });
  EXPECT_FALSE(culling.Visible(0.0f, 0.3f));
  EXPECT_FALSE(culling.Visible(-5.0f, 0.47f));
  EXPECT_TRUE(culling.Visible(0.2f, 0.7f));
  EXPECT_TRUE(culling.Visible(0.9f, 5.0f));
  EXPECT_FALSE(culling.Visible(std::numeric_limits<float>::quiet_NaN(), 1.0f));
}

TEST(Culling, TheMeshesCellsAreSelectedAsTheirRangesSelectThem)
{
  // The culling stage finds each cell's range on the way (no ranges stored): its list must
  // be the one the stored ranges select, for every thread count, with cells that are not
  // drawable (a NaN scalar); and the list it holds must be recognised, and no list with an
  // id more, less or twice.
  TetMesh mesh = JitteredGrid(9, 11);
  for (std::size_t p = 0; p < mesh.scalars.size(); ++p)
  {
    mesh.scalars[p] = 0.5f + 0.4f * mesh.points[3 * p] + 0.05f * mesh.points[3 * p + 1];
  }
  mesh.scalars[17] = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> table(4 * 64, 0.0f);
  for (int i = 0; i < 64; ++i)
  {
    table[4 * i + 3] = (i / 6) % 4 == 1 ? 0.5f : 0.0f;
  }
  mtpt::OpacityCulling culling;
  culling.SetTable({ table.data(), 64, 0.0, 1.0 });
  const mtpt::CellsView cells = mesh.Cells();
  const std::size_t n = cells.cellCount, points = mesh.points.size() / 3;
  const mtpt::ScalarsView scalars{ mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  std::vector<float> ranges(2 * n);
  mtpt::ComputeCellScalarRanges(cells, points, scalars, ranges.data(), 2);
  std::vector<std::uint32_t> list(n);
  list.resize(culling.SelectVisibleCells(ranges.data(), n, list.data(), 3));
  std::vector<std::uint32_t> hidden;
  for (std::size_t c = 0; c < n; ++c)
  {
    if (!std::binary_search(list.begin(), list.end(), c))
    {
      hidden.push_back(static_cast<std::uint32_t>(c));
    }
  }
  ASSERT_GT(list.size(), n / 10);
  ASSERT_GT(hidden.size(), n / 10);
  for (int threads : { 1, 2, 3, 8 })
  {
    SCOPED_TRACE(::testing::Message() << "threads=" << threads);
    std::vector<std::uint32_t> found(n);
    found.resize(culling.SelectVisibleCells(cells, points, scalars, found.data(), threads));
    EXPECT_EQ(found, list);
    EXPECT_TRUE(culling.SelectsExactly(cells, points, scalars, list.data(), list.size(), threads));
    for (std::size_t k = 0; k < list.size(); k += 1 + list.size() / 7)
    {
      std::vector<std::uint32_t> fewer = list;
      fewer.erase(fewer.begin() + static_cast<std::ptrdiff_t>(k));
      EXPECT_FALSE(
        culling.SelectsExactly(cells, points, scalars, fewer.data(), fewer.size(), threads));
    }
    for (std::size_t k = 0; k < hidden.size(); k += 1 + hidden.size() / 7)
    {
      std::vector<std::uint32_t> more = list;
      more.insert(std::upper_bound(more.begin(), more.end(), hidden[k]), hidden[k]);
      EXPECT_FALSE(
        culling.SelectsExactly(cells, points, scalars, more.data(), more.size(), threads));
    }
    std::vector<std::uint32_t> twice = list; // the last: no visible cell after it
    twice.push_back(list.back());
    EXPECT_FALSE(
      culling.SelectsExactly(cells, points, scalars, twice.data(), twice.size(), threads));
    std::vector<std::uint32_t> beyond = list;
    beyond.push_back(static_cast<std::uint32_t>(n));
    EXPECT_FALSE(
      culling.SelectsExactly(cells, points, scalars, beyond.data(), beyond.size(), threads));
  }
}

TEST(FramePipeline, OpacityAndFrustumCullingLeaveTheImageUnchanged)
{
  const TetMesh mesh = JitteredGrid(12, 3);               // 10,368 tetrahedra
  const std::vector<float> table = EdgeTable(256, 0.62f); // hides most of the scalar range
  for (bool perspective : { false, true })
  {
    SCOPED_TRACE(perspective ? "perspective" : "orthographic");
    mtpt::FrameInput input = Frame(mesh, 0.4, perspective);
    input.projection = perspective ? mtpt::test::Perspective(25, 1.0, 1, 10)
                                   : mtpt::test::Ortho(-1.2, 0.8, -1, 1, 1, 10); // crops
    mtpt::FrameInput unculled = input; // no culling of any kind
    unculled.cullFrustum = false;
    unculled.imageSize = {};
    mtpt::FramePipeline all;
    ASSERT_TRUE(all.Prepare(unculled, 2));
    EXPECT_EQ(all.SortedCount(), mesh.CellCount());
    const std::vector<float> reference = Composite(all, input, table);

    input.cullFrustum = true;
    input.opacity = { table.data(), 256, -2.0, 3.0 };
    mtpt::FramePipeline culled;
    ASSERT_TRUE(culled.Prepare(input, 2));
    const mtpt::FrameStats& stats = culled.Stats();
    // Expected opacity culls, counted independently: cells whose four scalars lie where
    // the table (and one entry of margin) is zero.
    std::size_t expectedOpacity = 0;
    for (std::size_t c = 0; c < mesh.CellCount(); ++c)
    {
      float high = -1e30f;
      for (int i = 0; i < 4; ++i)
      {
        high = std::max(high, mesh.scalars[mesh.connectivity[4 * c + i]]);
      }
      const int entry = static_cast<int>((high + 2.0f) * (255.0f / 5.0f)); // floor
      expectedOpacity += entry + 2 <= static_cast<int>(0.62f * 255.0f) ? 1 : 0;
    }
    EXPECT_EQ(stats.opacityCulled, expectedOpacity);
    EXPECT_GT(stats.opacityCulled, mesh.CellCount() / 2);
    EXPECT_GT(stats.frustumCulled, 0u);
    EXPECT_EQ(stats.opacityCulled + stats.frustumCulled + stats.pixelCulled + stats.sorted,
      mesh.CellCount());
    const std::vector<float> image = Composite(culled, input, table);
    EXPECT_TRUE(SameImage(reference, image));
    float alpha = 0;
    for (std::size_t i = 3; i < image.size(); i += 4)
    {
      alpha = std::max(alpha, image[i]);
    }
    EXPECT_GT(alpha, 0.2f); // the visible part is drawn
  }
}

TEST(FramePipeline, ReuseRecomputesOnlyWhatChanged)
{
  const TetMesh mesh = JitteredGrid(10, 4);
  std::vector<float> table = EdgeTable(128, 0.5f);
  mtpt::FrameInput input = Frame(mesh, 0.3, true);
  input.opacity = { table.data(), 128, -2.0, 3.0 };
  input.dataVersion = 1;
  input.opacityVersion = 1;
  mtpt::FramePipeline pipeline;
  pipeline.SetReuse(true);
  ASSERT_TRUE(pipeline.Run(input, 2));
  const mtpt::LargeVector<mtpt::SortKey> keys = pipeline.Keys();
  const std::vector<float> first = Composite(pipeline, input, table);

  // Unchanged: nothing recomputed, same buffers.
  ASSERT_TRUE(pipeline.Run(input, 2));
  EXPECT_TRUE(pipeline.Stats().transformReused);
  EXPECT_TRUE(pipeline.Stats().orderReused);
  EXPECT_TRUE(pipeline.Stats().decompositionReused);
  EXPECT_EQ(pipeline.Times().Total(), 0.0);
  EXPECT_TRUE(SameImage(first, Composite(pipeline, input, table)));

  // A colour change that keeps every opacity: the same visible cells, the same order.
  for (int i = 0; i < 128; ++i)
  {
    table[4 * i + 1] = 0.9f;
  }
  input.opacityVersion = 2;
  ASSERT_TRUE(pipeline.Run(input, 2));
  EXPECT_TRUE(pipeline.Stats().transformReused);
  EXPECT_TRUE(pipeline.Stats().orderReused);
  EXPECT_TRUE(pipeline.Stats().decompositionReused);

  // An opacity change: culling, keys, order and decomposition again, not the transform;
  // the result equals a fresh pipeline's.
  table = EdgeTable(128, 0.3f);
  input.opacity.table = table.data();
  input.opacityVersion = 3;
  ASSERT_TRUE(pipeline.Run(input, 2));
  EXPECT_TRUE(pipeline.Stats().transformReused);
  EXPECT_FALSE(pipeline.Stats().orderReused);
  EXPECT_GT(pipeline.SortedCount(), keys.size());
  mtpt::FramePipeline fresh;
  ASSERT_TRUE(fresh.Run(input, 2));
  EXPECT_EQ(pipeline.Keys(), fresh.Keys());
  EXPECT_TRUE(SameImage(Composite(fresh, input, table), Composite(pipeline, input, table)));

  // New data (a version change with the same arrays): everything again.
  input.dataVersion = 2;
  ASSERT_TRUE(pipeline.Run(input, 2));
  EXPECT_FALSE(pipeline.Stats().transformReused);
  EXPECT_FALSE(pipeline.Stats().orderReused);
  EXPECT_FALSE(pipeline.Stats().decompositionReused);

  // Without reuse nothing is ever skipped.
  mtpt::FramePipeline plain;
  ASSERT_TRUE(plain.Run(input, 2));
  ASSERT_TRUE(plain.Run(input, 2));
  EXPECT_FALSE(plain.Stats().transformReused || plain.Stats().orderReused ||
    plain.Stats().decompositionReused);
}

TEST(FramePipeline, AnOrderChangeInAStillViewSortsThisViewsKeys)
{
  // The order sorts in the depth keys' buffer; an order setting changed while the view
  // stands still must still sort this view's keys, with the eye outside the mesh and
  // inside it (the near plane cuts cells), after frames from other views.
  const TetMesh mesh = JitteredGrid(10, 6);
  for (bool inside : { false, true })
  {
    SCOPED_TRACE(inside ? "eye inside" : "eye outside");
    mtpt::FrameInput input = Frame(mesh, 0.4, true);
    mtpt::FramePipeline pipeline;
    pipeline.SetReuse(true);
    for (double azimuth : { 0.1, 0.9, 1.7 })
    {
      input = Frame(mesh, azimuth, true);
      if (inside)
      {
        input.modelView = LookAt(
          { 0.2 * std::sin(azimuth), 0.1, 0.2 * std::cos(azimuth) }, { 0, 0, 0 }, { 0, 1, 0 });
      }
      ASSERT_TRUE(pipeline.Run(input, 2));
    }
    EXPECT_EQ(pipeline.Stats().nearClipped > 0, inside);
    auto expectKeysOf = [&](mtpt::OrderMethod method, mtpt::OrderMutation mutation, bool ordered)
    {
      mtpt::FramePipeline fresh;
      fresh.SetOrderMethod(method);
      fresh.SetOrderMutationForTesting(mutation);
      input.ordered = ordered;
      ASSERT_TRUE(fresh.Run(input, 2));
      pipeline.SetOrderMethod(method);
      pipeline.SetOrderMutationForTesting(mutation);
      ASSERT_TRUE(pipeline.Run(input, 2));
      EXPECT_TRUE(pipeline.Stats().transformReused);
      ASSERT_GT(fresh.SortedCount(), 0u);
      EXPECT_EQ(pipeline.Keys(), fresh.Keys());
      // Unchanged again: nothing recomputed.
      ASSERT_TRUE(pipeline.Run(input, 2));
      EXPECT_TRUE(pipeline.Stats().orderReused);
      EXPECT_EQ(pipeline.Keys(), fresh.Keys());
    };
    expectKeysOf(mtpt::OrderMethod::PartitionSort, mtpt::OrderMutation::None, true);
    expectKeysOf(mtpt::OrderMethod::PartitionSort, mtpt::OrderMutation::Reversed, true);
    expectKeysOf(mtpt::OrderMethod::RadixSort, mtpt::OrderMutation::None, false);
    expectKeysOf(mtpt::OrderMethod::RadixSort, mtpt::OrderMutation::Storage, true);
    expectKeysOf(mtpt::OrderMethod::RadixSort, mtpt::OrderMutation::None, true);
  }
}

TEST(FramePipeline, SmallRotationsSortFromThePreviousOrderWithTheSameResult)
{
  const TetMesh mesh = JitteredGrid(12, 9);
  for (bool perspective : { false, true })
  {
    mtpt::FramePipeline pipeline;
    pipeline.SetReuse(true);
    double azimuth = 0.2;
    // No pixel culling: with it, cells that start or stop covering a pixel centre change the
    // set of sorted cells, and only the same set can be re-sorted from the previous order.
    mtpt::FrameInput input = Frame(mesh, azimuth, perspective);
    input.imageSize = {};
    input.projection = perspective ? mtpt::test::Perspective(70, 1.0, 1, 10)
                                   : mtpt::test::Ortho(-3, 3, -3, 3, 1, 10); // all in view
    ASSERT_TRUE(pipeline.Prepare(input, 2));
    int fromPrevious = 0;
    for (double step : { 1e-5, 1e-4, 1e-3, 0.005, 0.05, 1e-4 })
    {
      azimuth += step;
      const mtpt::Matrix4 projection = input.projection;
      input = Frame(mesh, azimuth, perspective);
      input.imageSize = {};
      input.projection = projection;
      ASSERT_TRUE(pipeline.Prepare(input, 2));
      fromPrevious += pipeline.Stats().orderFromPrevious;
      if (step > mtpt::FramePipeline::NearlySortedMaxAngle)
      {
        EXPECT_FALSE(pipeline.Stats().orderFromPrevious);
      }
      mtpt::FramePipeline fresh;
      ASSERT_TRUE(fresh.Prepare(input, 2));
      ASSERT_EQ(pipeline.Keys(), fresh.Keys()) << "step " << step;
    }
    EXPECT_GE(fromPrevious, 3); // the smallest steps took the nearly-sorted path
  }
}

TEST(VisibilityOrder, SortNearlySortedGivesTheUniqueOrderOrGivesUp)
{
  std::mt19937_64 random(3);
  for (std::size_t n : { 10u, 5000u, 100000u })
  {
    std::vector<mtpt::SortKey> keys(n);
    for (std::size_t i = 0; i < n; ++i)
    {
      keys[i] = mtpt::MakeSortKey(static_cast<float>(i / 3), static_cast<std::uint32_t>(i));
    }
    std::sort(keys.begin(), keys.end());
    const std::vector<mtpt::SortKey> sorted = keys;
    // Local swaps: nearly sorted.
    for (std::size_t i = 0; i + 5 < n; i += 7)
    {
      std::swap(keys[i], keys[i + random() % 5]);
    }
    for (int threads : { 1, 2, 3 })
    {
      std::vector<mtpt::SortKey> work = keys;
      ASSERT_TRUE(mtpt::SortNearlySorted(work.data(), n, 4 * n, threads));
      EXPECT_EQ(work, sorted) << n << " keys, " << threads << " threads";
    }
    // Reversed: far from sorted, the budget runs out.
    std::vector<mtpt::SortKey> reversed(sorted.rbegin(), sorted.rend());
    EXPECT_FALSE(mtpt::SortNearlySorted(reversed.data(), n, n, 2));
  }
}

TEST(FramePipeline, FixedSizeCellsGiveTheFrameOfExplicitOffsets)
{
  // VTK 9.6 stores cells of one size without offsets: the same mesh seen that way (64- and
  // 32-bit ids) must give the same order, the same fans and the same image.
  const TetMesh mesh = mtpt::test::JitteredGrid(8, 3);
  std::vector<std::int32_t> ids32(mesh.connectivity.begin(), mesh.connectivity.end());
  const std::vector<float> table = { 0.2f, 0.4f, 0.9f, 0.0f, 0.9f, 0.5f, 0.1f, 3.0f };
  for (bool perspective : { false, true })
  {
    const mtpt::FrameInput input = Frame(mesh, 0.7, perspective);
    mtpt::FramePipeline explicitOffsets;
    ASSERT_TRUE(explicitOffsets.Prepare(input, 2));
    const std::vector<float> reference = Composite(explicitOffsets, input, table);
    float drawn = 0;
    for (std::size_t i = 3; i < reference.size(); i += 4)
    {
      drawn = std::max(drawn, reference[i]);
    }
    ASSERT_GT(drawn, 0.1f);
    for (int bits : { 64, 32 })
    {
      mtpt::FrameInput fixed = input;
      fixed.cells = bits == 64
        ? mtpt::CellsView::FromFixedSizeInt64(mesh.connectivity.data(), 4, mesh.CellCount())
        : mtpt::CellsView::FromFixedSizeInt32(ids32.data(), 4, mesh.CellCount());
      mtpt::FramePipeline pipeline;
      ASSERT_TRUE(pipeline.Prepare(fixed, 2));
      EXPECT_EQ(pipeline.Keys(), explicitOffsets.Keys()) << bits;
      EXPECT_TRUE(SameImage(Composite(pipeline, fixed, table), reference)) << bits;
    }
    // Cells that are not 4 points long are not drawn (the fixed size is checked).
    mtpt::FrameInput triangles = input;
    triangles.cells =
      mtpt::CellsView::FromFixedSizeInt64(mesh.connectivity.data(), 3, mesh.CellCount());
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Prepare(triangles, 2));
    const std::vector<float> none = Composite(pipeline, triangles, table);
    float alpha = 0;
    for (std::size_t i = 3; i < none.size(); i += 4)
    {
      alpha = std::max(alpha, none[i]);
    }
    EXPECT_EQ(alpha, 0.0f);
  }
}

TEST(FramePipeline, AMeshOfPartsGivesTheFrameOfTheMergedMesh)
{
  // A multi-block data set used in place: the cells split into parts with their own points
  // (local ids), in 64-bit, 32-bit and fixed-size layouts, with an empty part among them.
  // The parts must be one mesh to every stage: the same order (same global cell ids), the
  // same image, and the same reference image.
  const TetMesh mesh = mtpt::test::JitteredGrid(8, 7);
  const std::size_t cells = mesh.CellCount();
  const std::size_t cut[3] = { 0, cells / 3, 2 * cells / 3 };
  struct PartData
  {
    std::vector<float> points;
    std::vector<std::int64_t> ids64, offsets64{ 0 };
    std::vector<std::int32_t> ids32, offsets32{ 0 };
  };
  std::vector<PartData> data(4);
  std::vector<float> scalars;        // point scalars in the parts' point order
  std::vector<std::int64_t> pointOf; // merged point id of each part point, part after part
  for (int k = 0; k < 3; ++k)
  {
    const std::size_t begin = cut[k], end = k < 2 ? cut[k + 1] : cells;
    std::vector<std::int64_t> local(mesh.points.size() / 3, -1);
    PartData& part = data[k == 2 ? 3 : k]; // part 2 stays empty
    for (std::size_t c = begin; c < end; ++c)
    {
      for (std::int64_t i = mesh.offsets[c]; i < mesh.offsets[c + 1]; ++i)
      {
        std::int64_t& id = local[mesh.connectivity[i]];
        if (id < 0)
        {
          id = static_cast<std::int64_t>(part.points.size() / 3);
          for (int d = 0; d < 3; ++d)
          {
            part.points.push_back(mesh.points[3 * mesh.connectivity[i] + d]);
          }
        }
        part.ids64.push_back(id);
        part.ids32.push_back(static_cast<std::int32_t>(id));
      }
      part.offsets64.push_back(static_cast<std::int64_t>(part.ids64.size()));
      part.offsets32.push_back(static_cast<std::int32_t>(part.ids32.size()));
    }
    std::vector<std::int64_t> merged(part.points.size() / 3);
    for (std::size_t p = 0; p < local.size(); ++p)
    {
      if (local[p] >= 0)
      {
        merged[local[p]] = static_cast<std::int64_t>(p);
      }
    }
    pointOf.insert(pointOf.end(), merged.begin(), merged.end());
  }
  // The merged mesh with its points in the parts' order, so that point ids agree too.
  TetMesh merged;
  std::vector<std::int64_t> partPointOf(mesh.points.size() / 3);
  std::int64_t first = 0;
  for (int k : { 0, 1, 3 })
  {
    for (std::size_t i = 0; i < data[k].points.size() / 3; ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        merged.points.push_back(data[k].points[3 * i + d]);
      }
    }
    for (std::size_t c = 0; c + 1 < data[k].offsets64.size(); ++c)
    {
      const std::int64_t* id = data[k].ids64.data() + data[k].offsets64[c];
      merged.AddTetrahedron(id[0] + first, id[1] + first, id[2] + first, id[3] + first);
    }
    first += static_cast<std::int64_t>(data[k].points.size() / 3);
  }
  for (std::int64_t p : pointOf)
  {
    merged.scalars.push_back(mesh.scalars[p]);
  }
  const std::vector<mtpt::MeshPart> parts = {
    { mtpt::PointsView::FromFloat(data[0].points.data(), data[0].points.size() / 3),
      mtpt::CellsView::FromInt64(
        data[0].ids64.data(), data[0].offsets64.data(), data[0].offsets64.size() - 1) },
    { mtpt::PointsView::FromFloat(data[1].points.data(), data[1].points.size() / 3),
      mtpt::CellsView::FromInt32(
        data[1].ids32.data(), data[1].offsets32.data(), data[1].offsets32.size() - 1) },
    { mtpt::PointsView::FromFloat(nullptr, 0), mtpt::CellsView::FromInt64(nullptr, nullptr, 0) },
    { mtpt::PointsView::FromFloat(data[3].points.data(), data[3].points.size() / 3),
      mtpt::CellsView::FromFixedSizeInt32(data[3].ids32.data(), 4, data[3].offsets32.size() - 1) },
  };
  const std::vector<float> table = { 0.2f, 0.4f, 0.9f, 0.0f, 0.9f, 0.5f, 0.1f, 3.0f };
  for (bool perspective : { false, true })
  {
    const mtpt::FrameInput whole = Frame(merged, 0.9, perspective);
    mtpt::FrameInput split = whole;
    mtpt::MeshParts(parts.data(), parts.size(), split.points, split.cells);
    ASSERT_EQ(split.cells.cellCount, cells);
    ASSERT_EQ(split.points.count, merged.points.size() / 3);
    for (int threads : { 1, 3 })
    {
      mtpt::FramePipeline a, b;
      ASSERT_TRUE(a.Prepare(whole, threads));
      ASSERT_TRUE(b.Prepare(split, threads));
      EXPECT_EQ(a.Keys(), b.Keys());
      EXPECT_GT(a.SortedCount(), cells / 2); // a few sub-pixel cells are culled
      const std::vector<float> image = Composite(b, split, table);
      EXPECT_TRUE(SameImage(Composite(a, whole, table), image));
      float drawn = 0;
      for (std::size_t i = 3; i < image.size(); i += 4)
      {
        drawn = std::max(drawn, image[i]);
      }
      EXPECT_GT(drawn, 0.1f);
    }
    mtpt::ReferenceSettings settings;
    settings.width = settings.height = 24;
    settings.modelView = whole.modelView;
    settings.projection = whole.projection;
    settings.color = { { -2.0, 0.2, 0.4, 0.9 }, { 3.0, 0.9, 0.5, 0.1 } };
    settings.opacity = { { -2.0, 0.0 }, { 3.0, 1.0 } };
    settings.unitDistance = 0.3;
    std::vector<double> referenceWhole, referenceSplit;
    ASSERT_TRUE(
      mtpt::RenderReference(whole.points, whole.cells, whole.scalars, settings, referenceWhole, 2));
    ASSERT_TRUE(
      mtpt::RenderReference(split.points, split.cells, split.scalars, settings, referenceSplit, 2));
    EXPECT_EQ(referenceWhole, referenceSplit);
  }
}

TEST(FramePipeline, BatchesReproduceTheWholeFrame)
{
  const TetMesh mesh = JitteredGrid(11, 2); // 7,986 tetrahedra
  const std::vector<float> table = EdgeTable(64, 0.2f);
  mtpt::FrameInput input = Frame(mesh, 0.7, true);
  mtpt::FramePipeline whole;
  ASSERT_TRUE(whole.Prepare(input, 2));
  const std::vector<float> reference = Composite(whole, input, table);
  whole.DecomposeBatch(0, whole.SortedCount(), 2); // the slots, for the batches' slices
  const std::vector<TetVertex> vertices(
    whole.Vertices().begin(), whole.Vertices().begin() + 5 * whole.SortedCount());
  const std::vector<std::uint32_t> indices(
    whole.Indices().begin(), whole.Indices().begin() + 12 * whole.SortedCount());
  for (std::size_t batch : { 1000u, 3333u, 7985u })
  {
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Prepare(input, 3));
    // The compositor draws each batch front to back on its own and composites it over the
    // batches behind it: the image is the whole frame's up to rounding, and up to the
    // fragments a batch skips behind its own opaque pixels (OpaqueAlpha: 2^-11).
    const std::vector<float> image = Composite(pipeline, input, table, batch);
    ASSERT_EQ(image.size(), reference.size());
    double worst = 0;
    for (std::size_t i = 0; i < image.size(); ++i)
    {
      worst = std::max(worst, static_cast<double>(std::fabs(image[i] - reference[i])));
    }
    EXPECT_LE(worst, 1.0 / 2048 + 1e-6) << batch;
    std::printf("batches of %zu: worst channel difference %.3g\n", batch, worst);
    EXPECT_GE(pipeline.Stats().batches, whole.SortedCount() / batch);
    // Each batch's buffers are the whole frame's slice, indices renumbered from 0.
    for (std::size_t first = 0; first < pipeline.SortedCount(); first += batch)
    {
      pipeline.DecomposeBatch(first, batch, 2);
      const std::size_t count = pipeline.TetrahedronCount();
      ASSERT_EQ(count, std::min(batch, pipeline.SortedCount() - first));
      ASSERT_EQ(0,
        std::memcmp(
          pipeline.Vertices().data(), vertices.data() + 5 * first, 5 * count * sizeof(TetVertex)));
      for (std::size_t i = 0; i < 12 * count; ++i)
      {
        ASSERT_EQ(pipeline.Indices()[i] + 5 * first, indices[12 * first + i]);
      }
    }
    if (batch == 1000) // memory follows the batch, not the mesh
    {
      EXPECT_LT(pipeline.MemoryBytes(), whole.MemoryBytes() - 100 * 7 * 168);
    }
  }
}

TEST(FramePipeline, BatchesOverManyRankGroupsReproduceTheWholeFrame)
{
  // A batch visits only the cells of the rank groups it overlaps (OrderStage::Group; the
  // first window's length is the groups'). Windows of that length, windows that start and
  // end inside groups and span several, and cells culled by opacity (a candidate list):
  // every window's slots and light factors must be the whole frame's slice.
  const TetMesh mesh = JitteredGrid(16, 8);
  const std::vector<float> table = EdgeTable(64, 0.2f);
  mtpt::FrameInput input = Frame(mesh, 0.4, true);
  input.opacity = { table.data(), 64, -2.0, 3.0 };
  std::vector<float> normals(3 * mesh.CellCount());
  std::mt19937 random(5);
  std::normal_distribution<float> gauss;
  for (float& v : normals)
  {
    v = gauss(random);
  }
  mtpt::Lighting lighting;
  mtpt::FramePipeline whole;
  ASSERT_TRUE(whole.Run(input, 2));
  const std::size_t total = whole.SortedCount();
  ASSERT_GT(whole.Stats().opacityCulled, 0u);
  ASSERT_GT(total, 5000u);
  const std::vector<TetVertex> vertices(
    whole.Vertices().begin(), whole.Vertices().begin() + 5 * total);
  std::vector<mtpt::LightFactors> wholeFactors;
  whole.LightWindow(0, total, lighting, normals.data(), input.modelView, wholeFactors, 2);
  for (const std::vector<std::size_t>& windows :
    { std::vector<std::size_t>{ 1001 }, std::vector<std::size_t>{ 1000, 2500, 700, 1 },
      std::vector<std::size_t>{ 3, 999, 4000, 64 }, std::vector<std::size_t>{ total - 1 } })
  {
    SCOPED_TRACE(::testing::Message() << "windows from " << windows[0]);
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Prepare(input, 3));
    std::vector<mtpt::LightFactors> factors;
    std::size_t w = 0;
    for (std::size_t first = 0; first < total; first += windows[w++ % windows.size()])
    {
      const std::size_t length = windows[w % windows.size()];
      pipeline.DecomposeBatch(first, length, 2);
      const std::size_t count = pipeline.TetrahedronCount();
      ASSERT_EQ(count, std::min(length, total - first));
      ASSERT_EQ(0,
        std::memcmp(
          pipeline.Vertices().data(), vertices.data() + 5 * first, 5 * count * sizeof(TetVertex)))
        << "the window from " << first;
      pipeline.LightWindow(first, length, lighting, normals.data(), input.modelView, factors, 3);
      ASSERT_EQ(factors.size(), count);
      ASSERT_EQ(0,
        std::memcmp(
          factors.data(), wholeFactors.data() + first, count * sizeof(mtpt::LightFactors)))
        << "the light of the window from " << first;
    }
  }
}

} // namespace

TEST(FramePipelineMemory, BytesNeededBoundsTheBuffersOfEveryFrame)
{
  // The bound a caller checks before a frame allocates (FramePipeline::BytesNeeded) must
  // hold the buffers the frames leave (MemoryBytes), whatever the view (the eye inside the
  // mesh: near-plane pieces), the window, the level of detail and the decompositions; and it
  // must stay near them, or it would refuse meshes that fit.
  const TetMesh mesh = JitteredGrid(9, 5);
  const std::vector<float> opacity = { 0, 0, 0, 0, 1, 1, 1, 0.5f, 1, 1, 1, 2 };
  for (const bool inside : { false, true })
  {
    // 0: batches of 5/13 of the order, so that its last window holds 0.6 of a batch.
    for (const std::size_t asked :
      { std::size_t{ 1 }, std::size_t{ 37 }, std::size_t{ 0 }, std::size_t{ 1 } << 20 })
    {
      for (const double fraction : { 1.0, 0.5 })
      {
        mtpt::FrameInput input;
        input.points = mesh.Points();
        input.cells = mesh.Cells();
        input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
        input.modelView = inside ? LookAt({ 0.1, -0.05, 0.3 }, { 0.18, 0.0, -0.7 }, { 0, 1, 0 })
                                 : LookAt({ 0.7, 1.1, 2.6 }, { 0.1, 0, 0 }, { 0, 1, 0 });
        input.projection = mtpt::test::Perspective(70, 1.0, inside ? 0.05 : 0.5, 10);
        input.perspective = true;
        input.imageSize = { 64, 64 };
        input.opacity = { opacity.data(), 3, -1.0, 1.0 };
        input.cellFraction = fraction;
        mtpt::FramePipeline pipeline;
        pipeline.PrepareLevelOfDetail(input, 2);
        ASSERT_TRUE(pipeline.Prepare(input, 2));
        const std::size_t batch = asked > 0 ? asked : pipeline.SortedCount() * 5 / 13;
        // The windows as the batch loop gives them: slots back to front, fans front to back
        // (the first of them the order's shorter last window).
        mtpt::FramePlan plan;
        plan.batchSize = batch;
        plan.threads = 2;
        plan.target = mtpt::BatchTarget::Slots;
        pipeline.DrawBatches(plan, [](const mtpt::Batch&) { return true; });
        plan.target = mtpt::BatchTarget::Fans;
        plan.frontToBack = true;
        pipeline.DrawBatches(plan, [](const mtpt::Batch&) { return true; });
        mtpt::MemoryNeed need;
        need.points = mesh.Points().count;
        need.cells = mesh.Cells().cellCount;
        need.batch = batch;
        need.slots = need.fans = true;
        need.levelOfDetail = fraction < 1;
        need.threads = 2;
        need.pieces = pipeline.Stats().nearPieces;
        const std::size_t held = pipeline.MemoryBytes(),
                          bound = mtpt::FramePipeline::BytesNeeded(need);
        SCOPED_TRACE(::testing::Message()
          << (inside ? "inside" : "outside") << ", batches of " << batch << ", fraction "
          << fraction << ", " << need.pieces << " pieces");
        std::printf("%s, batches of %zu, fraction %g: %zu bytes held, %zu bound (%zu pieces)\n",
          inside ? "inside" : "outside", batch, fraction, held, bound, need.pieces);
        EXPECT_EQ(inside, need.pieces > 0);
        EXPECT_LE(held, bound);
        if (!inside && fraction == 1)
        {
          // Every cell in view and drawn: only the culling's lists and the last window may be
          // shorter than the bound takes them.
          EXPECT_GE(static_cast<double>(held), 0.75 * static_cast<double>(bound));
        }
      }
    }
  }
}
