// SPDX-License-Identifier: BSD-3-Clause
// Pre-integrated shading: closed forms, a brute-force ray integral, and the compositor.
#include "mtpt/Compositor.h"
#include "mtpt/TransferFunctionTable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace
{

using mtpt::PreIntegrationTable;
using mtpt::TransferFunctionTable;

/// A table of `n` entries over [0, 1] from a function of the scalar.
template <typename F>
std::vector<float> Sample(int n, F rgba)
{
  std::vector<float> t(4 * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    rgba(static_cast<double>(i) / (n - 1), &t[4 * i]);
  }
  return t;
}

/// The emission-absorption integral of a segment by brute force: the table read as
/// Lookup reads it, `steps` midpoint steps, composited front to back.
void BruteForce(const TransferFunctionTable& tf, double front, double back, double length,
  double inverseUnit, int steps, double out[4])
{
  double colour[3] = { 0, 0, 0 }, alpha = 0;
  const double dt = length / steps;
  for (int s = 0; s < steps; ++s)
  {
    const double u = tf.EntryCoordinate(front + (back - front) * (s + 0.5) / steps);
    const int i = std::min(static_cast<int>(u), tf.size - 2);
    const double f = u - i;
    double v[4];
    for (int k = 0; k < 4; ++k)
    {
      v[k] = tf.table[4 * i + k] + f * (tf.table[4 * (i + 1) + k] - tf.table[4 * i + k]);
    }
    const double a = 1.0 - std::exp(-v[3] * dt * inverseUnit);
    for (int k = 0; k < 3; ++k)
    {
      colour[k] += (1.0 - alpha) * a * v[k];
    }
    alpha += (1.0 - alpha) * a;
  }
  for (int k = 0; k < 3; ++k)
  {
    out[k] = alpha > 0 ? colour[k] / alpha : 0.0;
  }
  out[3] = alpha;
}

TEST(PreIntegration, ConstantFunctionGivesTheClosedForm)
{
  const auto table =
    Sample(16, [](double, float* v) { v[0] = 0.2f, v[1] = 0.5f, v[2] = 0.9f, v[3] = 1.5f; });
  const TransferFunctionTable tf{ table.data(), 16, 0.0, 1.0 };
  PreIntegrationTable pre;
  pre.Build(tf);
  for (const float length : { 0.0f, 0.01f, 0.3f, 2.0f, 50.0f })
  {
    float rgba[4];
    pre.Segment(tf, 0.1f, 0.8f, length, 0.5f, rgba);
    EXPECT_NEAR(rgba[3], 1.0 - std::exp(-1.5 * length * 0.5), 1e-6) << length;
    if (length > 0)
    {
      EXPECT_NEAR(rgba[0], 0.2, 1e-6);
      EXPECT_NEAR(rgba[1], 0.5, 1e-6);
      EXPECT_NEAR(rgba[2], 0.9, 1e-6);
    }
  }
}

TEST(PreIntegration, LinearAttenuationIntegratesExactly)
{
  // tau(s) = 2 s: a segment from s0 to s1 of length L has optical depth L (s0 + s1).
  const auto table = Sample(
    101, [](double s, float* v) { v[0] = v[1] = v[2] = 1.0f, v[3] = static_cast<float>(2 * s); });
  const TransferFunctionTable tf{ table.data(), 101, 0.0, 1.0 };
  PreIntegrationTable pre;
  pre.Build(tf);
  const double cases[][3] = { { 0.0, 1.0, 1.0 }, { 0.9, 0.1, 0.7 }, { 0.333, 0.334, 3.0 },
    { 0.5, 0.5, 2.0 }, { 0.01, 0.99, 0.05 } };
  for (const auto& c : cases)
  {
    float rgba[4];
    pre.Segment(
      tf, static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]), 1.0f, rgba);
    EXPECT_NEAR(rgba[3], 1.0 - std::exp(-c[2] * (c[0] + c[1])), 2e-6) << c[0] << " " << c[1];
  }
}

TEST(PreIntegration, NarrowPeakBetweenTheEndScalarsIsCounted)
{
  // Opacity zero except for a peak of width 0.02 around s = 0.5 (area 0.01 * 4 = 0.04).
  const int n = 1001;
  const auto table = Sample(n,
    [](double s, float* v)
    {
      v[0] = 1.0f, v[1] = 0.5f, v[2] = 0.0f;
      v[3] = static_cast<float>(std::max(0.0, 4.0 * (1.0 - std::fabs(s - 0.5) / 0.01)));
    });
  const TransferFunctionTable tf{ table.data(), n, 0.0, 1.0 };
  PreIntegrationTable pre;
  pre.Build(tf);
  // Scalar from 0.2 to 0.8 over length 3: optical depth = 3 * 0.04 / 0.6 = 0.2. Classifying
  // the two end scalars (VTK's PT) sees no opacity at all.
  float rgba[4];
  pre.Segment(tf, 0.2f, 0.8f, 3.0f, 1.0f, rgba);
  EXPECT_NEAR(rgba[3], 1.0 - std::exp(-0.2), 1e-5);
  EXPECT_NEAR(rgba[0], 1.0, 1e-5);
  EXPECT_NEAR(rgba[1], 0.5, 1e-5);
  float front[4], back[4];
  tf.Lookup(0.2f, front);
  tf.Lookup(0.8f, back);
  EXPECT_EQ(front[3] + back[3], 0.0f);
}

TEST(PreIntegration, MatchesTheBruteForceIntegralOnRandomFunctions)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worstColour = 0, worstAlpha = 0;
  for (int trial = 0; trial < 40; ++trial)
  {
    // Random piecewise-linear functions with 6 nodes, some narrow, sampled at 256 entries.
    const int n = 256;
    std::vector<float> table(4 * n);
    std::vector<double> nodes(4 * 6);
    for (double& v : nodes)
    {
      v = unit(random);
    }
    for (int i = 0; i < n; ++i)
    {
      const double x = 5.0 * i / (n - 1);
      const int j = std::min(static_cast<int>(x), 4);
      const double f = x - j;
      for (int k = 0; k < 4; ++k)
      {
        table[4 * i + k] = static_cast<float>(
          (nodes[4 * j + k] + f * (nodes[4 * (j + 1) + k] - nodes[4 * j + k])) * (k == 3 ? 3 : 1));
      }
    }
    const TransferFunctionTable tf{ table.data(), n, 0.0, 1.0 };
    PreIntegrationTable pre;
    pre.Build(tf);
    const double front = unit(random), back = unit(random), length = 4.0 * unit(random);
    float rgba[4];
    pre.Segment(tf, static_cast<float>(front), static_cast<float>(back), static_cast<float>(length),
      1.0f, rgba);
    double exact[4];
    BruteForce(tf, static_cast<float>(front), static_cast<float>(back), static_cast<float>(length),
      1.0, 200000, exact);
    worstAlpha = std::max(worstAlpha, std::fabs(rgba[3] - exact[3]));
    for (int k = 0; k < 3; ++k)
    {
      worstColour = std::max(worstColour, std::fabs(rgba[3] * rgba[k] - exact[3] * exact[k]));
    }
  }
  // Opacity is exact (up to float rounding); premultiplied colour carries only the order
  // of emission inside each compositing step.
  EXPECT_LT(worstAlpha, 2e-5);
  EXPECT_LT(worstColour, 0.01);
  std::printf("pre-integration vs brute force: worst opacity error %.2e, worst premultiplied "
              "colour error %.2e\n",
    worstAlpha, worstColour);
}

TEST(PreIntegration, OpacityIsTheSameInBothDirections)
{
  const auto table = Sample(64,
    [](double s, float* v)
    {
      v[0] = static_cast<float>(s), v[1] = 0.3f, v[2] = static_cast<float>(1 - s);
      v[3] = static_cast<float>(s * s * 5);
    });
  const TransferFunctionTable tf{ table.data(), 64, 0.0, 1.0 };
  PreIntegrationTable pre;
  pre.Build(tf);
  float a[4], b[4];
  pre.Segment(tf, 0.1f, 0.95f, 1.3f, 1.0f, a);
  pre.Segment(tf, 0.95f, 0.1f, 1.3f, 1.0f, b);
  EXPECT_NEAR(a[3], b[3], 1e-6);
  // Emission nearer the front counts more: the bright-red back end shows more from behind.
  EXPECT_GT(b[0], a[0]);
}

TEST(PreIntegration, CompositorShadesBetweenVertexScalars)
{
  // One slot: a square with a thick-vertex-free constant segment (front 0.2, back 0.8,
  // length 3) everywhere; the narrow peak of the test above lies between the scalars.
  const int n = 1001, w = 8, h = 8;
  const auto table = Sample(n,
    [](double s, float* v)
    {
      v[0] = 1.0f, v[1] = 0.5f, v[2] = 0.0f;
      v[3] = static_cast<float>(std::max(0.0, 4.0 * (1.0 - std::fabs(s - 0.5) / 0.01)));
    });
  std::vector<mtpt::TetVertex> vertices(5);
  const float xs[4] = { -1, 1, 1, -1 }, ys[4] = { -1, -1, 1, 1 };
  for (int i = 0; i < 4; ++i)
  {
    vertices[i] = { xs[i], ys[i], 0.0f, 0.2f, 0.8f, 3.0f };
  }
  vertices[4] = vertices[0];
  const std::vector<std::uint32_t> indices = { 0, 1, 2, 0, 2, 3, 4, 4, 4, 4, 4, 4 };
  mtpt::CompositeSettings settings;
  settings.width = w;
  settings.height = h;
  settings.transferFunction = { table.data(), n, 0.0, 1.0 };
  PreIntegrationTable pre;
  pre.Build(settings.transferFunction);
  mtpt::Compositor compositor;
  std::vector<float> image;
  compositor.Composite(vertices.data(), indices.data(), 1, settings, image, 2);
  EXPECT_EQ(image[3], 0.0f) << "VTK-compatible shading misses the peak";
  settings.shading = mtpt::Shading::PreIntegrated;
  settings.preIntegration = &pre;
  compositor.Composite(vertices.data(), indices.data(), 1, settings, image, 2);
  const float alpha = static_cast<float>(1.0 - std::exp(-0.2));
  for (int p = 0; p < w * h; ++p)
  {
    ASSERT_NEAR(image[4 * p + 3], alpha, 1e-5) << p;
    ASSERT_NEAR(image[4 * p + 0], alpha, 1e-5) << p; // premultiplied red 1
    ASSERT_NEAR(image[4 * p + 1], 0.5f * alpha, 1e-5) << p;
  }
  // Without integral functions nothing is drawn (and nothing is read out of bounds).
  settings.preIntegration = nullptr;
  compositor.Composite(vertices.data(), indices.data(), 1, settings, image, 2);
  EXPECT_EQ(image[3], 0.0f);
}

} // namespace
