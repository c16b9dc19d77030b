// SPDX-License-Identifier: BSD-3-Clause
// Clipping planes' arithmetic (mtpt/Shading.h): the eye point of a pixel's ray at a depth,
// and the part of a segment the planes keep.
#include "TestHelpers.h"

#include "mtpt/Shading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{

TEST(ClipPlanes, EyePointInvertsTheProjection)
{
  // An eye point projected, and its NDC and eye depth taken back to eye coordinates.
  for (bool perspective : { false, true })
  {
    const mtpt::Matrix4 projection = perspective
      ? mtpt::test::Perspective(40, 1.3, 0.5, 9)
      : mtpt::test::Ortho(-1.7, 2.1, -1.2, 0.9, 0.5, 9);
    const mtpt::DepthClipping view = mtpt::DepthClipping::FromProjection(projection);
    const mtpt::test::Vec3 eye{ 0.31, -0.22, -3.7 };
    const mtpt::test::Vec3 ndc = mtpt::test::Apply(projection, eye);
    double e[3];
    view.EyePoint(ndc[0], ndc[1], view.EyeDepth(0.5 * (ndc[2] + 1.0)), e);
    for (int k = 0; k < 3; ++k)
    {
      EXPECT_NEAR(e[k], eye[k], 1e-12) << (perspective ? "perspective" : "orthographic");
    }
  }
}

TEST(ClipPlanes, NarrowKeepsThePartOnTheNormalsSide)
{
  mtpt::ClipPlanes planes;
  planes.count = 2;
  // z >= -2 (the near part of a ray along -z) and x <= 1.
  const double near[4] = { 0, 0, 1, 2 }, left[4] = { -1, 0, 0, 1 };
  std::copy(near, near + 4, planes.plane[0]);
  std::copy(left, left + 4, planes.plane[1]);
  const double front[3] = { 0, 0, -1 }, back[3] = { 2, 0, -5 };
  double t0 = 0, t1 = 1;
  ASSERT_TRUE(planes.Narrow(front, back, t0, t1));
  // z = -1 - 4t >= -2 up to t = 1/4; x = 2t <= 1 up to t = 1/2.
  EXPECT_DOUBLE_EQ(t0, 0.0);
  EXPECT_DOUBLE_EQ(t1, 0.25);
  // From the other end: the far side of the first plane only.
  planes.plane[0][2] = -1;
  planes.plane[0][3] = -2;
  planes.count = 1;
  t0 = 0;
  t1 = 1;
  ASSERT_TRUE(planes.Narrow(front, back, t0, t1));
  EXPECT_DOUBLE_EQ(t0, 0.25);
  EXPECT_DOUBLE_EQ(t1, 1.0);
  // Wholly on the clipped side, or touching it at one end only: nothing kept.
  const double behind[3] = { 0, 0, -1.5 };
  t0 = 0;
  t1 = 1;
  EXPECT_FALSE(planes.Narrow(front, behind, t0, t1));
  planes.plane[0][3] = -5;
  t0 = 0;
  t1 = 1;
  EXPECT_FALSE(planes.Narrow(front, back, t0, t1));
  // A plane that is not a number cuts nothing, as in VTK's GPU ray caster.
  planes.plane[0][0] = std::numeric_limits<double>::quiet_NaN();
  t0 = 0;
  t1 = 1;
  EXPECT_TRUE(planes.Narrow(front, back, t0, t1));
  EXPECT_EQ(t0, 0.0);
  EXPECT_EQ(t1, 1.0);
}

TEST(ClipPlanes, EqualityComparesThePlanesInUse)
{
  mtpt::ClipPlanes a, b;
  EXPECT_TRUE(a == b);
  a.count = b.count = 1;
  a.plane[0][3] = 1;
  EXPECT_FALSE(a == b);
  b.plane[0][3] = 1;
  b.plane[1][0] = 5; // not in use
  EXPECT_TRUE(a == b);
  b.count = 2;
  EXPECT_FALSE(a == b);
}

} // namespace
