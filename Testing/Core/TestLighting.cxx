// SPDX-License-Identifier: BSD-3-Clause
// Shading by lights (mtpt/Lighting.h): the gradients and normals, VTK's lighting equation,
// and the compositor's lit image against the exact reference.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/Gradients.h"
#include "mtpt/Lighting.h"
#include "mtpt/ReferenceRenderer.h"
#include "mtpt/TransferFunctionTable.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace
{

void ExpectFactors(const mtpt::LightFactors& f, const double scale[3], const double offset[3])
{
  for (int k = 0; k < 3; ++k)
  {
    EXPECT_NEAR(f.scale[k], scale[k], 1e-6) << "scale " << k;
    EXPECT_NEAR(f.offset[k], offset[k], 1e-6) << "offset " << k;
  }
}

/// The jittered grid lit in an oblique view, drawn by the pipeline and the compositor with
/// pre-integrated shading, and by the exact reference.
struct LitScene
{
  static constexpr int Width = 80, Height = 66;
  static constexpr double Low = -1.0, High = 2.5;
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(10, 17);
  std::vector<float> table;
  std::vector<float> normals;
  mtpt::FrameInput input;
  mtpt::FramePipeline pipeline;
  mtpt::PreIntegrationTable preIntegration;

  explicit LitScene(bool perspective)
  {
    for (int i = 0; i < 64; ++i)
    {
      const float t = i / 63.0f;
      this->table.insert(this->table.end(), { 0.3f + 0.6f * t, 0.8f - 0.5f * t, 0.6f, 1.5f * t });
    }
    this->input.points = this->mesh.Points();
    this->input.cells = this->mesh.Cells();
    this->input.scalars = { this->mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    mtpt::test::ObliqueView(this->input, perspective);
    std::vector<float> gradients;
    mtpt::PointGradients(this->input.points, this->input.cells, this->input.scalars, gradients, 2);
    mtpt::CellNormals(this->input.cells, this->input.points.count, gradients, this->normals, 2);
    this->preIntegration.Build(this->Table());
  }

  mtpt::TransferFunctionTable Table() const
  {
    return { this->table.data(), static_cast<int>(this->table.size() / 4), Low, High };
  }

  /// The compositor's premultiplied RGBA image, lit by `lighting` or not.
  std::vector<float> Composite(const mtpt::Lighting* lighting)
  {
    EXPECT_TRUE(this->pipeline.Run(this->input, 2));
    const std::size_t n = this->pipeline.SortedCount();
    this->pipeline.DecomposeFans(0, n, 2);
    std::vector<mtpt::LightFactors> lights;
    if (lighting)
    {
      this->pipeline.LightWindow(
        0, n, *lighting, this->normals.data(), this->input.modelView, lights, 2);
    }
    mtpt::CompositeSettings s;
    s.width = Width;
    s.height = Height;
    s.transferFunction = this->Table();
    s.unitDistance = 0.5;
    s.UsePreIntegration(
      this->preIntegration, mtpt::PerspectiveInterpolation::FromProjection(this->input.projection));
    mtpt::Compositor compositor;
    compositor.Begin(s);
    compositor.Composite(
      this->pipeline.Fans().data(), n, 2, lighting ? lights.data() : nullptr);
    std::vector<float> rgba(4 * Width * Height);
    compositor.Resolve({ 0, 0, Width, Height }, static_cast<const float*>(nullptr), rgba.data(), 2);
    return rgba;
  }

  std::vector<double> Reference(const mtpt::Lighting& lighting) const
  {
    mtpt::ReferenceSettings s;
    s.width = Width;
    s.height = Height;
    s.modelView = this->input.modelView;
    s.projection = this->input.projection;
    s.unitDistance = 0.5;
    s.lighting = lighting;
    s.normals = this->normals.data();
    return mtpt::test::TableReference(this->mesh, this->table, Low, High, s);
  }
};

/// Covered RMSE and worst channel difference between an RGBA and an RGB image.
std::pair<double, double> Difference(const std::vector<float>& rgba, const std::vector<double>& rgb)
{
  double sum = 0, worst = 0;
  std::size_t covered = 0;
  for (std::size_t i = 0; i < rgb.size() / 3; ++i)
  {
    if (!(rgba[4 * i + 3] > 0) && rgb[3 * i] + rgb[3 * i + 1] + rgb[3 * i + 2] == 0)
    {
      continue;
    }
    ++covered;
    for (int k = 0; k < 3; ++k)
    {
      const double e = std::fabs(rgba[4 * i + k] - rgb[3 * i + k]);
      sum += e * e;
      worst = std::max(worst, e);
    }
  }
  return { covered ? std::sqrt(sum / (3.0 * covered)) : 1.0, worst };
}

} // namespace

TEST(Lighting, LinearFieldsHaveTheirExactGradient)
{
  // Volume-weighted means of constant gradients: a linear field's own gradient at every point
  // and cell, on a jittered grid of Kuhn tetrahedra (every orientation of cell).
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(6, 3);
  const double a[3] = { 0.5, -2.0, 3.0 };
  for (std::size_t p = 0; p < mesh.scalars.size(); ++p)
  {
    const float* x = mesh.points.data() + 3 * p;
    mesh.scalars[p] = static_cast<float>(a[0] * x[0] + a[1] * x[1] + a[2] * x[2] + 1.0);
  }
  // A cell whose ids run out of range counts for nothing.
  mesh.AddTetrahedron(0, 1, 2, 1000000);
  const mtpt::ScalarsView scalars{ mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  std::vector<float> gradients, normals;
  mtpt::PointGradients(mesh.Points(), mesh.Cells(), scalars, gradients, 2);
  ASSERT_EQ(gradients.size(), mesh.points.size());
  const double length = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (std::size_t p = 0; p < gradients.size() / 3; ++p)
  {
    for (int k = 0; k < 3; ++k)
    {
      ASSERT_NEAR(gradients[3 * p + k], a[k], 2e-4) << "point " << p;
    }
  }
  mtpt::CellNormals(mesh.Cells(), mesh.points.size() / 3, gradients, normals, 2);
  ASSERT_EQ(normals.size(), 3 * mesh.CellCount());
  for (std::size_t c = 0; c + 1 < mesh.CellCount(); ++c)
  {
    for (int k = 0; k < 3; ++k)
    {
      ASSERT_NEAR(normals[3 * c + k], a[k] / length, 1e-5) << "cell " << c;
    }
  }
  const std::size_t last = mesh.CellCount() - 1;
  EXPECT_EQ(normals[3 * last] * normals[3 * last] + normals[3 * last + 2] * normals[3 * last + 2],
    0.0f);
  // Any thread count gives the same gradients.
  std::vector<float> one;
  mtpt::PointGradients(mesh.Points(), mesh.Cells(), scalars, one, 1);
  EXPECT_EQ(one, gradients);
  // A gradient beyond float's range keeps its direction at a magnitude of 1e30.
  mtpt::test::TetMesh tiny;
  tiny.points = { 0, 0, 0, 1e-20f, 0, 0, 0, 1e-20f, 0, 0, 0, 1e-20f };
  tiny.scalars = { 0, 1e25f, 0, 0 };
  tiny.AddTetrahedron(0, 1, 2, 3);
  std::vector<float> steep;
  mtpt::PointGradients(tiny.Points(), tiny.Cells(),
    { tiny.scalars.data(), mtpt::ScalarsView::Association::Points }, steep, 1);
  for (std::size_t p = 0; p < 4; ++p)
  {
    EXPECT_FLOAT_EQ(steep[3 * p], 1e30f);
    EXPECT_EQ(steep[3 * p + 1], 0.0f);
    EXPECT_EQ(steep[3 * p + 2], 0.0f);
  }
  // Cell scalars have no gradient: zero everywhere.
  std::vector<float> perCell(mesh.CellCount(), 1.0f);
  mtpt::PointGradients(mesh.Points(), mesh.Cells(),
    { perCell.data(), mtpt::ScalarsView::Association::Cells }, gradients, 2);
  EXPECT_EQ(*std::max_element(gradients.begin(), gradients.end()), 0.0f);
}

TEST(Lighting, TheHeadlightIsVTKsDefaultLighting)
{
  // vtkVolumeShaderComposer.h, default lighting: ambient c + [n.l > 0] (diffuse (n.l) Ld c +
  // specular (r.v)^p Ls), the light at the eye. A sample straight ahead of the eye.
  mtpt::Lighting lighting;
  lighting.lights[0].diffuse[1] = 0.5;
  lighting.lights[0].specular[2] = 0.25;
  const double at[3] = { 0, 0, -5 };
  {
    // The gradient along the light's way: fully lit, the highlight at its peak.
    const double n[3] = { 0, 0, -1 }, scale[3] = { 0.8, 0.45, 0.8 }, offset[3] = { 0.2, 0.2, 0.05 };
    ExpectFactors(mtpt::LightCell(lighting, n, at), scale, offset);
  }
  {
    // Facing the eye: two-sided lighting flips it, one-sided leaves only the ambient term.
    const double n[3] = { 0, 0, 1 }, scale[3] = { 0.8, 0.45, 0.8 }, offset[3] = { 0.2, 0.2, 0.05 };
    ExpectFactors(mtpt::LightCell(lighting, n, at), scale, offset);
    lighting.twoSided = false;
    const double ambient[3] = { 0.1, 0.1, 0.1 }, none[3] = { 0, 0, 0 };
    ExpectFactors(mtpt::LightCell(lighting, n, at), ambient, none);
    lighting.twoSided = true;
  }
  {
    // At 60 degrees: n.l = 1/2, and the reflection points away from the eye (no highlight).
    const double n[3] = { std::sqrt(0.75), 0, -0.5 };
    const double scale[3] = { 0.45, 0.275, 0.45 }, offset[3] = { 0, 0, 0 };
    ExpectFactors(mtpt::LightCell(lighting, n, at), scale, offset);
  }
  {
    // No normal (a zero gradient): the ambient term only.
    const double n[3] = { 0, 0, 0 }, scale[3] = { 0.1, 0.1, 0.1 }, offset[3] = { 0, 0, 0 };
    ExpectFactors(mtpt::LightCell(lighting, n, at), scale, offset);
  }
}

TEST(Lighting, EveryLightCountsOtherwise)
{
  // Several lights (the light kit): ambient sum(La) + diffuse sum((n.l) Ld) c +
  // specular sum((r.v)^p Ls), positional lights attenuated and bounded by their cone.
  mtpt::Lighting lighting;
  lighting.headlight = false;
  lighting.count = 3;
  mtpt::Light& key = lighting.lights[0]; // straight down the view axis
  key.ambient[0] = key.ambient[1] = key.ambient[2] = 0.5;
  mtpt::Light& side = lighting.lights[1]; // along +x: perpendicular to the normal
  side.direction[0] = 1;
  side.direction[2] = 0;
  side.diffuse[0] = 0.25;
  mtpt::Light& spot = lighting.lights[2]; // 4 units behind the eye, attenuated by 1 / d
  spot.positional = true;
  spot.position[2] = 4;
  spot.attenuation[0] = 0;
  spot.attenuation[1] = 1;
  spot.coneAngle = 30;
  spot.exponent = 2;
  const double at[3] = { 0, 0, -4 }, n[3] = { 0, 0, -1 };
  // key: n.l = 1, r.v = 1; side: n.l = 0; spot: d = 8, n.l = 1, r.v = 1, 1/8 attenuation.
  const double diffuse = 1 + 0.125, specular = 1 + 0.125;
  const double ambient = 0.5 + 1 + 1;
  const double scale[3] = { 0.7 * diffuse, 0.7 * diffuse, 0.7 * diffuse };
  const double offset[3] = { 0.1 * ambient + 0.2 * specular, 0.1 * ambient + 0.2 * specular,
    0.1 * ambient + 0.2 * specular };
  ExpectFactors(mtpt::LightCell(lighting, n, at), scale, offset);
  // Off the spot's cone: only the key light and the ambient colours remain.
  const double aside[3] = { 8, 0, -4 };
  const mtpt::LightFactors off = mtpt::LightCell(lighting, n, aside);
  EXPECT_NEAR(off.scale[0], 0.7, 1e-6);
  // No light at all: VTK's ray caster leaves the samples black.
  lighting.count = 0;
  const double black[3] = { 0, 0, 0 };
  ExpectFactors(mtpt::LightCell(lighting, n, at), black, black);
}

TEST(Lighting, CompositorMatchesTheReference)
{
  // Lit per cell, the factors commute with pre-integration: the compositor's fragments and the
  // reference's segments agree up to rounding, in both projections, with the headlight and
  // with several lights; and the light shows (far from the unlit image).
  for (bool perspective : { false, true })
  {
    LitScene scene(perspective);
    mtpt::Lighting headlight;
    headlight.specularPower = 4;
    mtpt::Lighting kit;
    kit.headlight = false;
    kit.count = 2;
    kit.lights[0].direction[0] = 0.6;
    kit.lights[0].direction[2] = -0.8;
    kit.lights[0].ambient[0] = kit.lights[0].ambient[1] = kit.lights[0].ambient[2] = 0;
    kit.lights[1].positional = true;
    kit.lights[1].position[1] = 3;
    kit.lights[1].coneAngle = 180;
    kit.lights[1].diffuse[2] = 0.3;
    const std::vector<float> unlit = scene.Composite(nullptr);
    {
      // The unlit image's own error, for scale: the pre-integration table's (64 entries).
      mtpt::Lighting identity;
      identity.ambient = 1;
      identity.diffuse = identity.specular = 0;
      const auto [rmse, worst] = Difference(unlit, scene.Reference(identity));
      std::printf("unlit: RMSE %.3g, worst %.3g\n", rmse, worst);
      EXPECT_LT(rmse, 2e-3);
    }
    for (const mtpt::Lighting* lighting : { &headlight, &kit })
    {
      const std::vector<double> reference = scene.Reference(*lighting);
      const auto [rmse, worst] = Difference(scene.Composite(lighting), reference);
      const auto [light, unused] = Difference(unlit, reference);
      std::printf("%s, %s: RMSE %.3g, worst %.3g, unlit %.3g\n",
        perspective ? "perspective" : "orthographic",
        lighting == &headlight ? "headlight" : "two lights", rmse, worst, light);
      // Measured: RMSE 5e-4 to 1e-3, worst 0.018, as the unlit image's (7.6e-4 to 9.7e-4).
      EXPECT_LT(rmse, 2e-3);
      EXPECT_LT(worst, 0.04);
      EXPECT_GT(light, 0.03) << "the lighting shows";
    }
  }
}
