// SPDX-License-Identifier: BSD-3-Clause
// Internal: the blend modes other than Composite. Each fragment's segment folded into its
// pixel in any order: the extremes of its scalar (maximum and minimum intensity), or the
// integrals of opacity times the normalized scalar (average intensity, additive), exactly
// over the segment, a fragment or a vector of them at a time.
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_REDUCTIONS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_REDUCTIONS_INL_H_
#undef MTPT_COMPOSITOR_REDUCTIONS_INL_H_
#else
#define MTPT_COMPOSITOR_REDUCTIONS_INL_H_
#endif

#include "detail/TileRaster.h"

#include "detail/RasterCorners-inl.h"
#include "detail/RasterPixels-inl.h"
#include "detail/Segments-inl.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

/**
 * A blend mode other than Composite: folds the fragment at column x whose drawn part runs
 * from entry coordinate u0 to u1 (not clamped) over eye length `length` into the pixel
 * (TileTarget). The average's range (RasterFrame::averageRange) is open beyond the table
 * where it reaches the table's ends, as it applies to the clamped scalar.
 */
inline void ReduceFragment(
  const RasterFrame& f, const TileRow& row, int x, double u0, double u1, double length)
{
  const bool seen = row.a[x] > 0.0f;
  row.a[x] = 1.0f;
  const double low = std::min(u0, u1), high = std::max(u0, u1);
  const double last = f.transferFunction.size - 1;
  switch (f.blendMode)
  {
    case BlendMode::MaximumIntensity:
    {
      const auto value = static_cast<float>(std::min(last, std::max(0.0, high)));
      row.r[x] = seen ? std::max(row.r[x], value) : value;
      return;
    }
    case BlendMode::MinimumIntensity:
    {
      const auto value = static_cast<float>(std::min(last, std::max(0.0, low)));
      row.r[x] = seen ? std::min(row.r[x], value) : value;
      return;
    }
    case BlendMode::Additive:
      row.r[x] += static_cast<float>(length * f.intensity->Mean(f.transferFunction, low, high));
      return;
    case BlendMode::AverageIntensity:
    {
      // The stretch of the segment whose scalar lies in the range: a fraction of its length.
      const double from = std::max(low, f.averageRange[0]);
      const double to = std::min(high, f.averageRange[1]);
      double fraction = 0.0;
      if (high > low)
      {
        fraction = to > from ? (to - from) / (high - low) : 0.0;
      }
      else
      {
        fraction = from <= to ? 1.0 : 0.0; // a constant scalar, in the range or not
      }
      if (fraction > 0.0)
      {
        const double part = length * fraction;
        row.r[x] += static_cast<float>(
          part * f.intensity->Mean(f.transferFunction, from, std::max(from, to)));
        row.g[x] += static_cast<float>(part);
      }
      return;
    }
    case BlendMode::Composite:
      return;
  }
}

/// A whole fragment's scalars at its ends and its depth, as vectors: the attribute planes at
/// the lanes' columns i of tile row j (Mode::Integrated and Mode::ExactIntegral).
template <class D, class V = hn::Vec<D>>
HWY_INLINE void WholeFragments(
  D d, Mode mode, const Planes& p, V i, float j, V& front, V& back, V& length, V& z)
{
  auto value = [&](int k)
  { return hn::MulAdd(hn::Set(d, p.dx[k]), i, hn::Set(d, p.base[k] + p.dy[k] * j)); };
  if (mode == Mode::Integrated)
  {
    front = value(0);
    back = value(1);
    length = value(2);
    z = value(3);
    return;
  }
  const V frontW = value(1), backW = value(3), rayX = value(4), rayY = value(5);
  front = hn::Div(value(0), frontW);
  back = hn::Div(value(2), backW);
  const V ray = hn::Sqrt(hn::MulAdd(rayX, rayX, hn::MulAdd(rayY, rayY, hn::Set(d, 1.0f))));
  length = ExactSegmentLength(frontW, backW, value(7), ray);
  z = value(6);
}

/// The lanes of `keep` whose whole fragments at depth z (NDC) are drawn: between the near
/// and far planes, and not behind the opaque depth of tile column x of `row`.
template <class D, class V = hn::Vec<D>>
HWY_INLINE hn::Mask<D> DrawnLanes(D d, const TileRow& row, int x, V z, hn::Mask<D> keep)
{
  keep = hn::And(keep, hn::And(hn::Ge(z, hn::Set(d, -1.0f)), hn::Le(z, hn::Set(d, 1.0f))));
  if (row.depth)
  {
    const auto depth = hn::MulAdd(z, hn::Set(d, 0.5f), hn::Set(d, 0.5f));
    keep = hn::And(keep, hn::Le(depth, hn::LoadU(d, row.depth + x)));
  }
  return keep;
}

/// The integral of o x over the fractions [g0, g1] of table interval b (opacity a + dd g
/// there, x = k (b + g)): k (g1 - g0) (a b + m1 (a + dd b) + m2 dd) with m1 and m2 the means
/// of g and g^2 over [g0, g1]. Closed form: no cancellation however short.
template <class D, class V = hn::Vec<D>>
HWY_INLINE V IntervalIntegralLanes(D d, V k, V a, V dd, V b, V g0, V g1)
{
  const V m1 = hn::Mul(hn::Set(d, 0.5f), hn::Add(g0, g1));
  const V m2 =
    hn::Mul(hn::Set(d, 1.0f / 3.0f), hn::MulAdd(g0, g0, hn::MulAdd(g0, g1, hn::Mul(g1, g1))));
  const V mean = hn::MulAdd(m2, dd, hn::MulAdd(m1, hn::MulAdd(dd, b, a), hn::Mul(a, b)));
  return hn::Mul(hn::Mul(k, hn::Sub(g1, g0)), mean);
}

/**
 * IntensityTable::Mean per lane, in float as the OpenGL backend's shader computes it: the
 * mean of o x over the entry coordinates [u0, u1] (u0 <= u1, not clamped). Within one
 * interval, or across one boundary, in closed form; across more, from the prefix sums (whose
 * rounding the span of at least one entry divides). Beyond the table: 0 below, the last
 * opacity above.
 */
template <class D, class V = hn::Vec<D>>
HWY_INLINE V IntensityMeanLanes(D d, const RasterFrame& f, V u0, V u1)
{
  const hn::RebindToSigned<D> di;
  const TransferFunctionTable& tf = f.transferFunction;
  const IntensityTable& t = *f.intensity;
  const int n = tf.size;
  if (n < 2 || !t.Covers(tf))
  {
    return hn::Zero(d);
  }
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  const V last = hn::Set(d, static_cast<float>(n - 1));
  const V k = hn::Set(d, 1.0f / static_cast<float>(n - 1));
  const V in0 = hn::Min(hn::Max(u0, zero), last), in1 = hn::Min(hn::Max(u1, zero), last);
  const V lastInterval = hn::Set(d, static_cast<float>(n - 2));
  const V b0 = hn::Min(hn::Floor(in0), lastInterval), b1 = hn::Min(hn::Floor(in1), lastInterval);
  const V f0 = hn::Sub(in0, b0), f1 = hn::Sub(in1, b1);
  const auto i0 = hn::ConvertTo(di, b0), i1 = hn::ConvertTo(di, b1);
  auto alpha = [&](hn::Vec<decltype(di)> i)
  { return hn::GatherIndex(d, tf.table + 3, hn::ShiftLeft<2>(i)); }; // entry i's alpha
  const V a0 = alpha(i0), d0 = hn::Sub(alpha(hn::Add(i0, hn::Set(di, 1))), a0);
  const V a1 = alpha(i1), d1 = hn::Sub(alpha(hn::Add(i1, hn::Set(di, 1))), a1);
  // One interval; two neighbouring ones; or the prefix sums and the two ends' partials.
  const V within = IntervalIntegralLanes(d, k, a0, d0, b0, f0, f1);
  const V neighbours = hn::Add(IntervalIntegralLanes(d, k, a0, d0, b0, f0, one),
    IntervalIntegralLanes(d, k, a1, d1, b1, zero, f1));
  auto prefix = [&](const std::vector<float>& w, hn::Vec<decltype(di)> i)
  { return hn::GatherIndex(d, w.data(), i); };
  const V sums = hn::Add(hn::Sub(prefix(t.prefixHigh, i1), prefix(t.prefixHigh, i0)),
    hn::Sub(prefix(t.prefixLow, i1), prefix(t.prefixLow, i0)));
  const V across = hn::Add(sums,
    hn::Sub(IntervalIntegralLanes(d, k, a1, d1, b1, zero, f1),
      IntervalIntegralLanes(d, k, a0, d0, b0, zero, f0)));
  const V steps = hn::Sub(b1, b0);
  const V inside = hn::IfThenElse(
    hn::Eq(steps, zero), within, hn::IfThenElse(hn::Eq(steps, one), neighbours, across));
  const V above = hn::ZeroIfNegative(hn::Sub(u1, hn::Max(u0, last)));
  const V span = hn::Sub(u1, u0);
  const V mean = hn::Div(hn::MulAdd(above, hn::Set(d, tf.table[4 * (n - 1) + 3]), inside), span);
  // A constant scalar: o x there.
  const V point = hn::Mul(hn::MulAdd(d0, f0, a0), hn::Mul(k, hn::Add(b0, f0)));
  return hn::IfThenElse(hn::Gt(span, zero), mean, point);
}

/**
 * Folds whole fragments with scalars `front` and `back` at their ends and depth z into the
 * lanes `keep` of the vector at tile column x of `row`: maximum or minimum intensity.
 */
template <class D, class V = hn::Vec<D>>
HWY_INLINE void FoldExtremes(
  D d, const RasterFrame& f, const TileRow& row, int x, V front, V back, V z, hn::Mask<D> keep)
{
  const TransferFunctionTable& tf = f.transferFunction;
  const auto one = hn::Set(d, 1.0f);
  keep = DrawnLanes(d, row, x, z, keep);
  if (hn::AllFalse(d, keep))
  {
    return;
  }
  const bool maximum = f.blendMode == BlendMode::MaximumIntensity;
  auto u = EntryLanes(d, tf, maximum ? hn::Max(front, back) : hn::Min(front, back));
  u = hn::Min(hn::Max(u, hn::Zero(d)), hn::Set(d, static_cast<float>(tf.size - 1)));
  const auto held = hn::LoadU(d, row.r + x), alpha = hn::LoadU(d, row.a + x);
  const auto folded = maximum ? hn::Max(held, u) : hn::Min(held, u);
  const auto value = hn::IfThenElse(hn::Gt(alpha, hn::Zero(d)), folded, u);
  hn::StoreU(hn::IfThenElse(keep, value, held), d, row.r + x);
  hn::StoreU(hn::IfThenElse(keep, one, alpha), d, row.a + x);
}

/**
 * Folds whole fragments (scalars `front` and `back` at their ends, eye length `length`, depth
 * z) into the lanes `keep` of the vector at tile column x of `row`: average intensity or
 * additive (ReduceFragment's arithmetic in float).
 */
template <class D, class V = hn::Vec<D>>
HWY_INLINE void FoldIntegrals(D d, const RasterFrame& f, const TileRow& row, int x, V front, V back,
  V length, V z, hn::Mask<D> keep)
{
  keep = DrawnLanes(d, row, x, z, keep);
  if (hn::AllFalse(d, keep))
  {
    return;
  }
  const V u0 = EntryLanes(d, f.transferFunction, front);
  const V u1 = EntryLanes(d, f.transferFunction, back);
  const V low = hn::Min(u0, u1), high = hn::Max(u0, u1);
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  V weighted, counted = zero;
  if (f.blendMode == BlendMode::Additive)
  {
    weighted = hn::Mul(length, IntensityMeanLanes(d, f, low, high));
  }
  else
  {
    // The stretch whose scalar lies in the range: a fraction of the segment's length.
    const V from = hn::Max(low, hn::Set(d, static_cast<float>(f.averageRange[0])));
    const V to = hn::Min(high, hn::Set(d, static_cast<float>(f.averageRange[1])));
    const V span = hn::Sub(high, low);
    const V fraction = hn::IfThenElse(hn::Gt(span, zero),
      hn::IfThenElseZero(hn::Gt(to, from), hn::Div(hn::Sub(to, from), span)),
      hn::IfThenElseZero(hn::Le(from, to), one));
    counted = hn::Mul(length, fraction);
    weighted = hn::IfThenElseZero(
      hn::Gt(fraction, zero), hn::Mul(counted, IntensityMeanLanes(d, f, from, hn::Max(from, to))));
  }
  const V r = hn::LoadU(d, row.r + x), g = hn::LoadU(d, row.g + x), a = hn::LoadU(d, row.a + x);
  hn::StoreU(hn::IfThenElse(keep, hn::Add(r, weighted), r), d, row.r + x);
  hn::StoreU(hn::IfThenElse(keep, hn::Add(g, counted), g), d, row.g + x);
  hn::StoreU(hn::IfThenElse(keep, one, a), d, row.a + x);
}

/// The whole fragments of the lanes `keep` at tile column x of `row` (tile row j) folded by the
/// frame's blend mode (FoldExtremes or FoldIntegrals).
template <class D>
void ReduceVector(D d, const RasterFrame& f, Mode mode, const TileRow& row, const Planes& p,
  float j, int x, hn::Mask<D> keep)
{
  const auto i = hn::Iota(d, static_cast<float>(x));
  hn::Vec<D> front, back, length, z;
  WholeFragments(d, mode, p, i, j, front, back, length, z);
  if (f.blendMode == BlendMode::MaximumIntensity || f.blendMode == BlendMode::MinimumIntensity)
  {
    FoldExtremes(d, f, row, x, front, back, z, keep);
  }
  else
  {
    FoldIntegrals(d, f, row, x, front, back, length, z, keep);
  }
}

/// ReduceVector over the pixels [lo, hi] of row y.
inline void ReduceWhole(
  const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p, int y, int lo, int hi)
{
  const FragmentTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const TileRow row = RowOf(tile, y);
  const float j = static_cast<float>(y - tile.y0);
  const int first = lo - tile.x0, end = hi - tile.x0;
  for (int from = first; from <= end; from += lanes)
  {
    const int x = std::min(from, T - lanes); // as ShadeCompatible
    const auto i = hn::Iota(d, static_cast<float>(x));
    ReduceVector(d, f, mode, row, p, j, x,
      hn::And(hn::Ge(i, hn::Set(d, static_cast<float>(from))),
        hn::Le(i, hn::Set(d, static_cast<float>(end)))));
  }
}

/// A blend mode other than Composite: reduces the fragments of the pixels [lo, hi] of row y,
/// each one's part drawn (DrawnPart) with its scalars in entry coordinates.
inline void ReduceSpan(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p,
  int y, int lo, int hi, bool cut)
{
  if (!cut && !f.clipToRange)
  {
    ReduceWhole(f, tile, mode, p, y, lo, hi);
    return;
  }
  const TileRow row = RowOf(tile, y);
  for (int x = lo - tile.x0; x <= hi - tile.x0; ++x)
  {
    const FragmentSegment s = SegmentAt(f, tile, mode, p, x, y);
    double t0, t1;
    if (!DrawnPart(f, tile, row, s, x, y, cut, t0, t1))
    {
      continue;
    }
    const double change = s.scalarBack - s.scalarFront;
    const double u0 = f.transferFunction.UnclampedEntryCoordinate(s.scalarFront + t0 * change);
    const double u1 = f.transferFunction.UnclampedEntryCoordinate(s.scalarFront + t1 * change);
    ReduceFragment(f, row, x, u0, u1, (t1 - t0) * s.length);
  }
}

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_REDUCTIONS_INL_H_
