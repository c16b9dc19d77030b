// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Shading.h"

#include <cmath>

namespace mtpt
{

PerspectiveInterpolation PerspectiveInterpolation::FromProjection(const Matrix4& p)
{
  PerspectiveInterpolation v;
  // A perspective frustum: clip w = p14 ez with p14 < 0 (the eye depth D = -ez times
  // -p14), clip z = p10 ez + p11, clip x and y free of translation terms.
  if (p[8] != 0.0 || p[9] != 0.0 || p[12] != 0.0 || p[13] != 0.0 || !(p[14] < 0.0) ||
    p[15] != 0.0 || !(p[0] != 0.0) || !(p[5] != 0.0) || p[1] != 0.0 || p[4] != 0.0 || p[3] != 0.0 ||
    p[7] != 0.0 || !(std::fabs(p[11]) > 0.0))
  {
    return v;
  }
  v.perspective = true;
  // z_ndc = p10 / p14 - p11 / (p14 D), so 1 / D = (p10 - p14 z_ndc) / p11.
  v.inverseWScale = -p[14] / p[11];
  v.inverseWOffset = p[10] / p[11];
  // x_ndc = p0 ex / (-p14 D) + p2 / p14, so ex / D = (x_ndc - p2 / p14) (-p14 / p0).
  v.scaleX = -p[14] / p[0];
  v.shiftX = -p[2] / p[14];
  v.scaleY = -p[14] / p[5];
  v.shiftY = -p[6] / p[14];
  return v;
}

DepthClipping DepthClipping::FromProjection(const Matrix4& p)
{
  DepthClipping c;
  c.ray = PerspectiveInterpolation::FromProjection(p);
  c.perspective = c.ray.perspective;
  if (c.perspective)
  {
    c.a = c.ray.inverseWScale;
    c.b = c.ray.inverseWOffset;
  }
  else if (p[10] != 0.0)
  {
    // Orthographic: z_ndc = p10 ez + p11 with ez = -D.
    c.a = -1.0 / p[10];
    c.b = p[11] / p[10];
  }
  if (!c.perspective && p[0] != 0.0 && p[5] != 0.0)
  {
    // x_ndc = p0 ex + p3, y_ndc = p5 ey + p7.
    c.scaleX = 1.0 / p[0];
    c.shiftX = -p[3];
    c.scaleY = 1.0 / p[5];
    c.shiftY = -p[7];
  }
  return c;
}

} // namespace mtpt
