// SPDX-License-Identifier: BSD-3-Clause
// ClassifyProjection against an independent brute-force geometric test on random
// tetrahedra, plus the crafted class 3 and 4 limits.
#include "mtpt/Decompose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace
{

using mtpt::ClassifyProjection;
using mtpt::Projection;
using mtpt::ProjectionClass;

using Real = long double;

Real Orient(const double x[4], const double y[4], int a, int b, int c)
{
  return (Real(x[b]) - x[a]) * (Real(y[c]) - y[a]) - (Real(y[b]) - y[a]) * (Real(x[c]) - x[a]);
}

/// Brute force: which vertex lies strictly inside the triangle of the other three, and
/// which pair of opposite edges crosses properly. Returns false if the configuration is
/// too close to a limit to call (some orientation within `relative` of zero).
struct BruteForce
{
  int insideVertex = -1;
  std::pair<int, int> crossing[2] = { { -1, -1 }, { -1, -1 } };
  bool clearCut = true;
};

BruteForce Classify(const double x[4], const double y[4], double relative)
{
  BruteForce result;
  Real scale = 0;
  for (int i = 0; i < 4; ++i)
  {
    for (int j = 0; j < 4; ++j)
    {
      scale = std::max(scale, std::fabs(Real(x[i]) - x[j]) + std::fabs(Real(y[i]) - y[j]));
    }
  }
  auto sign = [&](int a, int b, int c)
  {
    const Real o = Orient(x, y, a, b, c);
    if (std::fabs(o) <= relative * scale * scale)
    {
      result.clearCut = false;
    }
    return o > 0 ? 1 : (o < 0 ? -1 : 0);
  };
  for (int i = 0; i < 4; ++i)
  {
    int others[3], n = 0;
    for (int j = 0; j < 4; ++j)
    {
      if (j != i)
      {
        others[n++] = j;
      }
    }
    const int s0 = sign(others[0], others[1], i);
    const int s1 = sign(others[1], others[2], i);
    const int s2 = sign(others[2], others[0], i);
    if (s0 != 0 && s0 == s1 && s1 == s2)
    {
      result.insideVertex = i;
    }
  }
  const int pairs[3][4] = { { 0, 1, 2, 3 }, { 0, 2, 1, 3 }, { 0, 3, 1, 2 } };
  for (const auto& p : pairs)
  {
    const bool abSeparatesCd = sign(p[0], p[1], p[2]) * sign(p[0], p[1], p[3]) < 0;
    const bool cdSeparatesAb = sign(p[2], p[3], p[0]) * sign(p[2], p[3], p[1]) < 0;
    if (abSeparatesCd && cdSeparatesAb)
    {
      result.crossing[0] = { p[0], p[1] };
      result.crossing[1] = { p[2], p[3] };
    }
  }
  return result;
}

std::set<int> Pair(int a, int b)
{
  return { a, b };
}

TEST(Classification, MatchesBruteForceOnRandomTetrahedra)
{
  std::mt19937_64 random(20210001);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  const int count = 200000;
  int skipped = 0, triangles = 0, quadrilaterals = 0;
  for (int t = 0; t < count; ++t)
  {
    double x[4], y[4];
    for (int i = 0; i < 4; ++i)
    {
      x[i] = coordinate(random);
      y[i] = coordinate(random);
    }
    const BruteForce expected = Classify(x, y, 1e-6);
    if (!expected.clearCut)
    {
      ++skipped;
      continue;
    }
    const Projection p = ClassifyProjection(x, y);
    if (expected.insideVertex >= 0)
    {
      ++triangles;
      ASSERT_EQ(p.kind, ProjectionClass::Triangle) << "tetrahedron " << t;
      ASSERT_EQ(p.vertex[3], expected.insideVertex);
      // The weights reproduce the inner vertex from the outer triangle.
      double px = 0, py = 0, sum = 0;
      for (int k = 0; k < 3; ++k)
      {
        ASSERT_GE(p.weights[k], 0.0);
        px += p.weights[k] * x[p.vertex[k]];
        py += p.weights[k] * y[p.vertex[k]];
        sum += p.weights[k];
      }
      ASSERT_NEAR(sum, 1.0, 1e-12);
      ASSERT_NEAR(px, x[expected.insideVertex], 1e-9);
      ASSERT_NEAR(py, y[expected.insideVertex], 1e-9);
    }
    else
    {
      ++quadrilaterals;
      ASSERT_GE(expected.crossing[0].first, 0) << "neither class 1 nor class 2 at " << t;
      ASSERT_EQ(p.kind, ProjectionClass::Quadrilateral) << "tetrahedron " << t;
      const std::set<std::set<int>> expectedPairs = { Pair(expected.crossing[0].first,
                                                        expected.crossing[0].second),
        Pair(expected.crossing[1].first, expected.crossing[1].second) };
      const std::set<std::set<int>> gotPairs = { Pair(p.vertex[0], p.vertex[1]),
        Pair(p.vertex[2], p.vertex[3]) };
      ASSERT_EQ(gotPairs, expectedPairs);
      // The paper's formulation: P1 + alpha*A = P3 + beta*B with A = P2-P1, B = P4-P3,
      // C = P3-P1, solved by Cramer's rule, must give the same alpha and beta.
      const int a = p.vertex[0], b = p.vertex[1], c = p.vertex[2], d = p.vertex[3];
      const Real ax = Real(x[b]) - x[a], ay = Real(y[b]) - y[a];
      const Real bx = Real(x[d]) - x[c], by = Real(y[d]) - y[c];
      const Real cx = Real(x[c]) - x[a], cy = Real(y[c]) - y[a];
      const Real denominator = ax * (-by) - ay * (-bx);
      const Real alpha = (cx * (-by) - cy * (-bx)) / denominator;
      const Real beta = (ax * cy - ay * cx) / denominator;
      ASSERT_NEAR(p.alpha, static_cast<double>(alpha), 1e-9);
      ASSERT_NEAR(p.beta, static_cast<double>(beta), 1e-9);
    }
  }
  EXPECT_LT(skipped, count / 1000);
  // Both classes occur in bulk (random planar quadruples: about 30% are triangles).
  EXPECT_GT(triangles, count / 5);
  EXPECT_GT(quadrilaterals, count / 2);
}

struct Crafted
{
  const char* name;
  double x[4], y[4];
  ProjectionClass kind;
  int thick;
  std::set<int> outer;
  double weightOfThickOpposite; // weight of the outer vertex listed in `heavyVertex`
  int heavyVertex;
};

TEST(Classification, CraftedLimits)
{
  const std::vector<Crafted> cases = {
    { "vertex 3 at the middle of edge 01", { 0, 1, 0, 0.5 }, { 0, 0, 1, 0 },
      ProjectionClass::VertexOnEdge, 3, { 0, 1, 2 }, 0.0, 2 },
    { "vertex 3 a hair inside edge 01", { 0, 1, 0, 0.5 }, { 0, 0, 1, 1e-12 },
      ProjectionClass::VertexOnEdge, 3, { 0, 1, 2 }, 0.0, 2 },
    { "vertex 3 a hair outside edge 01", { 0, 1, 0, 0.5 }, { 0, 0, 1, -1e-12 },
      ProjectionClass::VertexOnEdge, 3, { 0, 1, 2 }, 0.0, 2 },
    { "vertex 1 on edge 02", { 0, 0.25, 1, 0.3 }, { 0, 0.25, 1, 2 }, ProjectionClass::VertexOnEdge,
      1, { 0, 2, 3 }, 0.0, 3 },
    { "vertices 2 and 3 coincide", { 0, 1, 0.2, 0.2 }, { 0, 0, 1, 1 },
      ProjectionClass::CoincidentVertices, 3, { 0, 1, 2 }, 1.0, 2 },
    { "vertices 0 and 1 coincide", { 0.4, 0.4, 1, 0 }, { 0.5, 0.5, 0, 1 },
      ProjectionClass::CoincidentVertices, 1, { 0, 2, 3 }, 1.0, 0 },
    { "vertex 0 strictly inside", { 0.3, 0, 1, 0 }, { 0.3, 0, 0, 1 }, ProjectionClass::Triangle, 0,
      { 1, 2, 3 }, 0.4, 1 },
  };
  for (const auto& c : cases)
  {
    SCOPED_TRACE(c.name);
    const Projection p = ClassifyProjection(c.x, c.y);
    EXPECT_EQ(p.kind, c.kind);
    EXPECT_EQ(p.vertex[3], c.thick);
    EXPECT_EQ((std::set<int>{ p.vertex[0], p.vertex[1], p.vertex[2] }), c.outer);
    for (int k = 0; k < 3; ++k)
    {
      EXPECT_TRUE(std::isfinite(p.weights[k]));
      if (p.vertex[k] == c.heavyVertex)
      {
        EXPECT_NEAR(p.weights[k], c.weightOfThickOpposite, 1e-9);
      }
    }
  }
}

TEST(Classification, DegenerateProjectionsAreNotDrawable)
{
  const double same[4] = { 0.5, 0.5, 0.5, 0.5 };
  const double line[4] = { 0, 1, 2, 3 };
  const double lineY[4] = { 0, 2, 4, 6 };
  const double nan = std::nan("");
  const double withNan[4] = { 0, 1, nan, 0 };
  const double inf = INFINITY;
  const double withInf[4] = { 0, 1, inf, 0 };
  const double y[4] = { 0, 0, 1, 1 };
  EXPECT_EQ(ClassifyProjection(same, same).kind, ProjectionClass::NotDrawable);
  EXPECT_EQ(ClassifyProjection(line, lineY).kind, ProjectionClass::NotDrawable);
  EXPECT_EQ(ClassifyProjection(withNan, y).kind, ProjectionClass::NotDrawable);
  EXPECT_EQ(ClassifyProjection(withInf, y).kind, ProjectionClass::NotDrawable);
}

} // namespace
