// SPDX-License-Identifier: BSD-3-Clause
// Transform to NDC and depth keys: against double-precision references, for every
// storage type VTK uses, identical for any thread count, and the batched (SIMD) culling
// keys identical to the scalar rule with every instruction set.
#include "TestHelpers.h"

#include "mtpt/DepthKeys.h"
#include "mtpt/Transform.h"

#include "detail/KeyBatch.h"
#include "detail/PixelCoverage.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace
{

using namespace mtpt::test;

TEST(Helpers, InverseIsInverse)
{
  const mtpt::Matrix4 m = mtpt::Multiply(Perspective(50, 1.3, 0.5, 20),
    mtpt::Multiply(LookAt({ 1, 2, 5 }, { 0, 0, 0 }, { 0, 1, 0 }), Scale(1, 2, 0.5)));
  const mtpt::Matrix4 product = mtpt::Multiply(m, Inverse(m));
  const mtpt::Matrix4 identity = mtpt::IdentityMatrix();
  for (int i = 0; i < 16; ++i)
  {
    EXPECT_NEAR(product[i], identity[i], 1e-12);
  }
}

bool SameRecord(const mtpt::ProjectedPoint& a, const mtpt::ProjectedPoint& b)
{
  return a.x == b.x && a.y == b.y && a.z == b.z && a.inverseW == b.inverseW && a.eyeX == b.eyeX &&
    a.eyeY == b.eyeY && a.eyeZ == b.eyeZ && a.scalar == b.scalar && a.usable == b.usable;
}

TEST(Transform, MatchesDoubleReferenceForFloatAndDoublePoints)
{
  const TetMesh mesh = JitteredGrid(6, 3);
  const std::size_t n = mesh.points.size() / 3;
  const std::vector<double> asDouble(mesh.points.begin(), mesh.points.end());
  const mtpt::Matrix4 mv = LookAt({ 0.5, 1, 4 }, { 0, 0, 0 }, { 0, 1, 0 });
  const mtpt::Matrix4 proj = Perspective(40, 1.0, 1.0, 10.0);
  const mtpt::Matrix4 mvp = mtpt::Multiply(proj, mv);
  const mtpt::ScalarsView scalars{ mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  std::vector<mtpt::ProjectedPoint> fromFloat(n), fromDouble(n), oneThread(n);
  mtpt::ProjectPoints(
    mtpt::PointsView::FromFloat(mesh.points.data(), n), scalars, mv, proj, fromFloat.data(), 3);
  mtpt::ProjectPoints(
    mtpt::PointsView::FromDouble(asDouble.data(), n), scalars, mv, proj, fromDouble.data(), 2);
  mtpt::ProjectPoints(
    mtpt::PointsView::FromFloat(mesh.points.data(), n), scalars, mv, proj, oneThread.data(), 1);
  for (std::size_t i = 0; i < n; ++i)
  {
    ASSERT_TRUE(SameRecord(fromFloat[i], fromDouble[i])) << i;
    ASSERT_TRUE(SameRecord(fromFloat[i], oneThread[i])) << i;
    const Vec3 p{ asDouble[3 * i], asDouble[3 * i + 1], asDouble[3 * i + 2] };
    double w;
    const Vec3 expected = Apply(mvp, p, &w);
    const Vec3 eye = Apply(mv, p);
    EXPECT_NEAR(fromFloat[i].x, expected[0], 1e-12);
    EXPECT_NEAR(fromFloat[i].y, expected[1], 1e-12);
    EXPECT_NEAR(fromFloat[i].z, expected[2], 1e-12);
    EXPECT_NEAR(fromFloat[i].inverseW, 1.0 / w, 1e-12);
    EXPECT_EQ(fromFloat[i].usable, 1);
    EXPECT_NEAR(fromFloat[i].eyeX, eye[0], 1e-12);
    EXPECT_NEAR(fromFloat[i].eyeY, eye[1], 1e-12);
    EXPECT_NEAR(fromFloat[i].eyeZ, eye[2], 1e-12);
    EXPECT_EQ(fromFloat[i].scalar, mesh.scalars[i]);
  }
  // Cell scalars are not copied into the point records.
  std::vector<mtpt::ProjectedPoint> withCellScalars(n);
  mtpt::ProjectPoints(mtpt::PointsView::FromFloat(mesh.points.data(), n),
    { mesh.scalars.data(), mtpt::ScalarsView::Association::Cells }, mv, proj,
    withCellScalars.data(), 2);
  EXPECT_EQ(withCellScalars[7].scalar, 0.0f);
}

TEST(Transform, PartsArePlacedByTheirOwnMatrices)
{
  // Two parts, the second with a model matrix of its own: its records are those of its points
  // projected with model-view times that matrix; the first part's, of model-view alone.
  const TetMesh mesh = JitteredGrid(4, 5);
  const std::size_t n = mesh.points.size() / 3;
  const mtpt::Matrix4 mv = LookAt({ 0.5, 1, 4 }, { 0, 0, 0 }, { 0, 1, 0 });
  const mtpt::Matrix4 proj = Perspective(40, 1.0, 1.0, 10.0);
  const mtpt::Matrix4 model =
    mtpt::Multiply(Scale(1.5, 0.5, 2), LookAt({ 0.2, 0, 1 }, { 0, 0, 0 }, { 0, 1, 0 }));
  const mtpt::ScalarsView scalars{ mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
  mtpt::MeshPart parts[2];
  for (mtpt::MeshPart& part : parts)
  {
    part.points = mtpt::PointsView::FromFloat(mesh.points.data(), n);
  }
  parts[1].model = &model;
  mtpt::PointsView points;
  mtpt::CellsView cells;
  mtpt::MeshParts(parts, 2, points, cells);
  std::vector<float> twice(mesh.scalars);
  twice.insert(twice.end(), mesh.scalars.begin(), mesh.scalars.end());
  std::vector<mtpt::ProjectedPoint> placed(2 * n), plain(n), moved(n);
  mtpt::ProjectPoints(points, { twice.data(), scalars.association }, mv, proj, placed.data(), 2);
  mtpt::ProjectPoints(parts[0].points, scalars, mv, proj, plain.data(), 1);
  mtpt::ProjectPoints(parts[0].points, scalars, mtpt::Multiply(mv, model), proj, moved.data(), 1);
  for (std::size_t i = 0; i < n; ++i)
  {
    ASSERT_TRUE(SameRecord(placed[i], plain[i])) << i;
    ASSERT_TRUE(SameRecord(placed[n + i], moved[i])) << i;
  }
  EXPECT_FALSE(SameRecord(placed[n + 1], plain[1])) << "the matrix moves the points";
}

TEST(Transform, FlagsPointsNoCellMayUse)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  // In front of the eye; behind it; on the eye plane; NaN; infinite; fine but NaN scalar;
  // beyond the coordinate limit (double input).
  const std::vector<double> xyz = { 0, 0, 0, 0, 0, 10, 0.5, 0, 5, nan, 0, 0, inf, 0, 0, 0.1, 0.2,
    0.3, 1e31, 0, 0 };
  const std::vector<float> scalars = { 1, 1, 1, 1, 1, nan, 1 };
  std::vector<mtpt::ProjectedPoint> out(7);
  mtpt::ProjectPoints(mtpt::PointsView::FromDouble(xyz.data(), 7),
    { scalars.data(), mtpt::ScalarsView::Association::Points },
    LookAt({ 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }), Perspective(60, 1, 0.1, 100), out.data(), 2);
  const std::int32_t expected[7] = { 1, 0, 0, 0, 0, 0, 0 };
  for (int i = 0; i < 7; ++i)
  {
    EXPECT_EQ(out[i].usable, expected[i]) << "point " << i;
  }
}

TEST(Transform, FarFromTheOriginKeepsPrecision)
{
  // A small cell centred at 1e7 with a camera looking at it: double points and double
  // arithmetic give NDC and eye coordinates as accurate as for the same scene at the origin.
  const double offset = 1e7;
  const std::vector<double> local = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, 0.25, 0.125 };
  std::vector<double> shifted = local;
  for (double& v : shifted)
  {
    v += offset;
  }
  const mtpt::Matrix4 proj = Ortho(-1, 1, -1, 1, 0.1, 10);
  const mtpt::Matrix4 atOrigin = LookAt({ 0.3, 0.2, 3 }, { 0.3, 0.2, 0 }, { 0, 1, 0 });
  const mtpt::Matrix4 atOffset = LookAt({ 0.3 + offset, 0.2 + offset, 3 + offset },
    { 0.3 + offset, 0.2 + offset, offset }, { 0, 1, 0 });
  std::vector<mtpt::ProjectedPoint> a(5), b(5);
  mtpt::ProjectPoints(
    mtpt::PointsView::FromDouble(local.data(), 5), {}, atOrigin, proj, a.data(), 1);
  mtpt::ProjectPoints(
    mtpt::PointsView::FromDouble(shifted.data(), 5), {}, atOffset, proj, b.data(), 1);
  for (int i = 0; i < 5; ++i)
  {
    EXPECT_NEAR(a[i].x, b[i].x, 1e-8);
    EXPECT_NEAR(a[i].y, b[i].y, 1e-8);
    EXPECT_NEAR(a[i].z, b[i].z, 1e-8);
    EXPECT_NEAR(a[i].eyeZ, b[i].eyeZ, 1e-8);
  }
}

TEST(DepthKeys, OrthographicAndPerspectiveDepthsForEveryStorage)
{
  const TetMesh mesh = JitteredGrid(4, 5);
  const std::size_t cells = mesh.CellCount();
  const std::size_t n = mesh.points.size() / 3;
  const std::vector<std::int32_t> conn32(mesh.connectivity.begin(), mesh.connectivity.end());
  const std::vector<std::int32_t> offs32(mesh.offsets.begin(), mesh.offsets.end());
  const mtpt::Matrix4 mv =
    mtpt::Multiply(LookAt({ 1, 2, 6 }, { 0, 0, 0 }, { 0, 1, 0 }), Scale(1, 1.5, 0.75));
  std::vector<mtpt::ProjectedPoint> projected(n);
  mtpt::ProjectPoints(mesh.Points(), {}, mv, Perspective(45, 1, 1, 20), projected.data(), 2);
  for (bool perspective : { false, true })
  {
    std::vector<mtpt::SortKey> reference(cells), other(cells);
    mtpt::ComputeDepthKeys(projected.data(), n, mesh.Cells(), perspective, reference.data(), 1);
    for (std::size_t c = 0; c < cells; ++c)
    {
      Vec3 centroid{ 0, 0, 0 };
      for (int i = 0; i < 4; ++i)
      {
        const std::int64_t id = mesh.connectivity[4 * c + i];
        for (int k = 0; k < 3; ++k)
        {
          centroid[k] += 0.25 * mesh.points[3 * id + k];
        }
      }
      const Vec3 eye = Apply(mv, centroid);
      const double depth = perspective ? Dot(eye, eye) : -eye[2];
      ASSERT_EQ(mtpt::CellOfKey(reference[c]), c);
      // Equal up to the float rounding of the depth (one unit in the last place).
      const auto code = static_cast<std::int64_t>(reference[c] >> 32);
      const auto expected = static_cast<std::int64_t>(mtpt::EncodeDepth(static_cast<float>(depth)));
      ASSERT_LE(std::abs(code - expected), 1) << c;
    }
    mtpt::ComputeDepthKeys(projected.data(), n,
      mtpt::CellsView::FromInt32(conn32.data(), offs32.data(), cells), perspective, other.data(),
      3);
    EXPECT_EQ(reference, other);
    mtpt::ComputeDepthKeys(projected.data(), n, mesh.Cells(), perspective, other.data(), 8);
    EXPECT_EQ(reference, other);
  }
}

TEST(DepthKeys, InvalidCellsGoFirstWithInfiniteDepth)
{
  TetMesh mesh;
  mesh.points = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1 };
  mesh.AddTetrahedron(0, 1, 2, 3);
  mesh.AddTetrahedron(0, 1, 2, 7);                                      // id out of range
  mesh.AddTetrahedron(0, 1, -1, 3);                                     // negative id
  mesh.connectivity.insert(mesh.connectivity.end(), { 0, 1, 2, 3, 4 }); // 5 points
  mesh.offsets.push_back(static_cast<std::int64_t>(mesh.connectivity.size()));
  std::vector<mtpt::SortKey> keys(mesh.CellCount());
  std::vector<mtpt::ProjectedPoint> projected(5);
  mtpt::ProjectPoints(
    mesh.Points(), {}, mtpt::IdentityMatrix(), mtpt::IdentityMatrix(), projected.data(), 1);
  mtpt::ComputeDepthKeys(projected.data(), 5, mesh.Cells(), false, keys.data(), 2);
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_NE(keys[0], mtpt::MakeSortKey(inf, 0));
  for (std::uint32_t c = 1; c < 4; ++c)
  {
    EXPECT_EQ(keys[c], mtpt::MakeSortKey(inf, c));
  }
}

/// The batched depth keys' tests, run with each instruction set in turn.
class KeySimd : public ::testing::TestWithParam<std::int64_t>
{
protected:
  void SetUp() override { hwy::SetSupportedTargetsForTest(this->GetParam()); }
  void TearDown() override { hwy::SetSupportedTargetsForTest(0); }
};

// ComputeVisibleDepthKeys (batched, one cell per SIMD lane) against the rule it implements,
// computed here from the scalar keys: a cell of four usable corners all beyond one clip plane
// is left out with the frustum test, one whose box holds no pixel centre with the viewport's;
// every other cell keeps ComputeDepthKeys' key, in list order, bit for bit.
TEST_P(KeySimd, VisibleKeysAreTheScalarKeysOfTheCellsKept)
{
  TetMesh mesh = LatticeTetrahedra(3000, 5);
  // Cells that are not tetrahedra: an id out of range, and five points.
  mesh.AddTetrahedron(0, 1, 2, 1000);
  mesh.connectivity.insert(mesh.connectivity.end(), { 0, 1, 2, 3, 4 });
  mesh.offsets.push_back(static_cast<std::int64_t>(mesh.connectivity.size()));
  mesh.AddTetrahedron(3, 4, 5, 6);
  const std::size_t cells = mesh.CellCount(), points = mesh.points.size() / 3;
  // Every cell, and every third one (a culling list).
  std::vector<std::uint32_t> everyThird;
  for (std::uint32_t c = 0; c < cells; c += 3)
  {
    everyThird.push_back(c);
  }
  struct KeyView
  {
    mtpt::Matrix4 modelView, projection;
    bool perspective;
  };
  const KeyView views[] = { { LookAt({ 0, 0, 6 }, { 0, 0, 0 }, { 0, 1, 0 }),
                              Ortho(-0.8, 0.8, -0.8, 0.8, 5.5, 12), false },
    { LookAt({ 0.3, 0.2, 2.5 }, { 0, 0, 0 }, { 0, 1, 0 }), Perspective(50, 1.2, 1.2, 4), true } };
  std::size_t culledByFrustum = 0, culledByPixels = 0;
  for (const KeyView& view : views)
  {
    std::vector<mtpt::ProjectedPoint> projected(points);
    mtpt::ProjectPoints(mesh.Points(), {}, view.modelView, view.projection, projected.data(), 2);
    std::vector<mtpt::SortKey> all(cells);
    mtpt::ComputeDepthKeys(projected.data(), points, mesh.Cells(), view.perspective, all.data(), 1);
    for (const mtpt::KeyCulling culling : { mtpt::KeyCulling{}, mtpt::KeyCulling{ true, 0, 0 },
           mtpt::KeyCulling{ true, 7, 5 }, mtpt::KeyCulling{ false, 300, 200 } })
    {
      const std::vector<std::uint32_t>* lists[] = { nullptr, &everyThird };
      for (const std::vector<std::uint32_t>* list : lists)
      {
        SCOPED_TRACE(::testing::Message()
          << "perspective " << view.perspective << ", frustum " << culling.frustum << ", viewport "
          << culling.imageSize.width << "x" << culling.imageSize.height << ", list "
          << (list != nullptr));
        std::vector<mtpt::SortKey> expected;
        mtpt::KeyCounts expectedCounts;
        const std::size_t n = list ? list->size() : cells;
        for (std::size_t i = 0; i < n; ++i)
        {
          const std::uint32_t c = list ? (*list)[i] : static_cast<std::uint32_t>(i);
          const auto begin = mesh.offsets[c], end = mesh.offsets[c + 1];
          bool tetrahedron = end - begin == 4, usable = tetrahedron;
          const mtpt::ProjectedPoint* corners[4] = {};
          for (int k = 0; tetrahedron && k < 4; ++k)
          {
            const auto id = mesh.connectivity[begin + k];
            tetrahedron = id >= 0 && static_cast<std::size_t>(id) < points;
            corners[k] = tetrahedron ? &projected[static_cast<std::size_t>(id)] : nullptr;
            usable = tetrahedron && usable && corners[k]->usable;
          }
          if (usable)
          {
            auto all4 = [&](auto beyond)
            {
              return beyond(*corners[0]) && beyond(*corners[1]) && beyond(*corners[2]) &&
                beyond(*corners[3]);
            };
            const bool outside = all4([](const mtpt::ProjectedPoint& p) { return p.x < -1; }) ||
              all4([](const mtpt::ProjectedPoint& p) { return p.x > 1; }) ||
              all4([](const mtpt::ProjectedPoint& p) { return p.y < -1; }) ||
              all4([](const mtpt::ProjectedPoint& p) { return p.y > 1; }) ||
              all4([](const mtpt::ProjectedPoint& p) { return p.z < -1; }) ||
              all4([](const mtpt::ProjectedPoint& p) { return p.z > 1; });
            if (culling.frustum && outside)
            {
              ++expectedCounts.frustumCulled;
              continue;
            }
            if (!culling.imageSize.Empty() &&
              !mtpt::detail::CoversPixelCentre(corners, culling.imageSize))
            {
              ++expectedCounts.pixelCulled;
              continue;
            }
          }
          expected.push_back(all[c]);
        }
        expectedCounts.kept = expected.size();
        culledByFrustum += expectedCounts.frustumCulled;
        culledByPixels += expectedCounts.pixelCulled;
        for (const int threads : { 1, 2, 3 })
        {
          std::vector<mtpt::SortKey> keys(n, 0);
          const mtpt::KeyCounts counts =
            mtpt::ComputeVisibleDepthKeys(projected.data(), points, mesh.Cells(),
              list ? list->data() : nullptr, n, view.perspective, culling, keys.data(), threads);
          keys.resize(counts.kept);
          ASSERT_EQ(keys, expected) << threads << " threads";
          EXPECT_EQ(counts.frustumCulled, expectedCounts.frustumCulled);
          EXPECT_EQ(counts.pixelCulled, expectedCounts.pixelCulled);
        }
      }
    }
  }
  // Both kinds of culling happened, so both were compared.
  EXPECT_GT(culledByFrustum, 100u);
  EXPECT_GT(culledByPixels, 100u);
}

INSTANTIATE_TEST_SUITE_P(InstructionSets, KeySimd,
  ::testing::ValuesIn(hwy::SupportedAndGeneratedTargets()),
  [](const ::testing::TestParamInfo<std::int64_t>& info)
  { return std::string(hwy::TargetName(info.param)); });

} // namespace
