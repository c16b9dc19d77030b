// SPDX-License-Identifier: BSD-3-Clause
// Level of detail for moving frames (mtpt/LevelOfDetail.h): the importance order (distinct,
// the same for any thread count, any prefix spread evenly over the mesh), the fraction
// levels, the selection stage against a brute-force filter, the pipeline on a subset (only
// the subset is keyed and sorted, the attenuation scale is visible / drawn, and the full
// frame after moving frames equals a fresh pipeline's bit for bit), and the budget rule on
// a simulated clock (it converges within a few frames, and a still frame is the full one).
#include "mtpt/FramePipeline.h"
#include "mtpt/LevelOfDetail.h"

#include "TestHelpers.h"
#include "detail/Parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{

using mtpt::test::TetMesh;

std::vector<std::uint32_t> Importance(const TetMesh& mesh, int threads)
{
  std::vector<std::uint32_t> importance(mesh.CellCount());
  mtpt::ComputeImportance(mesh.Points(), mesh.Cells(), importance.data(), threads);
  return importance;
}

/// The cells' centroids.
std::vector<mtpt::test::Vec3> Centroids(const TetMesh& mesh)
{
  std::vector<mtpt::test::Vec3> centres(mesh.CellCount(), mtpt::test::Vec3{ 0, 0, 0 });
  for (std::size_t c = 0; c < mesh.CellCount(); ++c)
  {
    for (int i = 0; i < 4; ++i)
    {
      const std::int64_t p = mesh.connectivity[4 * c + i];
      for (int a = 0; a < 3; ++a)
      {
        centres[c][a] += 0.25 * mesh.points[3 * p + a];
      }
    }
  }
  return centres;
}

TEST(LevelOfDetail, TheParallelSortIsStdSortForAnyThreadCount)
{
  // The importance order's sort (detail::ParallelSort): blocks sorted at once, merged pairwise.
  std::mt19937_64 random(17);
  for (const std::size_t n : { 0, 1, 2, 7, 1000, 100003 })
  {
    std::vector<std::uint64_t> keys(n);
    for (std::uint64_t& key : keys)
    {
      key = random() % 5000; // ties too
    }
    std::vector<std::uint64_t> expected = keys;
    std::sort(expected.begin(), expected.end());
    for (const int threads : { 1, 2, 3, 5, 8 })
    {
      std::vector<std::uint64_t> sorted = keys;
      mtpt::detail::ParallelSort(sorted.data(), sorted.size(), threads);
      EXPECT_EQ(sorted, expected) << n << " keys, " << threads << " threads";
    }
  }
}

TEST(LevelOfDetail, ImportanceIsDistinctAndIndependentOfThreads)
{
  const TetMesh mesh = mtpt::test::JitteredGrid(12, 3); // 10,368 cells
  const std::vector<std::uint32_t> one = Importance(mesh, 1);
  ASSERT_EQ(mtpt::ImportanceBits(mesh.CellCount()), 14);
  std::vector<std::uint32_t> sorted = one;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
  EXPECT_LT(sorted.back(), 1u << 14);
  EXPECT_EQ(Importance(mesh, 2), one);
  EXPECT_EQ(Importance(mesh, 3), one);
}

TEST(LevelOfDetail, EveryPrefixIsSpreadEvenlyOverTheMesh)
{
  // Importance below 2^bits / 2^k keeps every 2^k-th cell along the Morton curve, and the
  // curve visits the octants of the box one after the other: each octant keeps its share
  // of the cells to within one.
  const TetMesh mesh = mtpt::test::JitteredGrid(16, 5); // 24,576 cells
  const std::vector<std::uint32_t> importance = Importance(mesh, 2);
  const std::vector<mtpt::test::Vec3> centres = Centroids(mesh);
  const int bits = mtpt::ImportanceBits(mesh.CellCount());
  for (int k = 1; k <= 4; ++k)
  {
    const std::uint64_t threshold =
      mtpt::ImportanceThreshold(std::ldexp(1.0, -k), mesh.CellCount());
    ASSERT_EQ(threshold, std::uint64_t{ 1 } << (bits - k));
    std::size_t cells[8] = {}, kept[8] = {};
    for (std::size_t c = 0; c < mesh.CellCount(); ++c)
    {
      // The lattice splits the box [-1, 1]^3 at its centre, and no centroid lies on it.
      const int octant =
        (centres[c][0] > 0 ? 1 : 0) | (centres[c][1] > 0 ? 2 : 0) | (centres[c][2] > 0 ? 4 : 0);
      ++cells[octant];
      kept[octant] += importance[c] < threshold ? 1 : 0;
    }
    for (int o = 0; o < 8; ++o)
    {
      EXPECT_NEAR(static_cast<double>(kept[o]), std::ldexp(static_cast<double>(cells[o]), -k), 1.0)
        << "octant " << o << " at fraction 2^-" << k;
    }
  }
}

TEST(LevelOfDetail, FractionLevels)
{
  EXPECT_EQ(mtpt::CellFractionLevel(1.0, 0.05), 1.0);
  EXPECT_EQ(mtpt::CellFractionLevel(2.0, 0.05), 1.0);
  EXPECT_EQ(mtpt::CellFractionLevel(std::numeric_limits<double>::quiet_NaN(), 0.05), 1.0);
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.99, 0.05), std::exp2(-0.25));
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.5, 0.05), 0.5);
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.4999, 0.05), std::exp2(-1.25));
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.25, 0.05), 0.25);
  // Never below the level of the minimum.
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.01, 0.05), std::exp2(-4.5));
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.0, 0.25), 0.25);
  EXPECT_DOUBLE_EQ(mtpt::CellFractionLevel(0.3, 1.0), 1.0);
}

TEST(LevelOfDetail, KeptLevelsSelectWhatTheImportanceSelectsAtEveryLevel)
{
  // A byte a cell instead of the importance: its deepest kept level. At every level the
  // byte and the importance must keep the same cells, on meshes whose importance bits do
  // and do not fill the levels' thresholds.
  for (const TetMesh& mesh : { mtpt::test::JitteredGrid(10, 7), mtpt::test::JitteredGrid(1, 3) })
  {
    const std::size_t n = mesh.CellCount();
    const std::vector<std::uint32_t> importance = Importance(mesh, 2);
    for (int threads : { 1, 2 })
    {
      std::vector<std::uint8_t> levels(n, 0xcd);
      mtpt::ComputeKeptLevels(mesh.Points(), mesh.Cells(), levels.data(), threads);
      for (int k = 0; k <= mtpt::DeepestDetailLevel; ++k)
      {
        const std::uint64_t threshold = mtpt::ImportanceThreshold(mtpt::DetailLevelFraction(k), n);
        for (std::size_t c = 0; c < n; ++c)
        {
          ASSERT_EQ(levels[c] >= k, importance[c] < threshold)
            << "cell " << c << " of " << n << " at level " << k << ", " << threads << " threads";
        }
      }
    }
  }
  // The levels the frame's plan gives (CellFractionLevel) map back to their level.
  for (int k = 0; k <= mtpt::DeepestDetailLevel; ++k)
  {
    EXPECT_EQ(mtpt::DetailLevelOf(mtpt::DetailLevelFraction(k)), k);
    EXPECT_EQ(mtpt::DetailLevelFraction(k),
      k == 0 ? 1.0 : mtpt::CellFractionLevel(mtpt::DetailLevelFraction(k), 0.0));
  }
  EXPECT_EQ(mtpt::DetailLevelOf(1.0), 0);
  EXPECT_EQ(mtpt::DetailLevelOf(std::numeric_limits<double>::quiet_NaN()), 0);
}

TEST(LevelOfDetail, SelectionIsTheVisibleCellsTheLevelKeeps)
{
  const TetMesh mesh = mtpt::test::JitteredGrid(10, 7);
  const std::size_t n = mesh.CellCount();
  const std::vector<std::uint32_t> importance = Importance(mesh, 1);
  std::vector<std::uint32_t> visible;
  for (std::uint32_t c = 0; c < n; c += 1 + c % 3)
  {
    visible.push_back(c);
  }
  const mtpt::MeshKey key =
    mtpt::MeshKey::Of(mesh.Points(), mesh.Cells(), mtpt::ScalarsView{}, nullptr, 1);
  mtpt::CellSelectionStage stage;
  for (int level : { 4, 7, 13, 1 }) // fractions 0.5, 0.30, 0.105 and 0.84, the largest
  {
    const std::uint64_t threshold = mtpt::ImportanceThreshold(mtpt::DetailLevelFraction(level), n);
    std::vector<std::uint32_t> expected;
    for (std::uint32_t c : visible)
    {
      if (importance[c] < threshold)
      {
        expected.push_back(c);
      }
    }
    const std::uint64_t before = stage.Version();
    EXPECT_TRUE(stage.Update(
      { key, 4, level }, mesh.Points(), mesh.Cells(), visible.data(), visible.size(), 2));
    EXPECT_NE(stage.Version(), before);
    ASSERT_EQ(stage.SelectedCount(), expected.size());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), stage.Selected()));
    EXPECT_EQ(stage.LeftOut(), visible.size() - expected.size());
    EXPECT_LE(stage.SelectedCount(), mtpt::CellSelectionStage::LargestSubset(n));
    // The same key again: nothing computed, the same version.
    const std::uint64_t version = stage.Version();
    EXPECT_FALSE(stage.Update(
      { key, 4, level }, mesh.Points(), mesh.Cells(), visible.data(), visible.size(), 2));
    EXPECT_EQ(stage.Version(), version);
  }
  // A byte a cell and the largest subset's list, not the importance's 4 bytes a cell.
  EXPECT_LE(
    stage.MemoryBytes(), n + mtpt::CellSelectionStage::LargestSubset(n) * sizeof(std::uint32_t));
  // Every cell: the visible list itself.
  EXPECT_FALSE(
    stage.Update({ key, 4, 0 }, mesh.Points(), mesh.Cells(), visible.data(), visible.size(), 2));
  EXPECT_EQ(stage.Selected(), visible.data());
  EXPECT_EQ(stage.SelectedCount(), visible.size());
  EXPECT_EQ(stage.LeftOut(), 0u);
}

mtpt::FrameInput Frame(const TetMesh& mesh, double azimuth)
{
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  const double r = 4.0;
  input.modelView = mtpt::test::LookAt(
    { r * std::sin(azimuth), 1.2, r * std::cos(azimuth) }, { 0, 0, 0 }, { 0, 1, 0 });
  input.projection = mtpt::test::Perspective(45, 1.0, 1, 10);
  input.perspective = true;
  input.imageSize = { 64, 64 };
  return input;
}

TEST(LevelOfDetail, PipelineDrawsTheSubsetAndThenTheFullFrameExactly)
{
  const TetMesh mesh = mtpt::test::JitteredGrid(12, 11);
  std::vector<float> table(4 * 256, 0.5f); // RGBA entries
  for (std::size_t i = 0; i < 40; ++i)
  {
    table[4 * i + 3] = 0.0f; // culls the cells of the lowest scalars
  }
  mtpt::FramePipeline pipeline;
  pipeline.SetReuse(true);
  mtpt::FrameInput input = Frame(mesh, 0.3);
  input.opacity = { table.data(), 256, -2.0, 3.0 };
  input.dataVersion = 1;
  ASSERT_TRUE(pipeline.Run(input, 2));
  const std::size_t visible = mesh.CellCount() - pipeline.Stats().opacityCulled;
  ASSERT_GT(pipeline.Stats().opacityCulled, 0u);
  EXPECT_EQ(pipeline.Stats().leftOut, 0u);
  EXPECT_EQ(pipeline.Stats().attenuationScale, 1.0);

  // Moving frames at a quarter and an eighth of the cells.
  for (double fraction : { 0.25, 0.125 })
  {
    input = Frame(mesh, 0.3 + fraction);
    input.opacity = { table.data(), 256, -2.0, 3.0 };
    input.dataVersion = 1;
    input.cellFraction = fraction;
    ASSERT_TRUE(pipeline.Run(input, 2));
    const mtpt::FrameStats& stats = pipeline.Stats();
    const std::size_t drawn = visible - stats.leftOut;
    EXPECT_NEAR(static_cast<double>(drawn), fraction * static_cast<double>(visible),
      0.1 * fraction * static_cast<double>(visible));
    EXPECT_DOUBLE_EQ(stats.attenuationScale, static_cast<double>(visible) / drawn);
    // Only the subset is keyed and sorted (the whole mesh is in view).
    EXPECT_EQ(stats.frustumCulled, 0u);
    EXPECT_EQ(stats.sorted + stats.pixelCulled - stats.nearPieces, drawn);
  }

  // The view stops where the last moving frame was: the full frame of that view equals a
  // fresh pipeline's, buffer for buffer.
  input = Frame(mesh, 0.3 + 0.125);
  input.opacity = { table.data(), 256, -2.0, 3.0 };
  input.dataVersion = 1;
  ASSERT_TRUE(pipeline.Run(input, 2));
  mtpt::FramePipeline fresh;
  ASSERT_TRUE(fresh.Run(input, 2));
  EXPECT_EQ(pipeline.Stats().leftOut, 0u);
  EXPECT_EQ(pipeline.Stats().attenuationScale, 1.0);
  // (The buffers keep the capacity of the largest batch: compare the frame's slots.)
  const std::size_t slots = fresh.TetrahedronCount();
  ASSERT_EQ(pipeline.TetrahedronCount(), slots);
  EXPECT_TRUE(
    std::equal(fresh.Keys().begin(), fresh.Keys().begin() + slots, pipeline.Keys().begin()));
  EXPECT_EQ(0,
    std::memcmp(pipeline.Vertices().data(), fresh.Vertices().data(),
      mtpt::VerticesPerTetrahedron * slots * sizeof(mtpt::TetVertex)));
  EXPECT_TRUE(std::equal(fresh.Indices().begin(),
    fresh.Indices().begin() + mtpt::IndicesPerTetrahedron * slots, pipeline.Indices().begin()));
}

/// A simulated frame: fixed seconds, plus per-cell seconds scaled by the fraction, plus
/// per-sample seconds scaled by the fraction and 1 / d^2 (fill), plus a magnification that
/// costs `magnify` whenever d > 1; the fixed part and the magnification are reported as the
/// viewport's work.
struct SimulatedCost
{
  double fixed, cells, samples, magnify;
  double overhead = 0; ///< fixed too, but reported as nothing (the transform, the selection)
  double Seconds(const mtpt::Detail& d) const
  {
    return this->fixed + this->overhead +
      d.cellFraction * (this->cells + this->samples / (d.sampleDistance * d.sampleDistance)) +
      (d.sampleDistance > 1 ? this->magnify : 0.0);
  }
  double CellSeconds(const mtpt::Detail& d) const { return d.cellFraction * this->cells; }
  /// The fixed part and the magnification: what the backend reports as viewport work.
  double ViewportSeconds(const mtpt::Detail& d) const
  {
    return this->fixed + (d.sampleDistance > 1 ? this->magnify : 0.0);
  }
};

/// What the rule learns of a frame of `detail`: its time, its per-cell stages, and either
/// its compositing (`samplesMeasured`, as the CPU backend reports it) or its viewport work.
mtpt::MeasuredFrame Measure(
  const SimulatedCost& cost, const mtpt::Detail& detail, bool samplesMeasured)
{
  mtpt::MeasuredFrame m;
  m.detail = detail;
  m.seconds = cost.Seconds(detail);
  m.cellSeconds = cost.CellSeconds(detail);
  m.sampleSeconds = samplesMeasured ? m.seconds - m.cellSeconds - cost.ViewportSeconds(detail) : -1;
  m.viewportSeconds = cost.ViewportSeconds(detail);
  return m;
}

/// Runs `frames` frames of the rule from a full frame; returns the details chosen.
std::vector<mtpt::Detail> Simulate(const SimulatedCost& cost, double allotted,
  const mtpt::DetailLimits& limits, int frames, bool samplesMeasured)
{
  std::vector<mtpt::Detail> details;
  mtpt::MeasuredFrame last = Measure(cost, mtpt::Detail{}, samplesMeasured);
  for (int i = 0; i < frames; ++i)
  {
    const mtpt::Detail next = mtpt::ChooseDetail(last, allotted, limits, last.detail);
    details.push_back(next);
    last = Measure(cost, next, samplesMeasured);
  }
  return details;
}

TEST(LevelOfDetail, RuleConvergesToTheAllottedTimeInAFewFrames)
{
  // Costs shaped as measured (seconds at 1024 x 1024, 2 cores): a 1M-cell mesh (stages
  // 50 ms, fill 300 ms), a 200k-cell one, one dominated by fixed costs, a tiny one, and a
  // 200k-cell one whose fixed costs the backend does not all report.
  const SimulatedCost costs[] = { { 0.004, 0.050, 0.300, 0.004 }, { 0.004, 0.012, 0.120, 0.004 },
    { 0.015, 0.020, 0.100, 0.004 }, { 0.001, 0.001, 0.004, 0.001 },
    { 0.012, 0.020, 0.100, 0.004, 0.006 } };
  const mtpt::DetailLimits limits;
  for (const SimulatedCost& cost : costs)
  {
    for (const bool samplesMeasured : { true, false })
    {
      for (double rate : { 5.0, 10.0, 15.0, 25.0 })
      {
        const double allotted = 1.0 / rate;
        const std::vector<mtpt::Detail> details =
          Simulate(cost, allotted, limits, 12, samplesMeasured);
        for (std::size_t i = 0; i < details.size(); ++i)
        {
          const mtpt::Detail& d = details[i];
          EXPECT_GE(d.cellFraction, mtpt::CellFractionLevel(limits.minimumFraction, 0));
          EXPECT_LE(d.cellFraction, 1.0);
          EXPECT_GE(d.sampleDistance, limits.minimumDistance);
          EXPECT_LE(d.sampleDistance, limits.maximumDistance);
          const double seconds = cost.Seconds(d);
          if (i >= 3 && cost.Seconds({ limits.minimumFraction, limits.maximumDistance }) < allotted)
          {
            // From the fourth frame on: within the allotted time, and no coarser than one
            // fraction level (a factor 2^(1/4)) below what fits.
            EXPECT_LE(seconds, 1.1 * allotted)
              << "rate " << rate << ", frame " << i << ", measured: " << samplesMeasured;
            if (cost.Seconds({ 1, limits.minimumDistance }) > allotted)
            {
              EXPECT_GE(seconds, 0.75 * allotted)
                << "rate " << rate << ", frame " << i << ", measured: " << samplesMeasured;
            }
          }
        }
        // Once converged it stays: the last frames agree.
        EXPECT_EQ(details[10].cellFraction, details[11].cellFraction);
        EXPECT_NEAR(details[10].sampleDistance, details[11].sampleDistance, 0.05);
      }
    }
  }
}

TEST(LevelOfDetail, TheVolumeLeavesTheRestOfTheFrameItsTime)
{
  // Frames back to back: the rest of the frame (interval - volume) comes off the allotment.
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.1, 0.12, 0.1), 0.08);
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.04, 0.05, 0.03), 0.02);
  // At most half of it.
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.04, 0.1, 0.03), 0.02);
  // An interval shorter than the volume's time (clocks apart): nothing.
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.1, 0.05, 0.08), 0.1);
  // Frames not back to back (the application idled), no interval, a still allotment.
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.04, 0.5, 0.03), 0.04);
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.04, 0.0, 0.03), 0.04);
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(0.04, std::numeric_limits<double>::quiet_NaN(), 0.03), 0.04);
  EXPECT_DOUBLE_EQ(mtpt::VolumeBudget(10000.0, 0.2, 0.1), 10000.0 - 0.1);
}

TEST(LevelOfDetail, StillFramesAndUnusableInputsGiveTheFullFrame)
{
  const mtpt::DetailLimits limits;
  mtpt::MeasuredFrame moving;
  moving.detail = { 0.25, 1.5 };
  moving.seconds = 0.1;
  moving.cellSeconds = 0.02;
  const mtpt::Detail fixed{ 0.5, 3.0 };
  for (double allotted : { 10000.0, 1.0 / 0.0001, 0.0, -1.0,
         std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity() })
  {
    const mtpt::Detail d = mtpt::ChooseDetail(moving, allotted, limits, fixed);
    EXPECT_EQ(d.cellFraction, 1.0) << allotted;
    EXPECT_EQ(d.sampleDistance, limits.minimumDistance) << allotted;
  }
  // A frame never timed.
  mtpt::MeasuredFrame never;
  EXPECT_EQ(mtpt::ChooseDetail(never, 0.01, limits, fixed).cellFraction, 1.0);
  // Settings not adjusted keep their fixed value.
  mtpt::DetailLimits fractionOnly = limits;
  fractionOnly.adjustDistance = false;
  const mtpt::Detail d = mtpt::ChooseDetail(moving, 0.01, fractionOnly, fixed);
  EXPECT_EQ(d.sampleDistance, 3.0);
  EXPECT_LT(d.cellFraction, 0.25);
  mtpt::DetailLimits distanceOnly = limits;
  distanceOnly.adjustFraction = false;
  const mtpt::Detail e = mtpt::ChooseDetail(moving, 0.01, distanceOnly, fixed);
  EXPECT_EQ(e.cellFraction, 0.5);
  EXPECT_GT(e.sampleDistance, 1.5);
}

} // namespace
