// SPDX-License-Identifier: BSD-3-Clause
// Decomposition: exact thickness and scalars at the thick vertex, exact coverage of the
// projection, fixed-stride buffers identical for any thread count and order method, the
// batched (SIMD) decomposition identical to the scalar one with every instruction set, and
// finite, in-range buffers for degenerate input.
#include "TestHelpers.h"

#include "mtpt/Decompose.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/VisibilityOrder.h"
#include "mtpt/NearPlane.h"

#include "detail/DecomposeBatch.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <random>
#include <vector>

namespace
{

using namespace mtpt::test;
using mtpt::ProjectionClass;
using mtpt::TetVertex;

struct View
{
  mtpt::Matrix4 modelView, projection;
  bool perspective;
};

View OrthographicView()
{
  return { mtpt::Multiply(LookAt({ 1.0, 1.5, 4.0 }, { 0, 0, 0 }, { 0, 1, 0 }), Scale(1, 2, 0.5)),
    Ortho(-2, 2, -2, 2, 0.5, 10), false };
}

View PerspectiveView()
{
  return { mtpt::Multiply(LookAt({ 0.5, 1.0, 3.5 }, { 0, 0, 0 }, { 0, 1, 0 }), Scale(1, 2, 0.5)),
    Perspective(60, 1.2, 0.5, 10), true };
}

double TriangleArea(const TetVertex& a, const TetVertex& b, const TetVertex& c)
{
  return 0.5 *
    std::fabs(
      (double(b.x) - a.x) * (double(c.y) - a.y) - (double(b.y) - a.y) * (double(c.x) - a.x));
}

/// Area of the convex hull of 4 points (gift wrapping is overkill: try the 3 quad orders
/// and the 4 triangles and keep the largest simple polygon area).
double HullArea(const double x[4], const double y[4])
{
  auto tri = [&](int a, int b, int c)
  { return 0.5 * std::fabs((x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a])); };
  auto quad = [&](int a, int b, int c, int d)
  {
    const double s = (x[a] * y[b] - x[b] * y[a]) + (x[b] * y[c] - x[c] * y[b]) +
      (x[c] * y[d] - x[d] * y[c]) + (x[d] * y[a] - x[a] * y[d]);
    return 0.5 * std::fabs(s);
  };
  // The hull is the largest of the candidate polygons (a self-intersecting order has a
  // smaller signed area than the convex one).
  return std::max({ tri(1, 2, 3), tri(0, 2, 3), tri(0, 1, 3), tri(0, 1, 2), quad(0, 1, 2, 3),
    quad(0, 2, 1, 3), quad(0, 1, 3, 2) });
}

class ThickVertex : public ::testing::TestWithParam<bool>
{
};

TEST_P(ThickVertex, ThicknessAndScalarsAreTheExactRaySegment)
{
  const View view = GetParam() ? PerspectiveView() : OrthographicView();
  const mtpt::Matrix4 mvp = mtpt::Multiply(view.projection, view.modelView);
  const mtpt::Matrix4 unproject = Inverse(mvp);
  std::mt19937_64 random(99);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  const Vec3 gradient{ 0.7, -1.3, 2.1 };
  int checked = 0, quadrilaterals = 0;
  double worstRelative = 0;
  for (int t = 0; t < 20000; ++t)
  {
    Vec3 p[4];
    for (auto& q : p)
    {
      q = { coordinate(random), coordinate(random), coordinate(random) };
    }
    // Well-shaped tetrahedra only: the test is about exactness, the degenerate ones have
    // their own tests. Quality 6*sqrt(2)*V / max edge^3 is 1 for a regular tetrahedron.
    const double volume =
      std::fabs(Dot(Sub(p[1], p[0]), Cross(Sub(p[2], p[0]), Sub(p[3], p[0])))) / 6;
    double maxEdge = 0;
    for (int i = 0; i < 4; ++i)
    {
      for (int j = i + 1; j < 4; ++j)
      {
        maxEdge = std::max(maxEdge, std::sqrt(Dot(Sub(p[i], p[j]), Sub(p[i], p[j]))));
      }
    }
    if (6 * std::sqrt(2.0) * volume < 0.05 * maxEdge * maxEdge * maxEdge)
    {
      continue;
    }
    float coords[12];
    float scalars[4];
    for (int i = 0; i < 4; ++i)
    {
      for (int k = 0; k < 3; ++k)
      {
        coords[3 * i + k] = static_cast<float>(p[i][k]);
        p[i][k] = coords[3 * i + k]; // the test uses exactly the float points
      }
      scalars[i] = static_cast<float>(Dot(gradient, p[i]) + 0.5);
    }
    mtpt::ProjectedPoint ndc[4];
    mtpt::ProjectPoints(mtpt::PointsView::FromFloat(coords, 4),
      { scalars, mtpt::ScalarsView::Association::Points }, view.modelView, view.projection, ndc, 1);
    const mtpt::ProjectedPoint* corners[4] = { &ndc[0], &ndc[1], &ndc[2], &ndc[3] };
    TetVertex vertices[5];
    std::uint32_t indices[12];
    const mtpt::Projection projection =
      mtpt::DecomposeTetrahedron(corners, scalars, vertices, indices);
    ASSERT_NE(projection.kind, ProjectionClass::NotDrawable);
    quadrilaterals += projection.kind == ProjectionClass::Quadrilateral;
    const TetVertex& thick = projection.kind == ProjectionClass::Quadrilateral
      ? vertices[4]
      : vertices[projection.vertex[3]];

    // Ground truth: the ray through the thick vertex, unprojected in double. Its screen
    // position is the crossing of the projected edges or the inner vertex; the record
    // holds it rounded to float.
    double thickX = 0, thickY = 0;
    if (projection.kind == ProjectionClass::Quadrilateral)
    {
      const int a = projection.vertex[0], b = projection.vertex[1];
      thickX = ndc[a].x + projection.alpha * (ndc[b].x - ndc[a].x);
      thickY = ndc[a].y + projection.alpha * (ndc[b].y - ndc[a].y);
    }
    else
    {
      thickX = ndc[projection.vertex[3]].x;
      thickY = ndc[projection.vertex[3]].y;
    }
    ASSERT_NEAR(thick.x, thickX, 1e-6);
    ASSERT_NEAR(thick.y, thickY, 1e-6);
    const Vec3 nearPoint = Apply(unproject, { thickX, thickY, -1.0 });
    const Vec3 farPoint = Apply(unproject, { thickX, thickY, 1.0 });
    const Vec3 direction = Sub(farPoint, nearPoint);
    double tEnter = 0, tExit = 0;
    ASSERT_GT(ChordLength(p, nearPoint, direction, &tEnter, &tExit), 0.0);
    const Vec3 enter{ nearPoint[0] + tEnter * direction[0], nearPoint[1] + tEnter * direction[1],
      nearPoint[2] + tEnter * direction[2] };
    const Vec3 exit{ nearPoint[0] + tExit * direction[0], nearPoint[1] + tExit * direction[1],
      nearPoint[2] + tExit * direction[2] };
    const Vec3 eyeEnter = Apply(view.modelView, enter);
    const Vec3 eyeExit = Apply(view.modelView, exit);
    const Vec3 eyeSegment = Sub(eyeExit, eyeEnter);
    const double exact = std::sqrt(Dot(eyeSegment, eyeSegment));
    const double relative = std::fabs(thick.thickness - exact) / exact;
    worstRelative = std::max(worstRelative, relative);
    ASSERT_LT(relative, 1e-5) << "tetrahedron " << t << " class "
                              << static_cast<int>(projection.kind);
    // Entry is the front (nearer) point; scalars are the linear field there.
    ASSERT_NEAR(thick.scalarFront, Dot(gradient, enter) + 0.5, 1e-4);
    ASSERT_NEAR(thick.scalarBack, Dot(gradient, exit) + 0.5, 1e-4);
    ASSERT_NEAR(thick.z, Apply(mvp, enter)[2], 1e-5);
    // Every other record is a silhouette vertex: zero thickness, front == back.
    for (int i = 0; i < 5; ++i)
    {
      if (&vertices[i] != &thick && !(i == 4 && projection.kind != ProjectionClass::Quadrilateral))
      {
        EXPECT_EQ(vertices[i].thickness, 0.0f);
        EXPECT_EQ(vertices[i].scalarFront, vertices[i].scalarBack);
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 5000);
  EXPECT_GT(quadrilaterals, checked / 3);
  RecordProperty("worst_relative_thickness_error", std::to_string(worstRelative));
}

INSTANTIATE_TEST_SUITE_P(Projections, ThickVertex, ::testing::Values(false, true),
  [](const auto& info) { return info.param ? "Perspective" : "Orthographic"; });

TEST(Decompose, TrianglesCoverTheProjectionExactlyOnce)
{
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  const View view = OrthographicView();
  for (int t = 0; t < 50000; ++t)
  {
    float coords[12];
    const float scalars[4] = { 0, 1, 2, 3 };
    for (float& value : coords)
    {
      value = static_cast<float>(coordinate(random));
    }
    mtpt::ProjectedPoint ndc[4];
    mtpt::ProjectPoints(
      mtpt::PointsView::FromFloat(coords, 4), {}, view.modelView, view.projection, ndc, 1);
    const mtpt::ProjectedPoint* corners[4] = { &ndc[0], &ndc[1], &ndc[2], &ndc[3] };
    TetVertex v[5];
    std::uint32_t idx[12];
    const auto projection = mtpt::DecomposeTetrahedron(corners, scalars, v, idx);
    if (projection.kind == ProjectionClass::NotDrawable)
    {
      continue;
    }
    double covered = 0;
    for (int tri = 0; tri < 4; ++tri)
    {
      ASSERT_LT(idx[3 * tri], 5u);
      covered += TriangleArea(v[idx[3 * tri]], v[idx[3 * tri + 1]], v[idx[3 * tri + 2]]);
    }
    const double x[4] = { ndc[0].x, ndc[1].x, ndc[2].x, ndc[3].x };
    const double y[4] = { ndc[0].y, ndc[1].y, ndc[2].y, ndc[3].y };
    const double hull = HullArea(x, y);
    ASSERT_NEAR(covered, hull, 1e-5 * std::max(hull, 1e-3)) << "tetrahedron " << t;
  }
}

TEST(Decompose, BuffersAreBitIdenticalForEveryThreadCountAndOrderMethod)
{
  const TetMesh mesh = JitteredGrid(14, 11); // 16464 tetrahedra
  for (const View& view : { OrthographicView(), PerspectiveView() })
  {
    mtpt::FrameInput input;
    input.points = mesh.Points();
    input.cells = mesh.Cells();
    input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    input.modelView = view.modelView;
    input.projection = view.projection;
    input.perspective = view.perspective;
    mtpt::FramePipeline reference;
    reference.SetOrderMethod(mtpt::OrderMethod::PartitionSort, 1000);
    ASSERT_TRUE(reference.Run(input, 1));
    // Every cell is sorted unless the frustum culls it (the views crop a few corners).
    const mtpt::FrameStats& stats = reference.Stats();
    ASSERT_EQ(reference.TetrahedronCount(), reference.SortedCount());
    ASSERT_EQ(stats.sorted + stats.frustumCulled, mesh.CellCount());
    ASSERT_LT(stats.frustumCulled, mesh.CellCount() / 100);
    for (auto method : { mtpt::OrderMethod::PartitionSort, mtpt::OrderMethod::RadixSort })
    {
      for (int threads : { 1, 2, 3, 8 })
      {
        SCOPED_TRACE(::testing::Message() << mtpt::ToString(method) << " threads=" << threads);
        mtpt::FramePipeline pipeline;
        pipeline.SetOrderMethod(method);
        ASSERT_TRUE(pipeline.Run(input, threads));
        ASSERT_EQ(pipeline.Keys(), reference.Keys());
        ASSERT_EQ(0,
          std::memcmp(pipeline.Vertices().data(), reference.Vertices().data(),
            reference.Vertices().size() * sizeof(TetVertex)));
        ASSERT_EQ(pipeline.Indices(), reference.Indices());
      }
    }
    // Back to front: each slot's key depth never increases along the order.
    const auto& keys = reference.Keys();
    EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  }
}

TEST(Decompose, GatherAndRankEntryPointsAgreeOnFullAndPartialOrders)
{
  const TetMesh mesh = JitteredGrid(8, 4); // 3072 tetrahedra
  const View view = PerspectiveView();
  const std::size_t n = mesh.CellCount(), points = mesh.points.size() / 3;
  std::vector<mtpt::ProjectedPoint> projected(points);
  mtpt::ProjectPoints(mesh.Points(), {}, view.modelView, view.projection, projected.data(), 2);
  std::vector<mtpt::SortKey> order(n);
  mtpt::ComputeDepthKeys(projected.data(), points, mesh.Cells(), true, order.data(), 2);
  mtpt::MakeVisibilityOrder(mtpt::OrderMethod::RadixSort)->Sort(order.data(), n, 2);
  mtpt::DecomposeInput input;
  input.points = projected.data();
  input.pointCount = points;
  input.cells = mesh.Cells();
  // Cell scalars this time, so that path is covered too.
  std::vector<float> cellScalars(n);
  for (std::size_t c = 0; c < n; ++c)
  {
    cellScalars[c] = 0.001f * static_cast<float>(c);
  }
  input.scalars = { cellScalars.data(), mtpt::ScalarsView::Association::Cells };
  // A full order, and a partial one (every third cell dropped, as culling will).
  std::vector<mtpt::SortKey> partial;
  for (std::size_t k = 0; k < n; ++k)
  {
    if (mtpt::CellOfKey(order[k]) % 3 != 0)
    {
      partial.push_back(order[k]);
    }
  }
  for (const auto* keys : { &order, &partial })
  {
    const std::size_t count = keys->size();
    std::vector<TetVertex> gatherVertices(5 * count), rankVertices(5 * count);
    std::vector<std::uint32_t> gatherIndices(12 * count), rankIndices(12 * count, 7u);
    std::vector<ProjectionClass> gatherClasses(count), rankClasses(count);
    mtpt::DecomposeTetrahedra(input, keys->data(), count, gatherVertices.data(),
      gatherIndices.data(), gatherClasses.data(), 3);
    std::vector<std::uint32_t> rank(n);
    mtpt::InvertOrder(keys->data(), count, n, rank.data(), 2);
    for (std::size_t k = 0; k < count; ++k)
    {
      ASSERT_EQ(rank[mtpt::CellOfKey((*keys)[k])], k);
    }
    mtpt::DecomposeTetrahedraByRank(
      input, rank.data(), 0, count, rankVertices.data(), rankIndices.data(), rankClasses.data(), 3);
    ASSERT_EQ(
      0, std::memcmp(gatherVertices.data(), rankVertices.data(), count * 5 * sizeof(TetVertex)));
    ASSERT_EQ(gatherIndices, rankIndices);
    ASSERT_EQ(gatherClasses, rankClasses);
    // Cell scalars: every record of slot k carries the scalar of its cell.
    for (std::size_t k = 0; k < count; ++k)
    {
      if (gatherClasses[k] != ProjectionClass::NotDrawable)
      {
        ASSERT_EQ(gatherVertices[5 * k].scalarFront, cellScalars[mtpt::CellOfKey((*keys)[k])]);
        ASSERT_EQ(gatherVertices[5 * k + 4].scalarBack, cellScalars[mtpt::CellOfKey((*keys)[k])]);
      }
    }
  }
}

/// Records as text, every float to the last bit.
std::string Describe(const TetVertex* records, int count)
{
  std::ostringstream text;
  text.precision(9);
  for (int i = 0; i < count; ++i)
  {
    const TetVertex& r = records[i];
    text << "(" << r.x << " " << r.y << " " << r.z << " " << r.scalarFront << " " << r.scalarBack
         << " " << r.thickness << ") ";
  }
  return text.str();
}

/// The batched decomposition's tests, run with each instruction set in turn.
class DecomposeSimd : public ::testing::TestWithParam<std::int64_t>
{
protected:
  void SetUp() override { hwy::SetSupportedTargetsForTest(this->GetParam()); }
  void TearDown() override { hwy::SetSupportedTargetsForTest(0); }
};

// The by-rank decompositions (batched, one tetrahedron per SIMD lane) against the scalar
// decomposition of one tetrahedron, slot by slot and fan by fan, byte for byte.
TEST_P(DecomposeSimd, BatchedDecompositionIsTheScalarOneBitForBit)
{
  ASSERT_STREQ(mtpt::detail::DecomposeTargetName(), hwy::TargetName(this->GetParam()));
  const TetMesh mesh = LatticeTetrahedra(4000, 7);
  const std::size_t n = mesh.CellCount(), points = mesh.points.size() / 3;
  std::vector<float> cellScalars(n);
  for (std::size_t c = 0; c < n; ++c)
  {
    cellScalars[c] = c % 97 == 0 ? INFINITY : 0.01f * static_cast<float>(c % 101);
  }
  const View axisAligned{ LookAt({ 0, 0, 6 }, { 0, 0, 0 }, { 0, 1, 0 }),
    Ortho(-2, 2, -2, 2, 0.5, 12), false };
  std::map<ProjectionClass, int> seen;
  for (const View& view : { axisAligned, PerspectiveView() })
  {
    for (const bool perCell : { false, true })
    {
      for (const int viewport : { 0, 23 })
      {
        SCOPED_TRACE(::testing::Message() << "perspective " << view.perspective << ", cell scalars "
                                          << perCell << ", viewport " << viewport);
        const mtpt::ScalarsView scalars = perCell
          ? mtpt::ScalarsView{ cellScalars.data(), mtpt::ScalarsView::Association::Cells }
          : mtpt::ScalarsView{ mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
        std::vector<mtpt::ProjectedPoint> projected(points);
        mtpt::ProjectPoints(mesh.Points(), perCell ? mtpt::ScalarsView{} : scalars, view.modelView,
          view.projection, projected.data(), 2);
        mtpt::DecomposeInput input;
        input.points = projected.data();
        input.pointCount = points;
        input.cells = mesh.Cells();
        input.scalars = scalars;
        input.imageSize = { viewport, viewport };
        // A rank per cell, shuffled; a window of them, not a multiple of any batch.
        std::vector<std::uint32_t> rank(n);
        for (std::size_t c = 0; c < n; ++c)
        {
          rank[c] = static_cast<std::uint32_t>(c);
        }
        std::shuffle(rank.begin(), rank.end(), std::mt19937(11));
        const std::size_t first = 101, count = n - 333;
        // A cell not in the order (culled before the sort): one whose rank is before the window.
        *std::find(rank.begin(), rank.end(), 7u) = mtpt::NotInOrder;
        std::vector<TetVertex> expectedVertices(5 * count), vertices(5 * count);
        std::vector<std::uint32_t> expectedIndices(12 * count), indices(12 * count);
        std::vector<mtpt::Fan> expectedFans(count), fans(count);
        std::vector<ProjectionClass> expectedClasses(count), slotClasses(count), fanClasses(count);
        for (std::size_t c = 0; c < n; ++c)
        {
          const std::size_t k = rank[c] - first;
          if (rank[c] == mtpt::NotInOrder || rank[c] < first || k >= count)
          {
            continue;
          }
          const auto* ids = &mesh.connectivity[4 * c];
          const mtpt::ProjectedPoint* corners[4];
          float cornerScalars[4];
          for (int i = 0; i < 4; ++i)
          {
            corners[i] = &projected[static_cast<std::size_t>(ids[i])];
            cornerScalars[i] = perCell ? cellScalars[c] : corners[i]->scalar;
          }
          expectedClasses[k] = mtpt::DecomposeIntoSlot(
            input, corners, cornerScalars, k, expectedVertices.data(), expectedIndices.data());
          ASSERT_EQ(mtpt::DecomposeIntoFan(input, corners, cornerScalars, expectedFans[k]),
            expectedClasses[k]);
          ++seen[expectedClasses[k]];
        }
        for (const int threads : { 1, 2, 3 })
        {
          SCOPED_TRACE(::testing::Message() << threads << " threads");
          std::fill(vertices.begin(), vertices.end(), TetVertex{ NAN, NAN, NAN, NAN, NAN, NAN });
          std::fill(indices.begin(), indices.end(), 0xffffffffu);
          std::memset(fans.data(), 0xff, fans.size() * sizeof(mtpt::Fan));
          mtpt::DecomposeTetrahedraByRank(input, rank.data(), first, count, vertices.data(),
            indices.data(), slotClasses.data(), threads);
          mtpt::DecomposeFansByRank(
            input, rank.data(), first, count, fans.data(), fanClasses.data(), threads);
          ASSERT_EQ(slotClasses, expectedClasses);
          ASSERT_EQ(fanClasses, expectedClasses);
          for (std::size_t k = 0; k < count; ++k)
          {
            ASSERT_EQ(
              0, std::memcmp(&vertices[5 * k], &expectedVertices[5 * k], 5 * sizeof(TetVertex)))
              << "slot " << k << " of class " << static_cast<int>(expectedClasses[k]) << ": "
              << Describe(&vertices[5 * k], 5) << " instead of "
              << Describe(&expectedVertices[5 * k], 5);
            ASSERT_EQ(0, std::memcmp(&fans[k], &expectedFans[k], sizeof(mtpt::Fan)))
              << "fan " << k << ": " << Describe(&fans[k].centre, 5) << " instead of "
              << Describe(&expectedFans[k].centre, 5);
          }
          ASSERT_EQ(indices, expectedIndices);
        }
      }
    }
  }
  // Every class occurred, the degenerate ones included.
  for (const ProjectionClass kind : { ProjectionClass::Triangle, ProjectionClass::Quadrilateral,
         ProjectionClass::VertexOnEdge, ProjectionClass::CoincidentVertices,
         ProjectionClass::NotDrawable, ProjectionClass::CoversNoPixel })
  {
    EXPECT_GT(seen[kind], 20) << static_cast<int>(kind);
  }
}

INSTANTIATE_TEST_SUITE_P(InstructionSets, DecomposeSimd,
  ::testing::ValuesIn(hwy::SupportedAndGeneratedTargets()),
  [](const ::testing::TestParamInfo<std::int64_t>& info)
  { return std::string(hwy::TargetName(info.param)); });

TEST(Decompose, DegenerateInputGivesFiniteBuffersAndValidIndices)
{
  TetMesh mesh;
  auto addPoint = [&mesh](double x, double y, double z)
  {
    mesh.points.insert(mesh.points.end(), { float(x), float(y), float(z) });
    mesh.scalars.push_back(float(x + y + z));
    return static_cast<std::int64_t>(mesh.points.size() / 3 - 1);
  };
  std::vector<ProjectionClass> expected;
  auto tet = [&](std::int64_t a, std::int64_t b, std::int64_t c, std::int64_t d, ProjectionClass k)
  {
    mesh.AddTetrahedron(a, b, c, d);
    expected.push_back(k);
  };
  const auto nan = std::numeric_limits<double>::quiet_NaN();
  const auto inf = std::numeric_limits<double>::infinity();
  const auto o = addPoint(0, 0, 0), x = addPoint(1, 0, 0), y = addPoint(0, 1, 0),
             z = addPoint(0, 0, 1), xy = addPoint(0.3, 0.3, 0);
  const auto onAxis = addPoint(0, 0, -1); // behind o on the central ray: projects onto o
  const auto sliver = addPoint(0.5, 0.5, 1e-9);
  const auto bad = addPoint(nan, 0, 0), infinite = addPoint(inf, 1, 0);
  const auto behindEye = addPoint(0.1, 0.1, 10);
  const auto huge = addPoint(1e30, -1e30, 1e30);
  const auto nanScalar = addPoint(0.2, 0.8, 0.1);
  mesh.scalars[nanScalar] = std::nanf("");
  const auto q = ProjectionClass::Quadrilateral; // placeholder for "any drawable class"
  tet(o, x, y, z, q);                            // regular
  tet(o, x, y, xy, ProjectionClass::Triangle);   // zero volume, flat
  tet(o, o, o, o, ProjectionClass::NotDrawable); // one point
  tet(o, onAxis, z, addPoint(0, 0, 2), ProjectionClass::NotDrawable); // collinear on the axis
  tet(o, x, y, bad, ProjectionClass::NotDrawable);                    // NaN point
  tet(o, x, y, infinite, ProjectionClass::NotDrawable);               // infinite point
  tet(o, x, y, 1000, ProjectionClass::NotDrawable);                   // id out of range
  tet(o, x, y, -3, ProjectionClass::NotDrawable);                     // negative id
  tet(o, x, y, behindEye, ProjectionClass::NotDrawable);              // behind the eye
  tet(x, y, xy, sliver, q);                                           // sliver
  tet(o, x, y, nanScalar, ProjectionClass::NotDrawable);              // NaN scalar
  tet(o, x, y, huge, ProjectionClass::NotDrawable);                   // overflows NDC
  tet(x, y, o, onAxis, ProjectionClass::CoincidentVertices);          // o and onAxis coincide
  mesh.connectivity.insert(mesh.connectivity.end(), { o, x, y });     // a triangle: not a tet
  mesh.offsets.push_back(static_cast<std::int64_t>(mesh.connectivity.size()));
  expected.push_back(ProjectionClass::NotDrawable);

  const std::size_t n = mesh.CellCount();
  std::vector<mtpt::SortKey> order(n);
  for (std::size_t c = 0; c < n; ++c)
  {
    order[c] = mtpt::MakeSortKey(0.0f, static_cast<std::uint32_t>(c));
  }
  const mtpt::Matrix4 mv = LookAt({ 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 });
  const mtpt::Matrix4 proj = Perspective(60, 1, 0.1, 100);
  const mtpt::ScalarsView pointScalars{ mesh.scalars.data(),
    mtpt::ScalarsView::Association::Points };
  std::vector<mtpt::ProjectedPoint> projected(mesh.points.size() / 3);
  mtpt::ProjectPoints(mesh.Points(), pointScalars, mv, proj, projected.data(), 2);
  mtpt::DecomposeInput input;
  input.points = projected.data();
  input.pointCount = projected.size();
  input.cells = mesh.Cells();
  input.scalars = pointScalars;
  // Stale garbage in the buffers must be overwritten everywhere.
  std::vector<TetVertex> vertices(5 * n, TetVertex{ NAN, NAN, NAN, NAN, NAN, NAN });
  std::vector<std::uint32_t> indices(12 * n, 0xffffffffu);
  std::vector<ProjectionClass> classes(n, ProjectionClass::Triangle);
  mtpt::DecomposeTetrahedra(
    input, order.data(), n, vertices.data(), indices.data(), classes.data(), 2);

  for (std::size_t k = 0; k < n; ++k)
  {
    SCOPED_TRACE(::testing::Message() << "cell " << k);
    if (expected[k] == q)
    {
      EXPECT_NE(classes[k], ProjectionClass::NotDrawable);
    }
    else
    {
      EXPECT_EQ(classes[k], expected[k]);
    }
    for (std::size_t v = 5 * k; v < 5 * k + 5; ++v)
    {
      const TetVertex& r = vertices[v];
      for (float f : { r.x, r.y, r.z, r.scalarFront, r.scalarBack, r.thickness })
      {
        ASSERT_TRUE(std::isfinite(f));
      }
      EXPECT_GE(r.thickness, 0.0f);
      if (classes[k] == ProjectionClass::NotDrawable)
      {
        EXPECT_EQ(r.x, 0.0f);
        EXPECT_EQ(r.thickness, 0.0f);
      }
    }
    for (std::size_t i = 12 * k; i < 12 * k + 12; ++i)
    {
      ASSERT_GE(indices[i], 5 * k);
      ASSERT_LT(indices[i], 5 * k + 5);
      if (classes[k] == ProjectionClass::NotDrawable)
      {
        EXPECT_EQ(indices[i], 5 * k);
      }
    }
  }
  // The flat tetrahedron has a thick vertex of zero length; the coincident pair o/onAxis
  // has a thick vertex whose length is their eye-space distance, 1.
  const auto thicknessOf = [&](std::size_t k)
  {
    float t = 0;
    for (std::size_t v = 5 * k; v < 5 * k + 5; ++v)
    {
      t = std::max(t, vertices[v].thickness);
    }
    return t;
  };
  EXPECT_LT(thicknessOf(1), 1e-12f);
  EXPECT_NEAR(thicknessOf(12), 1.0f, 1e-6);
}

TEST(VertexColours, StoredAsSixteenBitsClampedToTheUnitRange)
{
  const float in[][4] = { { 0.0f, 1.0f, 0.5f, 0.25f }, { -1.0f, 2.0f, NAN, 1e-6f },
    { 0.123456f, 0.999999f, 1.0f / 65535.0f, 0.5f / 65535.0f } };
  for (const auto& rgba : in)
  {
    TetVertex v{ 0.25f, -0.5f, 0.75f, 0, 0, 2.0f };
    mtpt::StoreVertexColour(v, rgba);
    float out[4];
    mtpt::LoadVertexColour(v, out);
    for (int c = 0; c < 4; ++c)
    {
      const float expected = std::isnan(rgba[c]) ? 0.0f : std::min(1.0f, std::max(0.0f, rgba[c]));
      EXPECT_NEAR(out[c], expected, 0.5 / 65535 + 1e-7) << c;
    }
    EXPECT_EQ(v.x, 0.25f); // the other fields are untouched
    EXPECT_EQ(v.thickness, 2.0f);
  }
}

TEST(VertexColours, CornersKeepTheirColourAndTheThickVertexMeansItsSegment)
{
  // Colours are linear inside a tetrahedron, as scalars are: decomposing with a channel as
  // the scalar gives its value at the front and the back of the thick vertex's segment, and
  // the coloured records must hold the corners' colours and, at the thick vertex, the mean
  // of those two (VTK's PT's vertex classification).
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0), unit(0.0, 1.0);
  const View view = PerspectiveView();
  int checked = 0;
  for (int t = 0; t < 3000; ++t)
  {
    float coords[12], rgba[4][4];
    for (int i = 0; i < 4; ++i)
    {
      for (int k = 0; k < 3; ++k)
      {
        coords[3 * i + k] = static_cast<float>(coordinate(random));
      }
      for (float& c : rgba[i])
      {
        c = static_cast<float>(unit(random));
      }
    }
    const float attenuation[4] = { rgba[0][3], rgba[1][3], rgba[2][3], rgba[3][3] };
    mtpt::ProjectedPoint ndc[4];
    mtpt::ProjectPoints(mtpt::PointsView::FromFloat(coords, 4),
      { attenuation, mtpt::ScalarsView::Association::Points }, view.modelView, view.projection, ndc,
      1);
    const mtpt::ProjectedPoint* corners[4] = { &ndc[0], &ndc[1], &ndc[2], &ndc[3] };
    const float* colours[4] = { rgba[0], rgba[1], rgba[2], rgba[3] };
    TetVertex coloured[5];
    std::uint32_t indices[12];
    mtpt::Fan fan;
    const auto projection =
      mtpt::DecomposeTetrahedron(corners, attenuation, coloured, indices, colours);
    mtpt::DecomposeTetrahedronToFan(corners, attenuation, fan, colours);
    if (projection.kind == ProjectionClass::NotDrawable)
    {
      continue;
    }
    ++checked;
    const int thick = projection.kind == ProjectionClass::Quadrilateral ? 4 : projection.vertex[3];
    for (int c = 0; c < 4; ++c)
    {
      const float channel[4] = { rgba[0][c], rgba[1][c], rgba[2][c], rgba[3][c] };
      TetVertex plain[5];
      std::uint32_t plainIndices[12];
      mtpt::DecomposeTetrahedron(corners, channel, plain, plainIndices);
      for (int v = 0; v < 5; ++v)
      {
        float got[4];
        mtpt::LoadVertexColour(coloured[v], got);
        const double expected = v == thick
          ? 0.5 * (static_cast<double>(plain[v].scalarFront) + plain[v].scalarBack)
          : (v < 4 ? channel[v] : got[c]); // an unused vertex 4 copies the thick one
        ASSERT_NEAR(got[c], expected, 0.5 / 65535 + 1e-6) << "tetrahedron " << t << " vertex " << v;
        ASSERT_EQ(coloured[v].thickness, plain[v].thickness);
        ASSERT_EQ(coloured[v].x, plain[v].x);
      }
      // The fan holds the same records.
      float centre[4], slot[4];
      mtpt::LoadVertexColour(fan.centre, centre);
      mtpt::LoadVertexColour(coloured[thick], slot);
      ASSERT_EQ(centre[c], slot[c]);
    }
  }
  EXPECT_GT(checked, 2500);
}

TEST(VertexColours, NearPlanePiecesInterpolateColoursAsScalars)
{
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
  const mtpt::Matrix4 projection = Perspective(60, 1.0, 0.5, 10);
  const mtpt::NearPlane plane(projection);
  int pieces = 0;
  for (int trial = 0; trial < 500; ++trial)
  {
    mtpt::ProjectedPoint records[4];
    const mtpt::ProjectedPoint* corners[4];
    float rgba[4][4];
    const float* colours[4];
    float zero[4] = { 0, 0, 0, 0 };
    for (int i = 0; i < 4; ++i)
    {
      records[i] = mtpt::ProjectedPoint{};
      records[i].eyeX = u(random);
      records[i].eyeY = u(random);
      records[i].eyeZ = -0.5 + 0.6 * u(random); // around the near plane at z = -0.5
      records[i].usable = 1;
      corners[i] = &records[i];
      for (float& c : rgba[i])
      {
        c = static_cast<float>(unit(random));
      }
      colours[i] = rgba[i];
    }
    std::vector<mtpt::NearPiece> coloured;
    mtpt::CutTetrahedron(corners, zero, plane, projection, coloured, colours);
    pieces += static_cast<int>(coloured.size());
    for (int c = 0; c < 4; ++c)
    {
      const float channel[4] = { rgba[0][c], rgba[1][c], rgba[2][c], rgba[3][c] };
      std::vector<mtpt::NearPiece> plain;
      mtpt::CutTetrahedron(corners, channel, plane, projection, plain);
      ASSERT_EQ(plain.size(), coloured.size());
      for (std::size_t j = 0; j < plain.size(); ++j)
      {
        for (int i = 0; i < 4; ++i)
        {
          ASSERT_EQ(coloured[j].colours[i][c], plain[j].scalars[i]) << trial;
        }
      }
    }
  }
  EXPECT_GT(pieces, 100);
}

TEST(VertexColours, PipelineBuffersAreBitIdenticalForEveryThreadCount)
{
  const TetMesh mesh = JitteredGrid(12, 5);
  std::vector<float> rgba(4 * mesh.points.size() / 3), attenuation(mesh.points.size() / 3);
  for (std::size_t p = 0; p < attenuation.size(); ++p)
  {
    for (int c = 0; c < 4; ++c)
    {
      rgba[4 * p + c] = 0.5f + 0.5f * std::sin(static_cast<float>(p * (c + 3)));
    }
    // Transparent on one side: whole cells there are culled.
    attenuation[p] = mesh.points[3 * p] < 0.4f ? 0.0f : rgba[4 * p + 3];
    rgba[4 * p + 3] = attenuation[p];
  }
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = { attenuation.data(), mtpt::ScalarsView::Association::Points };
  input.colours = rgba.data();
  const View view = PerspectiveView();
  input.modelView = view.modelView;
  input.projection = view.projection;
  input.perspective = true;
  mtpt::FramePipeline reference;
  ASSERT_TRUE(reference.Run(input, 1));
  reference.DecomposeFans(0, reference.SortedCount(), 1);
  for (int threads : { 2, 3, 8 })
  {
    mtpt::FramePipeline pipeline;
    ASSERT_TRUE(pipeline.Run(input, threads));
    pipeline.DecomposeFans(0, pipeline.SortedCount(), threads);
    ASSERT_EQ(pipeline.Keys(), reference.Keys());
    ASSERT_EQ(0,
      std::memcmp(pipeline.Vertices().data(), reference.Vertices().data(),
        reference.Vertices().size() * sizeof(TetVertex)));
    ASSERT_EQ(0,
      std::memcmp(
        pipeline.Fans().data(), reference.Fans().data(), reference.FanCount() * sizeof(mtpt::Fan)));
  }
  // Culled: exactly the cells whose four attenuations are 0 (no table is given).
  std::size_t transparent = 0;
  for (std::size_t c = 0; c < mesh.CellCount(); ++c)
  {
    bool zero = true;
    for (int k = 0; k < 4; ++k)
    {
      zero = zero && attenuation[mesh.connectivity[4 * c + k]] == 0.0f;
    }
    transparent += zero ? 1 : 0;
  }
  EXPECT_GT(transparent, 0u);
  EXPECT_EQ(reference.Stats().opacityCulled, transparent);
}

TEST(FramePipeline, RejectsMeshesBeyondThirtyTwoBitIndices)
{
  EXPECT_EQ(mtpt::FramePipeline::MaxTetrahedra(), 0xffffffffu / 5);
  mtpt::FrameInput input;
  input.cells.cellCount = mtpt::FramePipeline::MaxTetrahedra() + 1; // never dereferenced
  mtpt::FramePipeline pipeline;
  EXPECT_FALSE(pipeline.Run(input, 1));
  EXPECT_EQ(pipeline.TetrahedronCount(), 0u);
}

} // namespace
