// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/NearPlane.h"
#include "mtpt/Faults.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>

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

/// The corners of the pieces of one cut tetrahedron: 0..3 the originals, then the
/// crossings of edges (visible corner, hidden corner) with the plane.
struct CutCorners
{
  const ProjectedPoint* const* corners;
  const float* scalars;
  const float* const* colours; ///< null without dependent components
  const Matrix4& projection;
  double d[4]; ///< signed distances of the corners from the plane
  ProjectedPoint records[10];
  float values[10];
  float rgba[10][4] = {};

  CutCorners(const ProjectedPoint* const c[4], const float s[4], const float* const* rgbaIn,
    const NearPlane& plane, const Matrix4& p)
    : corners(c)
    , scalars(s)
    , colours(rgbaIn)
    , projection(p)
  {
    for (int i = 0; i < 4; ++i)
    {
      this->d[i] = plane.Distance(*c[i]);
      this->records[i] = *c[i];
      this->values[i] = s[i];
      for (int ch = 0; rgbaIn && ch < 4; ++ch)
      {
        this->rgba[i][ch] = rgbaIn[i][ch];
      }
    }
  }

  /// Record k: where edge (a, b) crosses the plane, position, scalar and colour interpolated
  /// linearly. A visible corner (d >= 0) lies beyond the near plane: its projection is usable.
  void Cross(int k, int a, int b)
  {
    const ProjectedPoint& pa = *this->corners[a];
    const ProjectedPoint& pb = *this->corners[b];
    const double t = this->d[a] / (this->d[a] - this->d[b]); // in [0, 1): d[a] >= 0 > d[b]
    const auto lerp = [t](double u, double v) { return u + t * (v - u); };
    this->records[k] = Project(lerp(pa.eyeX, pb.eyeX), lerp(pa.eyeY, pb.eyeY),
      lerp(pa.eyeZ, pb.eyeZ), static_cast<float>(lerp(pa.scalar, pb.scalar)), this->projection);
    this->values[k] = static_cast<float>(lerp(this->scalars[a], this->scalars[b]));
    for (int ch = 0; this->colours && ch < 4; ++ch)
    {
      this->rgba[k][ch] = static_cast<float>(lerp(this->colours[a][ch], this->colours[b][ch]));
    }
  }

  /// The piece whose corners are records ids[0..3].
  void Emit(const int ids[4], std::vector<NearPiece>& pieces) const
  {
    NearPiece piece;
    for (int i = 0; i < 4; ++i)
    {
      piece.corners[i] = this->records[ids[i]];
      piece.scalars[i] = this->values[ids[i]];
      for (int ch = 0; ch < 4; ++ch)
      {
        piece.colours[i][ch] = this->rgba[ids[i]][ch];
      }
    }
    pieces.push_back(piece);
  }

  /// Two or three visible corners: the visible part is a triangular prism with ends a0 a1 a2
  /// and b0 b1 b2 and edges a_i b_i, cut into 3 tetrahedra.
  void EmitPrism(const int in[4], int nin, const int out[4], std::vector<NearPiece>& pieces)
  {
    int a[3], b[3];
    if (nin == 3)
    {
      for (int k = 0; k < 3; ++k)
      {
        a[k] = in[k];
        this->Cross(4 + k, in[k], out[0]);
        b[k] = 4 + k;
      }
    }
    else // two visible corners: the ends are the triangles around each of them
    {
      a[0] = in[0];
      b[0] = in[1];
      this->Cross(4, in[0], out[0]);
      this->Cross(5, in[0], out[1]);
      this->Cross(6, in[1], out[0]);
      this->Cross(7, in[1], out[1]);
      a[1] = 4;
      a[2] = 5;
      b[1] = 6;
      b[2] = 7;
    }
    const int t0[4] = { a[0], a[1], a[2], b[0] };
    const int t1[4] = { a[1], a[2], b[0], b[1] };
    const int t2[4] = { a[2], b[0], b[1], b[2] };
    this->Emit(t0, pieces);
    this->Emit(t1, pieces);
    this->Emit(t2, pieces);
  }
};

} // namespace

int CutTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  const NearPlane& plane, const Matrix4& projection, std::vector<NearPiece>& pieces,
  const float* const* colours)
{
  CutCorners cut(corners, scalars, colours, plane, projection);
  int in[4], out[4], nin = 0, nout = 0;
  for (int i = 0; i < 4; ++i)
  {
    (cut.d[i] >= 0.0 ? in[nin++] : out[nout++]) = i;
  }
  if (nin == 0)
  {
    return 0;
  }
  if (nout == 0)
  {
    const int ids[4] = { 0, 1, 2, 3 };
    cut.Emit(ids, pieces);
    return 1;
  }
  if (nin == 1)
  {
    for (int k = 0; k < 3; ++k)
    {
      cut.Cross(4 + k, in[0], out[k]);
    }
    const int ids[4] = { in[0], 4, 5, 6 };
    cut.Emit(ids, pieces);
    return 1;
  }
  cut.EmitPrism(in, nin, out, pieces);
  return 3;
}

bool NearPlaneStage::Update(const Key& key, const LargeVector<SortKey>& keys,
  const ProjectedPoint* points, std::size_t pointCount, const CellsView& cells,
  const ScalarsView& scalars, const float* colours, const Matrix4& projection, bool perspective,
  int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  this->Made.clear();
  this->Keys.clear();
  this->ClippedCells = 0;
  const NearPlane plane(projection);
  this->Cut = this->Classify(keys, points, pointCount, cells, scalars, plane, threads);
  if (this->Cut)
  {
    this->CutCrossing(
      keys, points, pointCount, cells, scalars, colours, plane, projection, perspective);
  }
  this->Record.Store(key);
  return true;
}

bool NearPlaneStage::Classify(const LargeVector<SortKey>& keys, const ProjectedPoint* points,
  std::size_t pointCount, const CellsView& cells, const ScalarsView& scalars,
  const NearPlane& plane, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  // Most frames have no point in front of the plane: one pass over the points decides.
  const auto points64 = static_cast<std::int64_t>(pointCount);
  const int any = detail::ParallelReduce(
    0, points64, nthreads, 0, [](int a, int b) { return a | b; },
    [&](std::int64_t i)
    { return HasFiniteEyeCoordinates(points[i]) && plane.Distance(points[i]) < 0.0 ? 1 : 0; });
  if (!any)
  {
    return false;
  }
  const float* cellScalars =
    scalars.association == ScalarsView::Association::Cells ? scalars.values : nullptr;
  const auto count = static_cast<std::int64_t>(keys.size());
  if (this->Verdicts.size() < keys.size())
  {
    this->Verdicts.resize(keys.size());
  }
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      detail::ParallelFor(0, count, nthreads,
        [&](std::int64_t k)
        {
          const std::uint32_t cell = CellOfKey(keys[k]);
          std::int64_t ids[4];
          Verdict verdict = Keep;
          if (access.TetrahedronPoints(cell, ids) &&
            (!cellScalars || std::isfinite(cellScalars[cell])))
          {
            int front = 0, finite = 0;
            for (int i = 0; i < 4; ++i)
            {
              const ProjectedPoint& p = points[ids[i]];
              const bool ok = HasFiniteEyeCoordinates(p);
              finite += ok ? 1 : 0;
              front += ok && plane.Distance(p) < 0.0 ? 1 : 0;
            }
            verdict = finite < 4 || front == 0 ? Keep : (front == 4 ? InFront : Crosses);
          }
          this->Verdicts[k] = verdict;
        });
    });
  return true;
}

void NearPlaneStage::CutCrossing(const LargeVector<SortKey>& keys, const ProjectedPoint* points,
  std::size_t pointCount, const CellsView& cells, const ScalarsView& scalars, const float* colours,
  const NearPlane& plane, const Matrix4& projection, bool perspective)
{
  const std::size_t n = cells.cellCount;
  const float* cellScalars =
    scalars.association == ScalarsView::Association::Cells ? scalars.values : nullptr;
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      for (std::size_t k = 0; k < keys.size(); ++k)
      {
        // Past the frame's capacity for pieces a cell is kept whole.
        if (this->Verdicts[k] != Keep && n + this->Made.size() + 3 > MaxFrameTetrahedra)
        {
          this->Verdicts[k] = Keep;
        }
        if (this->Verdicts[k] != Crosses)
        {
          continue;
        }
        const std::uint32_t cell = CellOfKey(keys[k]);
        std::int64_t ids[4] = { 0, 0, 0, 0 };
        access.TetrahedronPoints(cell, ids); // succeeded when the verdict was made
        const ProjectedPoint* corners[4] = { points + ids[0], points + ids[1], points + ids[2],
          points + ids[3] };
        float values[4];
        const float* rgba[4] = { nullptr, nullptr, nullptr, nullptr };
        for (int i = 0; i < 4; ++i)
        {
          const std::int64_t tuple = cellScalars ? static_cast<std::int64_t>(cell) : ids[i];
          values[i] = cellScalars ? cellScalars[cell] : corners[i]->scalar;
          rgba[i] = colours ? colours + 4 * tuple : nullptr;
        }
        if (!this->Made.empty())
        {
          AllocationPoint(AllocationSite::NearPlane); // pieces made already: halfway through
        }
        const std::size_t before = this->Made.size();
        CutTetrahedron(corners, values, plane, projection, this->Made, colours ? rgba : nullptr);
        ++this->ClippedCells;
        for (std::size_t j = before; j < this->Made.size(); ++j)
        {
          this->Made[j].cell = cell;
          const NearPiece& piece = this->Made[j];
          const ProjectedPoint* pieceCorners[4] = { &piece.corners[0], &piece.corners[1],
            &piece.corners[2], &piece.corners[3] };
          this->Keys.push_back(MakeSortKey(
            CentroidDepth(pieceCorners, perspective), static_cast<std::uint32_t>(n + j)));
        }
      }
    });
  std::sort(this->Keys.begin(), this->Keys.end());
}

void NearPlaneStage::Release()
{
  LargeVector<std::uint8_t>().swap(this->Verdicts);
  std::vector<NearPiece>().swap(this->Made);
  LargeVector<SortKey>().swap(this->Keys);
  this->Cut = false;
  this->Record.Forget();
}

std::size_t NearPlaneStage::MemoryBytes() const
{
  return this->Verdicts.capacity() + this->Made.capacity() * sizeof(NearPiece) +
    this->Keys.capacity() * sizeof(SortKey);
}

} // namespace mtpt
