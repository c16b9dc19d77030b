// SPDX-License-Identifier: BSD-3-Clause
// Near-plane clipping: exact pieces, no holes with the camera inside a mesh, the ray
// integral from the near plane on, and thread-count independence.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/NearPlane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace
{

using mtpt::NearPiece;
using mtpt::NearPlane;
using mtpt::ProjectedPoint;
using mtpt::test::Vec3;

double Volume(const ProjectedPoint c[4])
{
  const Vec3 a = { c[1].eyeX - c[0].eyeX, c[1].eyeY - c[0].eyeY, c[1].eyeZ - c[0].eyeZ };
  const Vec3 b = { c[2].eyeX - c[0].eyeX, c[2].eyeY - c[0].eyeY, c[2].eyeZ - c[0].eyeZ };
  const Vec3 d = { c[3].eyeX - c[0].eyeX, c[3].eyeY - c[0].eyeY, c[3].eyeZ - c[0].eyeZ };
  return std::fabs(mtpt::test::Dot(mtpt::test::Cross(a, b), d)) / 6.0;
}

TEST(NearPlane, PiecesTileTheVisiblePartExactly)
{
  std::mt19937 random(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const mtpt::Matrix4 projection = mtpt::test::Perspective(60, 1.0, 0.5, 10);
  for (int trial = 0; trial < 500; ++trial)
  {
    ProjectedPoint records[4];
    const ProjectedPoint* corners[4];
    float scalars[4];
    for (int i = 0; i < 4; ++i)
    {
      records[i] = ProjectedPoint{};
      records[i].eyeX = u(random);
      records[i].eyeY = u(random);
      records[i].eyeZ = -0.5 + 0.6 * u(random); // around the near plane at z = -0.5
      records[i].scalar = static_cast<float>(i);
      double w = 0;
      const Vec3 ndc =
        mtpt::test::Apply(projection, { records[i].eyeX, records[i].eyeY, records[i].eyeZ }, &w);
      records[i].x = ndc[0];
      records[i].y = ndc[1];
      records[i].z = ndc[2];
      records[i].inverseW = 1.0 / w;
      records[i].usable = w > 0 ? 1 : 0;
      scalars[i] = static_cast<float>(i);
      corners[i] = &records[i];
    }
    if (trial % 7 == 0)
    {
      records[3].eyeZ = records[2].eyeZ = -0.5; // corners near the plane itself
    }
    NearPlane visible(projection);
    NearPlane hidden = visible;
    for (double& c : hidden.c)
    {
      c = -c;
    }
    std::vector<NearPiece> front, back;
    const int n = mtpt::CutTetrahedron(corners, scalars, visible, projection, front);
    mtpt::CutTetrahedron(corners, scalars, hidden, projection, back);
    ASSERT_TRUE(n == 0 || n == 1 || n == 3);
    ASSERT_EQ(static_cast<int>(front.size()), n);
    double pieces = 0;
    for (const auto* list : { &front, &back })
    {
      for (const NearPiece& p : *list)
      {
        pieces += Volume(p.corners);
      }
    }
    const double total = Volume(records);
    ASSERT_NEAR(pieces, total, 1e-12 + 1e-9 * total) << trial;
    // Every corner of a visible piece is on the visible side (new ones on the plane), is
    // projected, and carries the scalar of the tetrahedron's linear field at its position.
    for (const NearPiece& p : front)
    {
      for (int i = 0; i < 4; ++i)
      {
        const ProjectedPoint& c = p.corners[i];
        ASSERT_GE(visible.Distance(c), -1e-12);
        ASSERT_EQ(c.usable, 1);
        ASSERT_NEAR(c.z, std::min(1.0, std::max(c.z, mtpt::NearPlaneNdcZ)), 1e-9);
        // Barycentric coordinates of c in the original tetrahedron give the scalar.
        double m[3][3],
          rhs[3] = { c.eyeX - records[0].eyeX, c.eyeY - records[0].eyeY, c.eyeZ - records[0].eyeZ };
        for (int k = 0; k < 3; ++k)
        {
          m[0][k] = records[k + 1].eyeX - records[0].eyeX;
          m[1][k] = records[k + 1].eyeY - records[0].eyeY;
          m[2][k] = records[k + 1].eyeZ - records[0].eyeZ;
        }
        const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
          m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
          m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        if (std::fabs(det) < 1e-6)
        {
          continue;
        }
        double lambda[3];
        for (int k = 0; k < 3; ++k)
        {
          double mk[3][3];
          std::memcpy(mk, m, sizeof(m));
          for (int r = 0; r < 3; ++r)
          {
            mk[r][k] = rhs[r];
          }
          lambda[k] = (mk[0][0] * (mk[1][1] * mk[2][2] - mk[1][2] * mk[2][1]) -
                        mk[0][1] * (mk[1][0] * mk[2][2] - mk[1][2] * mk[2][0]) +
                        mk[0][2] * (mk[1][0] * mk[2][1] - mk[1][1] * mk[2][0])) /
            det;
        }
        const double expected = 1 * lambda[0] + 2 * lambda[1] + 3 * lambda[2];
        ASSERT_NEAR(p.scalars[i], expected, 1e-4);
      }
    }
  }
}

/// A constant transfer function: every ray's opacity is 1 - exp(-tau * path length).
struct InsideFrame
{
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(6, 3);
  mtpt::FrameInput input;
  std::vector<float> table = { 0.8f, 0.6f, 0.2f, 0.7f, 0.8f, 0.6f, 0.2f, 0.7f };
  int size = 64;
  Vec3 eye = { 0.1, -0.05, 0.3 };
  Vec3 forward = mtpt::test::Normalized({ 0.08, 0.05, -1.0 });
  double nearDistance = 0.05;
  bool preIntegrated = false;
  mtpt::PreIntegrationTable pre;

  explicit InsideFrame(bool perspective)
  {
    input.points = mesh.Points();
    input.cells = mesh.Cells();
    input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    // A view slightly off the grid's axes: along an axis, columns of grid points project
    // onto each other (the edge-on hard case, tested on its own).
    input.modelView = mtpt::test::LookAt(
      eye, { eye[0] + forward[0], eye[1] + forward[1], eye[2] + forward[2] }, { 0, 1, 0 });
    input.projection = perspective ? mtpt::test::Perspective(70, 1.0, nearDistance, 10)
                                   : mtpt::test::Ortho(-0.7, 0.7, -0.7, 0.7, nearDistance, 10);
    input.perspective = perspective;
    input.imageSize = { size, size };
  }

  std::vector<float> Render(int threads, mtpt::FrameStats* stats = nullptr)
  {
    mtpt::FramePipeline pipeline;
    EXPECT_TRUE(pipeline.Run(input, threads));
    if (stats)
    {
      *stats = pipeline.Stats();
    }
    mtpt::CompositeSettings settings;
    settings.width = settings.height = size;
    settings.transferFunction = { table.data(), 2, -10.0, 10.0 };
    settings.unitDistance = 1.0;
    if (preIntegrated)
    {
      pre.Build(settings.transferFunction);
      settings.UsePreIntegration(
        pre, mtpt::PerspectiveInterpolation::FromProjection(input.projection));
    }
    mtpt::Compositor compositor;
    std::vector<float> image;
    compositor.Composite(pipeline.Vertices().data(), pipeline.Indices().data(),
      pipeline.TetrahedronCount(), settings, image, threads);
    return image;
  }

  /// The exact opacity of the pixel: path length inside [-1, 1]^3 beyond the near plane.
  double ExactOpacity(int px, int py) const
  {
    const double x = 2.0 * (px + 0.5) / size - 1.0, y = 2.0 * (py + 0.5) / size - 1.0;
    // World-space ray: origin + t * direction, t the distance along the view axis.
    const Vec3 side = mtpt::test::Normalized(mtpt::test::Cross(forward, { 0, 1, 0 }));
    const Vec3 up = mtpt::test::Cross(side, forward);
    double a = 0.7 * x, b = 0.7 * y; // orthographic: offsets of the origin
    Vec3 origin = eye;
    if (input.perspective)
    {
      const double t = std::tan(35.0 * M_PI / 180.0);
      a = x * t;
      b = y * t;
    }
    else
    {
      for (int k = 0; k < 3; ++k)
      {
        origin[k] += a * side[k] + b * up[k];
      }
      a = b = 0;
    }
    Vec3 direction;
    for (int k = 0; k < 3; ++k)
    {
      direction[k] = forward[k] + a * side[k] + b * up[k];
    }
    double enter = nearDistance, exit = 1e300;
    for (int k = 0; k < 3; ++k)
    {
      const double a = (-1.0 - origin[k]) / direction[k], b = (1.0 - origin[k]) / direction[k];
      enter = std::max(enter, std::min(a, b));
      exit = std::min(exit, std::max(a, b));
    }
    const double length =
      std::max(0.0, exit - enter) * std::sqrt(mtpt::test::Dot(direction, direction));
    return 1.0 - std::exp(-0.7 * length);
  }
};

TEST(NearPlane, OrthographicCameraInsideTheMeshIntegratesFromTheNearPlane)
{
  InsideFrame frame(false);
  mtpt::FrameStats stats;
  const std::vector<float> image = frame.Render(2, &stats);
  EXPECT_GT(stats.nearClipped, 0u);
  EXPECT_GE(stats.nearPieces, stats.nearClipped);
  double worst = 0;
  for (int y = 0; y < frame.size; ++y)
  {
    for (int x = 0; x < frame.size; ++x)
    {
      worst =
        std::max(worst, std::fabs(image[4 * (y * frame.size + x) + 3] - frame.ExactOpacity(x, y)));
    }
  }
  std::printf("orthographic camera inside: %zu cells cut into %zu pieces, worst opacity error "
              "%.2e\n",
    stats.nearClipped, stats.nearPieces, worst);
  EXPECT_LT(worst, 1.5e-3); // float vertex records
}

TEST(NearPlane, PerspectiveCameraInsideTheMeshLeavesNoHoles)
{
  for (bool preIntegrated : { false, true })
  {
    InsideFrame frame(true);
    frame.preIntegrated = preIntegrated;
    mtpt::FrameStats stats;
    const std::vector<float> image = frame.Render(2, &stats);
    EXPECT_GT(stats.nearClipped, 0u);
    double sum = 0, worst = 0;
    int holes = 0;
    for (int y = 0; y < frame.size; ++y)
    {
      for (int x = 0; x < frame.size; ++x)
      {
        const double alpha = image[4 * (y * frame.size + x) + 3];
        holes += alpha < 0.05 ? 1 : 0;
        const double e = alpha - frame.ExactOpacity(x, y);
        sum += e * e;
        worst = std::max(worst, std::fabs(e));
      }
    }
    const double rmse = std::sqrt(sum / (frame.size * frame.size));
    std::printf("perspective camera inside, %s: %zu cells cut into %zu pieces, %d holes, "
                "opacity RMSE %.5f, worst %.5f\n",
      preIntegrated ? "pre-integrated" : "VTK-compatible", stats.nearClipped, stats.nearPieces,
      holes, rmse, worst);
    EXPECT_EQ(holes, 0);
    if (preIntegrated)
    {
      // Perspective-exact segment lengths (mtpt::PerspectiveInterpolation).
      EXPECT_LT(worst, 2e-3);
    }
    else
    {
      // VTK-compatible: lengths interpolated linearly in screen space, as VTK's PT does;
      // cells near the eye span a wide range of depths.
      EXPECT_LT(rmse, 0.025);
    }
  }
}

TEST(NearPlane, IdenticalForEveryThreadCountAndNothingCutFromOutside)
{
  InsideFrame frame(true);
  const std::vector<float> one = frame.Render(1);
  for (int threads : { 2, 3, 8 })
  {
    const std::vector<float> other = frame.Render(threads);
    ASSERT_EQ(0, std::memcmp(one.data(), other.data(), one.size() * sizeof(float))) << threads;
  }
  frame.input.modelView = mtpt::test::LookAt({ 0.3, 0.2, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 });
  mtpt::FrameStats stats;
  frame.Render(2, &stats);
  EXPECT_EQ(stats.nearClipped, 0u);
  EXPECT_EQ(stats.nearPieces, 0u);
}

} // namespace
