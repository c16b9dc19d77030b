// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/NearPlane.h"

#include <cmath>

namespace mtpt
{

NearPlane::NearPlane(const Matrix4& p)
{
  for (int i = 0; i < 4; ++i)
  {
    this->c[i] = p[8 + i] - NearPlaneNdcZ * p[12 + i];
  }
}

bool HasFiniteEyeCoordinates(const ProjectedPoint& p)
{
  return std::fabs(p.eyeX) < CoordinateLimit && std::fabs(p.eyeY) < CoordinateLimit &&
    std::fabs(p.eyeZ) < CoordinateLimit && std::isfinite(p.scalar);
}

namespace
{

/// A point from eye coordinates and scalar, projected as ProjectPoints does.
ProjectedPoint Project(double ex, double ey, double ez, float scalar, const Matrix4& p)
{
  const double cx = p[0] * ex + p[1] * ey + p[2] * ez + p[3];
  const double cy = p[4] * ex + p[5] * ey + p[6] * ez + p[7];
  const double cz = p[8] * ex + p[9] * ey + p[10] * ez + p[11];
  const double cw = p[12] * ex + p[13] * ey + p[14] * ez + p[15];
  ProjectedPoint r{};
  r.inverseW = 1.0 / cw;
  r.x = cx * r.inverseW;
  r.y = cy * r.inverseW;
  r.z = cz * r.inverseW;
  r.eyeX = ex;
  r.eyeY = ey;
  r.eyeZ = ez;
  r.scalar = scalar;
  r.usable = cw > 0.0 && cw < CoordinateLimit && std::fabs(r.x) < CoordinateLimit &&
      std::fabs(r.y) < CoordinateLimit && std::fabs(r.z) < CoordinateLimit
    ? 1
    : 0;
  return r;
}

} // namespace

int CutTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  const NearPlane& plane, const Matrix4& projection, std::vector<NearPiece>& pieces,
  const float* const* colours)
{
  double d[4];
  int in[4], out[4], nin = 0, nout = 0;
  for (int i = 0; i < 4; ++i)
  {
    d[i] = plane.Distance(*corners[i]);
    if (d[i] >= 0.0)
    {
      in[nin++] = i;
    }
    else
    {
      out[nout++] = i;
    }
  }
  if (nin == 0)
  {
    return 0;
  }
  // Corner records: 0..3 the originals, then the crossings of edges (in, out).
  ProjectedPoint records[10];
  float values[10];
  float rgba[10][4] = {};
  for (int i = 0; i < 4; ++i)
  {
    records[i] = *corners[i];
    values[i] = scalars[i];
    for (int c = 0; colours && c < 4; ++c)
    {
      rgba[i][c] = colours[i][c];
    }
  }
  // Record k: where edge (a, b) crosses the plane. A visible corner (d >= 0) lies beyond the
  // near plane, so its projection is usable.
  auto crossing = [&](int k, int a, int b)
  {
    const ProjectedPoint& pa = *corners[a];
    const ProjectedPoint& pb = *corners[b];
    const double t = d[a] / (d[a] - d[b]); // in [0, 1): d[a] >= 0 > d[b]
    const auto lerp = [t](double u, double v) { return u + t * (v - u); };
    records[k] = Project(lerp(pa.eyeX, pb.eyeX), lerp(pa.eyeY, pb.eyeY), lerp(pa.eyeZ, pb.eyeZ),
      static_cast<float>(lerp(pa.scalar, pb.scalar)), projection);
    values[k] = static_cast<float>(lerp(scalars[a], scalars[b]));
    for (int c = 0; colours && c < 4; ++c)
    {
      rgba[k][c] = static_cast<float>(lerp(colours[a][c], colours[b][c]));
    }
  };
  auto emit = [&](const int ids[4])
  {
    NearPiece piece;
    for (int i = 0; i < 4; ++i)
    {
      piece.corners[i] = records[ids[i]];
      piece.scalars[i] = values[ids[i]];
      for (int c = 0; c < 4; ++c)
      {
        piece.colours[i][c] = rgba[ids[i]][c];
      }
    }
    pieces.push_back(piece);
  };
  if (nout == 0)
  {
    const int ids[4] = { 0, 1, 2, 3 };
    emit(ids);
    return 1;
  }
  if (nin == 1)
  {
    for (int k = 0; k < 3; ++k)
    {
      crossing(4 + k, in[0], out[k]);
    }
    const int ids[4] = { in[0], 4, 5, 6 };
    emit(ids);
    return 1;
  }
  // A triangular prism: ends a0 a1 a2 and b0 b1 b2, with edges a_i b_i.
  int a[3], b[3];
  if (nin == 3)
  {
    for (int k = 0; k < 3; ++k)
    {
      a[k] = in[k];
      crossing(4 + k, in[k], out[0]);
      b[k] = 4 + k;
    }
  }
  else // two visible corners: the ends are the triangles around each of them
  {
    a[0] = in[0];
    b[0] = in[1];
    crossing(4, in[0], out[0]);
    crossing(5, in[0], out[1]);
    crossing(6, in[1], out[0]);
    crossing(7, in[1], out[1]);
    a[1] = 4;
    a[2] = 5;
    b[1] = 6;
    b[2] = 7;
  }
  const int t0[4] = { a[0], a[1], a[2], b[0] };
  const int t1[4] = { a[1], a[2], b[0], b[1] };
  const int t2[4] = { a[2], b[0], b[1], b[2] };
  emit(t0);
  emit(t1);
  emit(t2);
  return 3;
}

} // namespace mtpt
