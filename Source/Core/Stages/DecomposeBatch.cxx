// SPDX-License-Identifier: BSD-3-Clause
// The decomposition's arithmetic for a batch of tetrahedra, one per lane
// (detail/DecomposeBatch.h). Google Highway compiles this file once per instruction set
// (foreach_target.h includes it again for each) and the dispatch at the end picks the best
// the processor has.
//
// Every value is computed with the operations of the scalar code in Decompose.cxx, in the
// same order; a lane computes both the quadrilateral's and the triangle's formulas and keeps
// the one its class needs. The file is compiled without floating-point contraction
// (CMakeLists.txt), so no multiply-add is fused and each lane's result equals the scalar
// one bit for bit. Lanes of the class not taken may hold infinities; they are discarded.
#include "detail/DecomposeBatch.h"

#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "DecomposeBatch.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using DI = hn::RebindToSigned<D>;
using DF = hn::Rebind<float, D>;
using V = hn::Vec<D>;
using VI = hn::Vec<DI>;
using M = hn::Mask<D>;

/// The fields of ProjectedPoint a lane gathers, in units of doubles.
enum Field : std::int64_t
{
  X = 0,
  Y,
  Z,
  InverseW,
  EyeX,
  EyeY,
  EyeZ,
  Stride = sizeof(ProjectedPoint) / sizeof(double)
};
static_assert(offsetof(ProjectedPoint, y) == Field::Y * sizeof(double) &&
    offsetof(ProjectedPoint, inverseW) == Field::InverseW * sizeof(double) &&
    offsetof(ProjectedPoint, eyeZ) == Field::EyeZ * sizeof(double),
  "Field is ProjectedPoint's layout");
static_assert(Field::Stride == 8, "a point is 8 doubles: DecomposeLanes shifts its ids by 3");

/// The four corners of the lanes' tetrahedra, one vector per field and corner.
struct Corners
{
  V x[4], y[4], z[4], inverseW[4], eye[3][4], scalar[4];
};

/// Selects, per lane, corner `role`'s value of a field (role[lane] in 0..3).
struct RoleSelect
{
  M is[4][3]; ///< is[r][i]: the lane's corner in part r is corner i (i < 3; else corner 3)

  V operator()(int r, const V field[4]) const
  {
    return hn::IfThenElse(this->is[r][0], field[0],
      hn::IfThenElse(this->is[r][1], field[1], hn::IfThenElse(this->is[r][2], field[2], field[3])));
  }
};

/// Eye-space point, scalar, NDC z and screen x, y at the segment ends the class defines.
struct SegmentEnds
{
  V first[3], second[3], firstScalar, secondScalar, firstZ, secondZ, thickX, thickY;
};

/// PerspectiveCorrect (Decompose.cxx): s * (1/wb) / ((1 - s) / wa + s / wb).
HWY_INLINE V PerspectiveCorrect(D d, V s, V inverseWa, V inverseWb)
{
  return hn::Div(hn::Mul(s, inverseWb),
    hn::Add(hn::Mul(hn::Sub(hn::Set(d, 1.0), s), inverseWa), hn::Mul(s, inverseWb)));
}

/// a + t * (b - a)
HWY_INLINE V Lerp(V a, V b, V t)
{
  return hn::Add(a, hn::Mul(t, hn::Sub(b, a)));
}

/// Class 2 (ComputeFanGeometry's first branch): the diagonals' crossing, parts (a, b, d0, d1).
HWY_INLINE void QuadrilateralEnds(
  D d, const Corners& c, const V magnitude[4], const RoleSelect& select, SegmentEnds& e)
{
  const V magA = select(0, magnitude), magB = select(1, magnitude);
  const V magD0 = select(2, magnitude), magD1 = select(3, magnitude);
  const V alpha = hn::Div(magB, hn::Add(magA, magB));
  const V beta = hn::Div(magD1, hn::Add(magD0, magD1));
  const V tab = PerspectiveCorrect(d, alpha, select(0, c.inverseW), select(1, c.inverseW));
  const V tcd = PerspectiveCorrect(d, beta, select(2, c.inverseW), select(3, c.inverseW));
  for (int k = 0; k < 3; ++k)
  {
    e.first[k] = Lerp(select(0, c.eye[k]), select(1, c.eye[k]), tab);
    e.second[k] = Lerp(select(2, c.eye[k]), select(3, c.eye[k]), tcd);
  }
  e.firstScalar = Lerp(select(0, c.scalar), select(1, c.scalar), tab);
  e.secondScalar = Lerp(select(2, c.scalar), select(3, c.scalar), tcd);
  e.firstZ = Lerp(select(0, c.z), select(1, c.z), alpha);
  e.secondZ = Lerp(select(2, c.z), select(3, c.z), beta);
  e.thickX = Lerp(select(0, c.x), select(1, c.x), alpha);
  e.thickY = Lerp(select(0, c.y), select(1, c.y), alpha);
}

/// u0 * f[j0] + u1 * f[j1] + u2 * f[j2], left to right.
HWY_INLINE V Weighted(const V u[3], const RoleSelect& select, const V field[4])
{
  return hn::Add(hn::Add(hn::Mul(u[0], select(0, field)), hn::Mul(u[1], select(1, field))),
    hn::Mul(u[2], select(2, field)));
}

/// Classes 1, 3 and 4 (the second branch): parts (j0, j1, j2, t). `magnitude` is zero
/// where an area is within the zero band.
HWY_INLINE void TriangleEnds(
  D d, const Corners& c, const V magnitude[4], const RoleSelect& select, SegmentEnds& e)
{
  // ClassifyProjection's barycentric weights of the inner point in the outer triangle.
  V w[3] = { select(0, magnitude), select(1, magnitude), select(2, magnitude) };
  const V inverseSum = hn::Div(hn::Set(d, 1.0), hn::Add(hn::Add(w[0], w[1]), w[2]));
  V m[3];
  for (int k = 0; k < 3; ++k)
  {
    w[k] = hn::Mul(w[k], inverseSum);
    m[k] = hn::Mul(w[k], select(k, c.inverseW));
  }
  const V inv = hn::Div(hn::Set(d, 1.0), hn::Add(hn::Add(m[0], m[1]), m[2]));
  const V u[3] = { hn::Mul(m[0], inv), hn::Mul(m[1], inv), hn::Mul(m[2], inv) };
  for (int k = 0; k < 3; ++k)
  {
    e.first[k] = select(3, c.eye[k]);
    e.second[k] = Weighted(u, select, c.eye[k]);
  }
  e.firstScalar = select(3, c.scalar);
  e.secondScalar = Weighted(u, select, c.scalar);
  e.firstZ = select(3, c.z);
  e.secondZ = Weighted(w, select, c.z);
  e.thickX = select(3, c.x);
  e.thickY = select(3, c.y);
}

/// SignedAreas: the doubled signed areas, whether the projection has an area, and the
/// sign pattern (SignPatterns) as an integer per lane.
HWY_INLINE M SignedAreas(D d, const Corners& c, double tolerance, V magnitude[4], VI& pattern)
{
  auto orient = [&](int p, int q, int r)
  {
    return hn::Sub(hn::Mul(hn::Sub(c.x[q], c.x[p]), hn::Sub(c.y[r], c.y[p])),
      hn::Mul(hn::Sub(c.y[q], c.y[p]), hn::Sub(c.x[r], c.x[p])));
  };
  const V area2[4] = { orient(1, 2, 3), orient(0, 3, 2), orient(0, 1, 3), orient(0, 2, 1) };
  V sumAbs = hn::Zero(d);
  for (int i = 0; i < 4; ++i)
  {
    magnitude[i] = hn::Abs(area2[i]);
    sumAbs = hn::Add(sumAbs, magnitude[i]);
  }
  V extent = hn::Zero(d);
  for (int i = 1; i < 4; ++i)
  {
    // The corners are finite (usable): Max is the scalar code's comparison.
    extent = hn::Max(extent, hn::Abs(hn::Sub(c.x[i], c.x[0])));
    extent = hn::Max(extent, hn::Abs(hn::Sub(c.y[i], c.y[0])));
  }
  const M hasArea = hn::And(
    hn::Gt(sumAbs, hn::Mul(hn::Mul(hn::Set(d, 1e-12), extent), extent)), hn::IsFinite(sumAbs));
  const V zeroBand = hn::Mul(hn::Set(d, tolerance), sumAbs);
  const DI di;
  pattern = hn::Zero(di);
  for (int i = 0; i < 4; ++i)
  {
    const M nonZero = hn::Gt(magnitude[i], zeroBand);
    const M positive = hn::And(nonZero, hn::Gt(area2[i], hn::Zero(d)));
    const M negative = hn::AndNot(positive, nonZero);
    pattern =
      hn::Or(pattern, hn::IfThenElseZero(hn::RebindMask(di, positive), hn::Set(di, 1 << i)));
    pattern =
      hn::Or(pattern, hn::IfThenElseZero(hn::RebindMask(di, negative), hn::Set(di, 16 << i)));
    // ClassifyProjection's weights: a zero-band area weighs nothing.
    magnitude[i] = hn::IfThenElseZero(nonZero, magnitude[i]);
  }
  return hasArea;
}

/// Lanes [base, base + Lanes(d)) of the batch.
HWY_INLINE void DecomposeLanes(const ProjectedPoint* points, const TetBatch& batch,
  std::size_t base, const RoleTable& roles, TetBatchResult& result)
{
  const D d;
  const DI di;
  const DF df;
  const auto* values = reinterpret_cast<const double*>(points);
  Corners c;
  for (int i = 0; i < 4; ++i)
  {
    const VI at = hn::ShiftLeft<3>(hn::LoadU(di, batch.point[i] + base)); // Field::Stride
    c.x[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::X)));
    c.y[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::Y)));
    c.z[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::Z)));
    c.inverseW[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::InverseW)));
    c.eye[0][i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::EyeX)));
    c.eye[1][i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::EyeY)));
    c.eye[2][i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, Field::EyeZ)));
    c.scalar[i] = hn::PromoteTo(d, hn::LoadU(df, batch.scalar[i] + base));
  }
  V magnitude[4];
  VI pattern;
  const M hasArea = SignedAreas(d, c, roles.tolerance, magnitude, pattern);
  RoleSelect select;
  for (int r = 0; r < 4; ++r)
  {
    const VI role = hn::GatherIndex(di, roles.role[r], pattern);
    for (int i = 0; i < 3; ++i)
    {
      select.is[r][i] = hn::RebindMask(d, hn::Eq(role, hn::Set(di, i)));
    }
  }
  const M quadrilateral =
    hn::RebindMask(d, hn::Ne(hn::GatherIndex(di, roles.quadrilateral, pattern), hn::Zero(di)));
  SegmentEnds quad, tri;
  QuadrilateralEnds(d, c, magnitude, select, quad);
  TriangleEnds(d, c, magnitude, select, tri);
  auto pick = [&](V SegmentEnds::*field)
  { return hn::IfThenElse(quadrilateral, quad.*field, tri.*field); };
  V dSquared = hn::Zero(d);
  for (int k = 0; k < 3; ++k)
  {
    const V delta = hn::Sub(hn::IfThenElse(quadrilateral, quad.first[k], tri.first[k]),
      hn::IfThenElse(quadrilateral, quad.second[k], tri.second[k]));
    // ((dx * dx + dy * dy) + dz * dz), as the scalar code.
    dSquared = k == 0 ? hn::Mul(delta, delta) : hn::Add(dSquared, hn::Mul(delta, delta));
  }
  const V firstZ = pick(&SegmentEnds::firstZ), secondZ = pick(&SegmentEnds::secondZ);
  const V firstScalar = pick(&SegmentEnds::firstScalar);
  const V secondScalar = pick(&SegmentEnds::secondScalar);
  const M firstInFront = hn::Le(firstZ, secondZ);
  const V thick[6] = { pick(&SegmentEnds::thickX), pick(&SegmentEnds::thickY),
    hn::IfThenElse(firstInFront, firstZ, secondZ),
    hn::IfThenElse(firstInFront, firstScalar, secondScalar),
    hn::IfThenElse(firstInFront, secondScalar, firstScalar), hn::Sqrt(dSquared) };
  for (int f = 0; f < 6; ++f)
  {
    hn::StoreU(hn::DemoteTo(df, thick[f]), df, result.thick[f] + base);
  }
  hn::StoreU(pattern, di, result.pattern + base);
  hn::StoreU(
    hn::IfThenElseZero(hn::RebindMask(di, hasArea), hn::Set(di, 1)), di, result.hasArea + base);
}

void DecomposeBatchImpl(const ProjectedPoint* points, const TetBatch& batch, int count,
  const RoleTable& roles, TetBatchResult& result)
{
  const std::size_t lanes = hn::Lanes(D());
  for (std::size_t base = 0; base < static_cast<std::size_t>(count); base += lanes)
  {
    DecomposeLanes(points, batch, base, roles, result);
  }
}

const char* BatchTargetName()
{
  return hwy::TargetName(HWY_TARGET);
}

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtpt
{
namespace detail
{

HWY_EXPORT(DecomposeBatchImpl);
HWY_EXPORT(BatchTargetName);

void DecomposeBatch(const ProjectedPoint* points, const TetBatch& batch, int count,
  const RoleTable& roles, TetBatchResult& result)
{
  HWY_DYNAMIC_DISPATCH(DecomposeBatchImpl)(points, batch, count, roles, result);
}

const char* DecomposeTargetName()
{
  return HWY_DYNAMIC_DISPATCH(BatchTargetName)();
}

} // namespace detail
} // namespace mtpt
#endif
