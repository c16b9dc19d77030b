// SPDX-License-Identifier: BSD-3-Clause
// The blend modes other than composite (mtpt::BlendMode): the intensity table's integral,
// the compositor's reductions against the exact reference, and the frame that skips the sort.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/ReferenceRenderer.h"
#include "mtpt/TransferFunctionTable.h"
#include "detail/TileRaster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace
{

constexpr mtpt::BlendMode Reductions[] = { mtpt::BlendMode::MaximumIntensity,
  mtpt::BlendMode::MinimumIntensity, mtpt::BlendMode::AverageIntensity,
  mtpt::BlendMode::Additive };

const char* NameOf(mtpt::BlendMode mode)
{
  switch (mode)
  {
    case mtpt::BlendMode::MaximumIntensity:
      return "maximum";
    case mtpt::BlendMode::MinimumIntensity:
      return "minimum";
    case mtpt::BlendMode::AverageIntensity:
      return "average";
    case mtpt::BlendMode::Additive:
      return "additive";
    case mtpt::BlendMode::Composite:
      break;
  }
  return "composite";
}

/// A table with a steep, non-monotonic opacity and colour, 64 entries over [low, high].
std::vector<float> SteepTable()
{
  std::vector<float> table;
  for (int i = 0; i < 64; ++i)
  {
    const float t = i / 63.0f;
    const float bump = std::exp(-60.0f * (t - 0.6f) * (t - 0.6f));
    table.insert(table.end(), { t, 1 - t, 0.5f, 0.1f + 0.8f * bump + 0.3f * t * t });
  }
  return table;
}

/// The jittered grid of the compositor's split tests, seen in perspective or not, with the
/// cells left in id order (FrameInput::ordered false) or sorted.
struct Scene
{
  static constexpr int Width = 72, Height = 60;
  static constexpr double Low = -0.5, High = 1.5;
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(10, 17);
  std::vector<float> table = SteepTable();
  mtpt::FrameInput input;
  mtpt::FramePipeline pipeline;
  mtpt::IntensityTable intensity;

  Scene(bool perspective, bool ordered)
  {
    this->input.points = this->mesh.Points();
    this->input.cells = this->mesh.Cells();
    this->input.scalars = { this->mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    mtpt::test::ObliqueView(this->input, perspective);
    this->input.ordered = ordered;
    this->intensity.Build(this->Table());
  }

  mtpt::TransferFunctionTable Table() const
  {
    return { this->table.data(), static_cast<int>(this->table.size() / 4), Low, High };
  }

  mtpt::CompositeSettings Settings(mtpt::BlendMode mode) const
  {
    mtpt::CompositeSettings s;
    s.width = Width;
    s.height = Height;
    s.transferFunction = this->Table();
    s.unitDistance = 0.5;
    s.interpolation = mtpt::PerspectiveInterpolation::FromProjection(this->input.projection);
    s.clipping = mtpt::DepthClipping::FromProjection(this->input.projection);
    s.blendMode = mode;
    s.intensity = &this->intensity;
    s.averageRange[0] = 0.2;
    s.averageRange[1] = 0.9;
    return s;
  }

  /// The compositor's premultiplied RGBA image.
  std::vector<float> Composite(const mtpt::CompositeSettings& s)
  {
    this->pipeline.DecomposeFans(0, this->pipeline.SortedCount(), 2);
    mtpt::Compositor compositor;
    compositor.Begin(s);
    compositor.Composite(this->pipeline.Fans().data(), this->pipeline.FanCount(), 2);
    std::vector<float> rgba(4 * static_cast<std::size_t>(s.width) * s.height);
    compositor.Resolve(
      { 0, 0, s.width, s.height }, static_cast<const float*>(nullptr), rgba.data(), 2);
    return rgba;
  }

  /// The exact reference's image over black with the compositor's settings: the table's
  /// entries as the transfer functions' nodes.
  std::vector<double> Reference(const mtpt::CompositeSettings& c) const
  {
    mtpt::ReferenceSettings s;
    s.width = c.width;
    s.height = c.height;
    s.modelView = this->input.modelView;
    s.projection = this->input.projection;
    s.unitDistance = c.unitDistance;
    s.clipPlanes = c.clipPlanes;
    s.blendMode = c.blendMode;
    s.scalarRange[0] = Low;
    s.scalarRange[1] = High;
    s.averageRange[0] = c.averageRange[0];
    s.averageRange[1] = c.averageRange[1];
    return mtpt::test::TableReference(this->mesh, this->table, Low, High, s);
  }
};

/// Covered pixels (either image's alpha, or colour, above 0) and their RMSE and worst
/// channel difference between the compositor's RGB and the reference's.
struct Difference
{
  std::size_t covered = 0;
  double rmse = 0, worst = 0;
};

Difference Compare(const std::vector<float>& rgba, const std::vector<double>& rgb)
{
  Difference d;
  double sum = 0;
  for (std::size_t i = 0; i < rgb.size() / 3; ++i)
  {
    const bool covered = rgba[4 * i + 3] > 0 || rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2] > 0;
    if (!covered)
    {
      continue;
    }
    ++d.covered;
    for (int k = 0; k < 3; ++k)
    {
      const double e = std::fabs(rgba[4 * i + k] - rgb[3 * i + k]);
      sum += e * e;
      d.worst = std::max(d.worst, e);
    }
  }
  d.rmse = d.covered ? std::sqrt(sum / (3.0 * d.covered)) : 0.0;
  return d;
}

} // namespace

TEST(BlendModes, IntensityTableIntegratesExactly)
{
  // The mean of o x over random entry intervals against a fine midpoint sum of the table's
  // linear interpolation: the closed form inside one entry and the prefix sums across many.
  const std::vector<float> values = SteepTable();
  const mtpt::TransferFunctionTable tf{ values.data(), 64, -0.5, 1.5 };
  mtpt::IntensityTable table;
  table.Build(tf);
  ASSERT_TRUE(table.Covers(tf));
  auto ox = [&](double u)
  {
    const int i = std::min(static_cast<int>(u), 62);
    const double f = u - i;
    const double o = values[4 * i + 3] + f * (values[4 * i + 7] - values[4 * i + 3]);
    return o * u / 63.0;
  };
  std::mt19937 random(7);
  std::uniform_real_distribution<double> at(0.0, 63.0);
  double worst = 0;
  for (int trial = 0; trial < 400; ++trial)
  {
    double u0 = at(random), u1 = trial % 4 == 0 ? u0 + 0.3 * (at(random) / 63.0) : at(random);
    u1 = std::min(u1, 63.0);
    if (u1 < u0)
    {
      std::swap(u0, u1);
    }
    const int steps = 20000;
    double sum = 0;
    for (int k = 0; k < steps; ++k)
    {
      sum += ox(u0 + (u1 - u0) * (k + 0.5) / steps);
    }
    const double expected = u1 > u0 ? sum / steps : ox(u0);
    worst = std::max(worst, std::fabs(table.Mean(tf, u0, u1) - expected));
  }
  std::printf("worst mean error %.3g\n", worst);
  EXPECT_LT(worst, 1e-7);
  EXPECT_DOUBLE_EQ(table.Mean(tf, 10.0, 10.0), ox(10.0));
  // Beyond the table the scalar is clamped: o x is 0 below it and the last opacity above.
  EXPECT_NEAR(table.Mean(tf, -30.0, 30.0), table.Mean(tf, 0.0, 30.0) * 0.5, 1e-12);
  EXPECT_NEAR(table.Mean(tf, 33.0, 93.0), 0.5 * (table.Mean(tf, 33.0, 63.0) + values[4 * 63 + 3]),
    1e-12);
  EXPECT_DOUBLE_EQ(table.Mean(tf, 80.0, 80.0), values[4 * 63 + 3]);
  EXPECT_EQ(table.Mean(tf, -5.0, -2.0), 0.0);
  // Not built for this table: every mean is 0.
  EXPECT_EQ(mtpt::IntensityTable{}.Mean(tf, 1.0, 2.0), 0.0);
}

TEST(BlendModes, VectorMeansMatchTheTable)
{
  // The compositor's vector paths compute the mean in float (as the OpenGL backend's shader):
  // against IntensityTable::Mean in double, over random intervals, intervals that barely
  // cross an entry boundary, constant scalars and scalars beyond the table.
  const std::vector<float> values = SteepTable();
  const mtpt::TransferFunctionTable tf{ values.data(), 64, -0.5, 1.5 };
  mtpt::IntensityTable table;
  table.Build(tf);
  std::mt19937 random(11);
  std::uniform_real_distribution<float> at(-8.0f, 71.0f), tiny(0.0f, 1e-4f);
  std::vector<float> u0, u1;
  for (int trial = 0; trial < 600; ++trial)
  {
    float a = at(random), b = at(random);
    if (trial % 3 == 1)
    {
      a = std::round(a) - tiny(random); // across a boundary, barely
      b = a + 2 * tiny(random);
    }
    if (trial % 7 == 2)
    {
      b = a; // a constant scalar
    }
    u0.push_back(std::min(a, b));
    u1.push_back(std::max(a, b));
  }
  std::vector<float> means(u0.size());
  mtpt::detail::IntensityMeans(tf, table, u0.data(), u1.data(), means.data(), u0.size());
  double worst = 0;
  for (std::size_t i = 0; i < u0.size(); ++i)
  {
    worst = std::max(worst, std::fabs(means[i] - table.Mean(tf, u0[i], u1[i])));
  }
  std::printf("worst float mean error %.3g (%s)\n", worst, mtpt::detail::RasterTargetName());
  EXPECT_LT(worst, 2e-5);
}

TEST(BlendModes, UnorderedFramesSkipTheSort)
{
  // A frame for a blend mode that reduces in any order keeps the culled cells in id order.
  Scene scene(true, false);
  ASSERT_TRUE(scene.pipeline.Prepare(scene.input, 2));
  EXPECT_TRUE(scene.pipeline.Stats().unordered);
  const mtpt::LargeVector<mtpt::SortKey>& keys = scene.pipeline.Keys();
  ASSERT_GT(keys.size(), 1000u);
  Scene sorted(true, true);
  ASSERT_TRUE(sorted.pipeline.Prepare(sorted.input, 2));
  EXPECT_FALSE(sorted.pipeline.Stats().unordered);
  EXPECT_EQ(sorted.pipeline.Keys().size(), keys.size());
  bool inIdOrder = true, depthSorted = true;
  for (std::size_t k = 1; k < keys.size(); ++k)
  {
    inIdOrder = inIdOrder && mtpt::CellOfKey(keys[k - 1]) < mtpt::CellOfKey(keys[k]);
    depthSorted = depthSorted && keys[k - 1] <= keys[k];
  }
  EXPECT_TRUE(inIdOrder);
  EXPECT_FALSE(depthSorted);
}

TEST(BlendModes, CompositorMatchesTheReference)
{
  // Each mode, orthographic and perspective, against the exact reference over black. The
  // fans come in cell order: the reductions do not depend on it (maximum and minimum bit for
  // bit; the sums to rounding).
  for (bool perspective : { false, true })
  {
    Scene scene(perspective, false);
    Scene sorted(perspective, true);
    ASSERT_TRUE(scene.pipeline.Prepare(scene.input, 2));
    ASSERT_TRUE(sorted.pipeline.Prepare(sorted.input, 2));
    for (mtpt::BlendMode mode : Reductions)
    {
      SCOPED_TRACE(::testing::Message()
        << (perspective ? "perspective" : "orthographic") << ", " << NameOf(mode));
      const mtpt::CompositeSettings s = scene.Settings(mode);
      const std::vector<float> image = scene.Composite(s);
      const Difference d = Compare(image, scene.Reference(s));
      std::printf("%s %s: %zu covered, RMSE %.2e, worst %.2e\n",
        perspective ? "perspective" : "orthographic", NameOf(mode), d.covered, d.rmse, d.worst);
      EXPECT_GT(d.covered, 1000u);
      EXPECT_LT(d.rmse, 5e-4);
      EXPECT_LT(d.worst, 1e-2);
      const std::vector<float> inOrder = sorted.Composite(s);
      double worst = 0;
      for (std::size_t i = 0; i < image.size(); ++i)
      {
        worst = std::max(worst, double(std::fabs(image[i] - inOrder[i])));
      }
      const bool extreme = mode == mtpt::BlendMode::MaximumIntensity ||
        mode == mtpt::BlendMode::MinimumIntensity;
      EXPECT_LE(worst, extreme ? 0.0 : 1e-5);
    }
  }
}

TEST(BlendModes, ClippingPlanesAndOpaqueDepthCutTheReductions)
{
  // An oblique plane through the mesh: the reductions see only the part it keeps, as the
  // reference's rays do. Then an opaque depth in front of everything hides the volume.
  Scene scene(true, false);
  ASSERT_TRUE(scene.pipeline.Prepare(scene.input, 2));
  const mtpt::test::Vec3 centre = mtpt::test::Apply(scene.input.modelView, { 0, 0, 0 });
  const double n[3] = { 0.6, -0.2, -0.77 };
  for (mtpt::BlendMode mode : Reductions)
  {
    SCOPED_TRACE(NameOf(mode));
    mtpt::CompositeSettings s = scene.Settings(mode);
    s.clipPlanes.count = 1;
    std::copy(n, n + 3, s.clipPlanes.plane[0]);
    s.clipPlanes.plane[0][3] = -(n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2]);
    const std::vector<float> clipped = scene.Composite(s);
    const Difference d = Compare(clipped, scene.Reference(s));
    const Difference change = Compare(clipped, scene.Reference(scene.Settings(mode)));
    std::printf("%s clipped: RMSE %.2e (unclipped reference %.2e)\n", NameOf(mode), d.rmse,
      change.rmse);
    EXPECT_LT(d.rmse, 5e-4);
    EXPECT_GT(change.rmse, 100 * d.rmse);
    std::vector<float> depth(static_cast<std::size_t>(s.width) * s.height, 0.0f);
    s.opaqueDepth = depth.data();
    const std::vector<float> hidden = scene.Composite(s);
    EXPECT_EQ(*std::max_element(hidden.begin(), hidden.end()), 0.0f);
  }
}
