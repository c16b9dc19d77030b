// SPDX-License-Identifier: BSD-3-Clause
// Internal: pre-integrated segments. Each fragment's ray segment shaded through the
// transfer function's prefix integrals, several to a vector (SegmentOfLanes); the fragments
// waiting to be shaded, packed into full vectors (WaitingFragments, ShadeWaiting); and the
// fragments whose segment a depth range or a clipping plane cuts, one at a time
// (ShadeClipped).
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_SEGMENTS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_SEGMENTS_INL_H_
#undef MTPT_COMPOSITOR_SEGMENTS_INL_H_
#else
#define MTPT_COMPOSITOR_SEGMENTS_INL_H_
#endif

#include "detail/TileRaster.h"

#include "detail/RasterCorners-inl.h"
#include "detail/RasterPixels-inl.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

/// Scalars in entry coordinates of `tf`, not clamped (NaN gives 0, as EntryCoordinate).
template <class D, class V = hn::Vec<D>>
HWY_INLINE V EntryLanes(D d, const TransferFunctionTable& tf, V scalar)
{
  const double scale = (tf.size - 1) / (tf.high > tf.low ? tf.high - tf.low : 1.0);
  const V u = hn::MulAdd(
    scalar, hn::Set(d, static_cast<float>(scale)), hn::Set(d, static_cast<float>(-tf.low * scale)));
  return hn::IfThenZeroElse(hn::IsNaN(u), u);
}

/**
 * Pre-integrated shading in single precision, a fragment per lane of the fragment loops'
 * vectors: what PreIntegrationTable::Segment computes (TransferFunctionTable.cxx, in double
 * precision) with the same formulas, reading the table and the prefix integrals (as float
 * sums high + low, so that differences of nearby entries keep their precision); the
 * exponential is OpacityOfDensity's. Within 5e-5 of Segment in every channel of the
 * premultiplied colour (PreIntegratedSegmentsMatchTheScalarIntegration). Most segments of a
 * fine mesh are one step (PreIntegrationSteps); the steps' loop costs only what the thickest
 * lane of a vector asks for. The tables are read a row per lane (TableRows).
 */
struct SegmentTable
{
  TransferFunctionTable tf;
  const float* table = nullptr;     ///< RGBA (alpha: attenuation), padded (PreIntegrationTable)
  const float* integrals = nullptr; ///< prefix integrals, high and low parts, padded
  std::int32_t last = 0;            ///< size - 1
  float lastInterval = 0;           ///< max(size - 2, 0): the last interval's first entry
  float inverseUnit = 1;            ///< 1 / ScalarOpacityUnitDistance

  SegmentTable() = default;
  /// The frame's tables; `f` must have them (RasterFrame::preIntegration).
  explicit SegmentTable(const RasterFrame& f)
    : tf(f.transferFunction)
    , table(f.preIntegration->paddedTable.data())
    , integrals(f.preIntegration->integralsSplit.data())
    , last(f.transferFunction.size - 1)
    , lastInterval(static_cast<float>(std::max(f.transferFunction.size - 2, 0)))
    , inverseUnit(f.inverseUnit)
  {
  }
};

/// TransferFunctionTable::EntryCoordinate per lane: clamped to [0, size - 1], NaN gives 0.
template <class D, class V = hn::Vec<D>>
HWY_INLINE V ClampedEntryLanes(D d, const SegmentTable& t, V scalar)
{
  return hn::Min(
    hn::Max(EntryLanes(d, t.tf, scalar), hn::Zero(d)), hn::Set(d, static_cast<float>(t.last)));
}

/// IntervalAt per lane: attenuation and colour at the interval's start and their changes.
template <class D, class V = hn::Vec<D>>
struct IntervalLanes
{
  V tau, dTau, c[3], dC[3];
};

/**
 * Eight consecutive floats for each lane, from base + offset[l] (l < Lanes(d)), transposed:
 * lane l of out[k] is base[offset[l] + k]. A row load per lane and shuffles: on 8 and 4 lanes
 * far fewer operations than eight gathers.
 */
template <class D>
HWY_INLINE void LoadRows8(D d, const float* base, const std::int32_t* offset, hn::Vec<D> out[8])
{
#if HWY_TARGET != HWY_SCALAR // (one lane: the loop at the end)
  constexpr std::size_t lanes = hn::MaxLanes(D());
  if constexpr (lanes == 8)
  {
    // Within each 128-bit half: pairs, then quadruples of rows; then the halves.
    const hn::Repartition<double, D> dd;
    hn::Vec<D> r[8], t[8];
    for (int l = 0; l < 8; ++l)
    {
      r[l] = hn::LoadU(d, base + offset[l]);
    }
    for (int l = 0; l < 8; l += 2)
    {
      t[l] = hn::InterleaveLower(d, r[l], r[l + 1]);     // rows l, l + 1: items 0 1 | 4 5
      t[l + 1] = hn::InterleaveUpper(d, r[l], r[l + 1]); // items 2 3 | 6 7
    }
    auto pairs = [&](hn::Vec<D> a, hn::Vec<D> b, bool upper)
    {
      const auto x = hn::BitCast(dd, a), y = hn::BitCast(dd, b);
      return hn::BitCast(d, upper ? hn::InterleaveUpper(dd, x, y) : hn::InterleaveLower(dd, x, y));
    };
    for (int half = 0; half < 2; ++half) // rows 0-3, rows 4-7
    {
      const int o = 4 * half;
      r[o] = pairs(t[o], t[o + 2], false);         // item 0 of four rows | item 4
      r[o + 1] = pairs(t[o], t[o + 2], true);      // item 1 | item 5
      r[o + 2] = pairs(t[o + 1], t[o + 3], false); // item 2 | item 6
      r[o + 3] = pairs(t[o + 1], t[o + 3], true);  // item 3 | item 7
    }
    for (int k = 0; k < 4; ++k)
    {
      out[k] = hn::ConcatLowerLower(d, r[4 + k], r[k]);
      out[4 + k] = hn::ConcatUpperUpper(d, r[4 + k], r[k]);
    }
  }
  else if constexpr (lanes == 4)
  {
    for (int part = 0; part < 2; ++part) // items 0-3, items 4-7
    {
      hn::Vec<D> r[4];
      for (int l = 0; l < 4; ++l)
      {
        r[l] = hn::LoadU(d, base + offset[l] + 4 * part);
      }
      const hn::Repartition<double, D> dd;
      const auto t0 = hn::BitCast(dd, hn::InterleaveLower(d, r[0], r[1]));
      const auto t1 = hn::BitCast(dd, hn::InterleaveLower(d, r[2], r[3]));
      const auto t2 = hn::BitCast(dd, hn::InterleaveUpper(d, r[0], r[1]));
      const auto t3 = hn::BitCast(dd, hn::InterleaveUpper(d, r[2], r[3]));
      out[4 * part] = hn::BitCast(d, hn::InterleaveLower(dd, t0, t1));
      out[4 * part + 1] = hn::BitCast(d, hn::InterleaveUpper(dd, t0, t1));
      out[4 * part + 2] = hn::BitCast(d, hn::InterleaveLower(dd, t2, t3));
      out[4 * part + 3] = hn::BitCast(d, hn::InterleaveUpper(dd, t2, t3));
    }
  }
  else
#endif
  {
    HWY_ALIGN float items[8][MaxLanes];
    for (std::size_t l = 0; l < hn::Lanes(d); ++l)
    {
      for (int k = 0; k < 8; ++k)
      {
        items[k][l] = base[offset[l] + k];
      }
    }
    for (int k = 0; k < 8; ++k)
    {
      out[k] = hn::Load(d, items[k]);
    }
  }
}

/**
 * Reads the tables a row per lane (LoadRows8): any interval of the table. The table's
 * entries i and i + 1 are eight consecutive floats (the table is padded past its last
 * entry), and so are the prefix integrals' high and low parts at entry i
 * (PreIntegrationTable::integralsSplit).
 */
struct TableRows
{
  const SegmentTable& t;

  template <class D, class VI>
  HWY_INLINE IntervalLanes<D> Intervals(D d, VI index) const
  {
    HWY_ALIGN std::int32_t offset[MaxLanes];
    hn::Store(hn::ShiftLeft<2>(index), hn::RebindToSigned<D>(), offset);
    hn::Vec<D> items[8]; // r, g, b, tau at entry i, then at entry i + 1
    LoadRows8(d, this->t.table, offset, items);
    IntervalLanes<D> v;
    v.tau = items[3];
    v.dTau = hn::Sub(items[7], items[3]);
    for (int k = 0; k < 3; ++k)
    {
      v.c[k] = items[k];
      v.dC[k] = hn::Sub(items[4 + k], items[k]);
    }
    return v;
  }

  /// The differences of the prefix integrals (T, E_r, E_g, E_b) between entries i1 and i0.
  template <class D, class VI, class V = hn::Vec<D>>
  HWY_INLINE void IntegralsBetween(D d, VI i0, VI i1, V sums[4]) const
  {
    HWY_ALIGN std::int32_t offset0[MaxLanes], offset1[MaxLanes];
    hn::Store(hn::ShiftLeft<3>(i0), hn::RebindToSigned<D>(), offset0);
    hn::Store(hn::ShiftLeft<3>(i1), hn::RebindToSigned<D>(), offset1);
    V at0[8], at1[8]; // high parts of T, E_r, E_g, E_b, then the low parts
    LoadRows8(d, this->t.integrals, offset0, at0);
    LoadRows8(d, this->t.integrals, offset1, at1);
    for (int k = 0; k < 4; ++k)
    {
      sums[k] = hn::Add(hn::Sub(at1[k], at0[k]), hn::Sub(at1[4 + k], at0[4 + k]));
    }
  }
};

/// An entry coordinate as its interval's first entry (clamped to the table's last interval
/// and to 0, as Split does, so that lanes past the end of their segment read inside the table
/// too) and the fraction past it.
template <class D, class V = hn::Vec<D>>
HWY_INLINE void SplitLanes(
  D d, const SegmentTable& t, V u, hn::Vec<hn::RebindToSigned<D>>& index, V& fraction)
{
  const V whole = hn::Max(hn::Zero(d), hn::Min(hn::Floor(u), hn::Set(d, t.lastInterval)));
  index = hn::ConvertTo(hn::RebindToSigned<D>(), whole);
  fraction = hn::Sub(u, whole);
}

/**
 * PieceMeans per lane: the means of tau and c tau over the fractions [fa, fb] of interval v,
 * from the values at the two ends, every term positive.
 */
template <class D, class V = hn::Vec<D>>
HWY_INLINE void PieceMeansLanes(D d, const IntervalLanes<D>& v, V fa, V fb, V& t, V e[3])
{
  const V zero = hn::Zero(d), sixth = hn::Set(d, 1.0f / 6.0f);
  const V ta = hn::Max(zero, hn::MulAdd(fa, v.dTau, v.tau));
  const V tb = hn::Max(zero, hn::MulAdd(fb, v.dTau, v.tau));
  t = hn::Mul(hn::Set(d, 0.5f), hn::Add(ta, tb));
  const V wa = hn::Add(hn::Add(ta, ta), tb), wb = hn::Add(hn::Add(tb, tb), ta);
  for (int k = 0; k < 3; ++k)
  {
    const V ca = hn::MulAdd(fa, v.dC[k], v.c[k]), cb = hn::MulAdd(fb, v.dC[k], v.c[k]);
    e[k] = hn::Mul(sixth, hn::MulAdd(ca, wa, hn::Mul(cb, wb)));
  }
}

/// Lane by lane interval a where `pick` is set, b elsewhere.
template <class D, class M>
HWY_INLINE IntervalLanes<D> PickInterval(
  M pick, const IntervalLanes<D>& a, const IntervalLanes<D>& b)
{
  IntervalLanes<D> v;
  v.tau = hn::IfThenElse(pick, a.tau, b.tau);
  v.dTau = hn::IfThenElse(pick, a.dTau, b.dTau);
  for (int k = 0; k < 3; ++k)
  {
    v.c[k] = hn::IfThenElse(pick, a.c[k], b.c[k]);
    v.dC[k] = hn::IfThenElse(pick, a.dC[k], b.dC[k]);
  }
  return v;
}

/**
 * The means of tau and c tau over [u0, u1] where its ends lie in different intervals
 * (SpanMeans): from the lower end to the end of its interval, the whole intervals between as
 * prefix integrals, from the start of the upper end's interval to it. Lanes whose ends share
 * an interval get 1 / 0 here and are replaced by the caller.
 */
template <class D, class VI, class V = hn::Vec<D>>
HWY_INLINE void MeansAcrossLanes(D d, const TableRows& r, V u0, V u1, VI i0, VI i1, V f0, V f1,
  const IntervalLanes<D>& v0, const IntervalLanes<D>& v1, V& tau, V e[3])
{
  const hn::RebindToSigned<D> di;
  const auto forward = hn::Le(u0, u1);
  const auto forwardIndex = hn::RebindMask(di, forward);
  const V fl = hn::IfThenElse(forward, f0, f1), fh = hn::IfThenElse(forward, f1, f0);
  const VI il = hn::IfThenElse(forwardIndex, i0, i1), ih = hn::IfThenElse(forwardIndex, i1, i0);
  const V one = hn::Set(d, 1.0f);
  V tl, th, el[3], eh[3], sums[4];
  PieceMeansLanes(d, PickInterval(forward, v0, v1), fl, one, tl, el);
  PieceMeansLanes(d, PickInterval(forward, v1, v0), hn::Zero(d), fh, th, eh);
  r.IntegralsBetween(d, hn::Add(il, hn::Set(di, 1)), ih, sums);
  const V wl = hn::Sub(one, fl);
  const V inverse = hn::Div(one, hn::Sub(hn::Max(u0, u1), hn::Min(u0, u1)));
  tau = hn::Mul(hn::MulAdd(wl, tl, hn::MulAdd(fh, th, sums[0])), inverse);
  for (int k = 0; k < 3; ++k)
  {
    e[k] = hn::Mul(hn::MulAdd(wl, el[k], hn::MulAdd(fh, eh[k], sums[1 + k])), inverse);
  }
}

/// One step of a segment per lane, over the entry coordinates [u0, u1] (SpanMeans and the
/// step of Segment): its mean attenuation, its opacity and its colour (not premultiplied).
template <class D, class V = hn::Vec<D>>
struct StepLanes
{
  V tau;       ///< the mean attenuation over the step
  V opacity;   ///< 0 where the step is transparent
  V colour[3]; ///< the attenuation-weighted colour, moved towards the front (see Segment)
};

template <class D, class V = hn::Vec<D>>
HWY_INLINE StepLanes<D> StepOfLanes(D d, const TableRows& r, V u0, V u1, V depth)
{
  hn::Vec<hn::RebindToSigned<D>> i0, i1;
  V f0, f1;
  SplitLanes(d, r.t, u0, i0, f0);
  SplitLanes(d, r.t, u1, i1, f1);
  const auto same = hn::RebindMask(d, hn::Eq(i0, i1));
  const IntervalLanes<D> v0 = r.Intervals(d, i0);
  const bool oneInterval = hn::AllTrue(d, same);
  const IntervalLanes<D> v1 = oneInterval ? v0 : r.Intervals(d, i1);
  StepLanes<D> step;
  V e[3];
  if (!oneInterval)
  {
    MeansAcrossLanes(d, r, u0, u1, i0, i1, f0, f1, v0, v1, step.tau, e);
  }
  if (!hn::AllFalse(d, same))
  {
    // Inside one interval (SpanMeans).
    V tau, inside[3];
    PieceMeansLanes(d, v0, f0, f1, tau, inside);
    step.tau = oneInterval ? tau : hn::IfThenElse(same, tau, step.tau);
    for (int k = 0; k < 3; ++k)
    {
      e[k] = oneInterval ? inside[k] : hn::IfThenElse(same, inside[k], e[k]);
    }
  }
  const auto seen = hn::Gt(step.tau, hn::Zero(d));
  const V stepDepth = hn::IfThenElseZero(seen, hn::Mul(step.tau, depth));
  const V opacity = OpacityOfDensity(d, stepDepth);
  // h(d) = 1/d - 1/(e^d - 1) = 1/d - (1 - a) / a (Segment), its series for thin steps.
  const V one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  const V series = hn::NegMulAdd(stepDepth,
    hn::NegMulAdd(
      hn::Mul(stepDepth, stepDepth), hn::Set(d, 1.0f / 720.0f), hn::Set(d, 1.0f / 12.0f)),
    half);
  const auto thin = hn::Lt(stepDepth, hn::Set(d, static_cast<float>(MTPT_WEIGHT_SERIES_DEPTH)));
  V h = series;
  if (!hn::AllTrue(d, thin))
  {
    // 1/d - (1 - a)/a as one quotient, (a - d (1 - a)) / (d a); where the series is taken
    // instead, the quotient may be 0 / 0.
    const V thick = hn::Div(
      hn::NegMulAdd(stepDepth, hn::Sub(one, opacity), opacity), hn::Mul(stepDepth, opacity));
    h = hn::IfThenElse(thin, series, thick);
  }
  const V shift = hn::Sub(half, h);
  // 1 / tau overflows for a subnormal tau, and a colour integral of 0 times it would be NaN
  // (found by the fuzzer): there tau and the integrals are scaled by 2^64 first, exactly,
  // which leaves their quotient, the mean, as it is. Such lanes are rare: the common vector
  // pays one comparison.
  V tau = step.tau;
  const auto subnormal =
    hn::And(seen, hn::Lt(tau, hn::Set(d, std::numeric_limits<float>::min())));
  if (!hn::AllFalse(d, subnormal))
  {
    const V scale = hn::IfThenElse(subnormal, hn::Set(d, 18446744073709551616.0f), one);
    tau = hn::Mul(tau, scale);
    for (int k = 0; k < 3; ++k)
    {
      e[k] = hn::Mul(e[k], scale);
    }
  }
  const V inverseTau = hn::Div(one, hn::IfThenElse(seen, tau, one));
  for (int k = 0; k < 3; ++k)
  {
    // The colours at the step's ends (LookupEntry), the mean kept in [0, 1] and the colour
    // within the three, as in Segment.
    const V c0 = hn::MulAdd(f0, v0.dC[k], v0.c[k]);
    const V c1 = hn::MulAdd(f1, v1.dC[k], v1.c[k]);
    const V mean = hn::Min(one, hn::Max(hn::Zero(d), hn::Mul(e[k], inverseTau)));
    const V lowest = hn::Min(hn::Min(mean, c0), c1), highest = hn::Max(hn::Max(mean, c0), c1);
    const V c = hn::MulAdd(hn::Sub(c0, c1), shift, mean);
    step.colour[k] = hn::IfThenElseZero(seen, hn::Min(highest, hn::Max(lowest, c)));
  }
  step.opacity = hn::IfThenElseZero(seen, opacity);
  return step;
}

/**
 * PreIntegrationTable::Segment per lane for the segments from scalar front to back of eye
 * length `length`: opacity and colour (not premultiplied; 0 where nothing is seen). The
 * caller checks PreIntegrationTable::Covers.
 */
template <class D, class V = hn::Vec<D>>
HWY_INLINE V SegmentOfLanes(D d, const SegmentTable& t, V front, V back, V length, V colour[3])
{
  const TableRows r{ t };
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  const V ua = ClampedEntryLanes(d, t, front), ub = ClampedEntryLanes(d, t, back);
  const auto drawn = hn::Gt(length, zero);
  const V depth = hn::IfThenElseZero(drawn, hn::Mul(length, hn::Set(d, t.inverseUnit)));
  const StepLanes<D> whole = StepOfLanes(d, r, ua, ub, depth);
  // PreIntegrationSteps per lane: one per PreIntegrationStepDepth of optical depth.
  const V wanted = hn::Ceil(hn::Mul(
    hn::Mul(whole.tau, depth), hn::Set(d, static_cast<float>(1.0 / PreIntegrationStepDepth))));
  const V steps = hn::IfThenElse(hn::Gt(wanted, one),
    hn::Min(wanted, hn::Set(d, static_cast<float>(MaxPreIntegrationSteps))), one);
  if (hn::AllTrue(d, hn::Eq(steps, one)))
  {
    const auto seen = hn::Gt(whole.opacity, zero); // not where the segment has no length
    for (int k = 0; k < 3; ++k)
    {
      colour[k] = hn::IfThenElseZero(seen, whole.colour[k]);
    }
    return whole.opacity;
  }
  // Thick lanes: the steps composited front to back (Segment's loop), each lane its own count.
  const V range = hn::Sub(ub, ua);
  const V stepDepth = hn::Div(depth, steps);
  const int most = static_cast<int>(hn::GetLane(hn::MaxOfLanes(d, steps)));
  V premultiplied[3] = { zero, zero, zero }, alpha = zero;
  for (int s = 0; s < most; ++s)
  {
    const auto active = hn::Lt(hn::Set(d, static_cast<float>(s)), steps);
    const V u0 = hn::Add(ua, hn::Div(hn::Mul(range, hn::Set(d, static_cast<float>(s))), steps));
    const V u1 = hn::Add(ua, hn::Div(hn::Mul(range, hn::Set(d, s + 1.0f)), steps));
    const StepLanes<D> step = StepOfLanes(d, r, u0, u1, stepDepth);
    const V weight = hn::IfThenElseZero(active, hn::Mul(hn::Sub(one, alpha), step.opacity));
    for (int k = 0; k < 3; ++k)
    {
      premultiplied[k] = hn::MulAdd(weight, step.colour[k], premultiplied[k]);
    }
    alpha = hn::Add(alpha, weight);
  }
  // Below the smallest normal float the reciprocal overflows: such a lane deposits nothing
  // a pixel can show, and its colour is taken as zero.
  const auto seen = hn::Gt(alpha, hn::Set(d, std::numeric_limits<float>::min()));
  const V inverse = hn::Div(one, hn::IfThenElse(seen, alpha, one));
  for (int k = 0; k < 3; ++k)
  {
    colour[k] = hn::IfThenElseZero(seen, hn::Mul(premultiplied[k], inverse));
  }
  return alpha;
}

/**
 * The lane permutations that pack the lanes `bits` of a vector into its first lanes and back
 * (WaitingFragments): pack[bits][j] is the lane of the j-th lane of `bits`, unpack[bits][l]
 * the packed position of lane l (the number of lanes of `bits` below it). A table lookup of
 * lanes each way: Highway's Compress on AVX2 copies its own table onto the stack at every
 * call, which cost more than packing saved, and a compressing store to memory is microcoded
 * on some processors (AMD's Zen 4).
 */
struct PackingIndices
{
  std::int32_t pack[1 << MaxLanes][MaxLanes];
  std::int32_t unpack[1 << MaxLanes][MaxLanes];
  constexpr PackingIndices()
    : pack()
    , unpack()
  {
    for (int bits = 0; bits < (1 << MaxLanes); ++bits)
    {
      int below = 0;
      for (int l = 0; l < static_cast<int>(MaxLanes); ++l)
      {
        this->unpack[bits][l] = below;
        if ((bits >> l) & 1)
        {
          this->pack[bits][below++] = l;
        }
      }
    }
  }
};
alignas(64) constexpr PackingIndices Packing;

/**
 * Pre-integrated fragments waiting to be shaded, packed. The vectors of a span or a fan's
 * row cover a third to a half of their lanes, and a segment costs several times what finding
 * it does, so the drawn lanes' segments are packed into full vectors (Wait), shaded a full
 * vector at a time and unpacked into the vectors they came from to be blended there, one
 * vector after another in the order they came (ShadeWaiting): a pixel covered twice is
 * blended as it would be one fragment at a time. The rasterizer shades what waits at the end
 * of each fan, before the next is drawn, so that its opaque pixels hide what lies behind.
 */
struct WaitingFragments
{
  /// Packed lanes at most; shaded when fewer than a vector's worth are left (Full).
  static constexpr int Capacity = 16 * static_cast<int>(MaxLanes);
  /// The lanes' segments, then their opacity and colour; a vector's worth past Capacity for
  /// the whole-vector stores of the packing and the loads of the last vector.
  HWY_ALIGN float front[Capacity + MaxLanes] = {}, back[Capacity + MaxLanes] = {},
                                   length[Capacity + MaxLanes] = {};
  HWY_ALIGN float opacity[Capacity + MaxLanes] = {}, colour[3][Capacity + MaxLanes] = {};
  /// The vectors the lanes came from, in order: tile column, image row, drawn lanes, the
  /// packed position of the first and the lighting of its fan.
  int x[Capacity] = {}, y[Capacity] = {}, first[Capacity] = {};
  std::uint8_t bits[Capacity] = {};
  const LightFactors* light[Capacity] = {};
  int vectors = 0, lanes = 0;
  /// Per tile row, bit i: column i opaque (FanPath's); marked as fragments are blended.
  std::uint64_t* opaque = nullptr;

  bool Full() const { return this->lanes > Capacity - static_cast<int>(MaxLanes); }

  /// Records the vector at tile column x of image row y of `tile` (lit by tile.light) and
  /// packs the segments of its lanes `keep` (some lane set).
  template <class D, class V = hn::Vec<D>>
  HWY_INLINE void Wait(
    D d, const TileTarget& tile, int x, int y, V front, V back, V length, hn::Mask<D> keep)
  {
    std::uint8_t drawn[8] = {};
    hn::StoreMaskBits(d, keep, drawn);
    const hn::RebindToSigned<D> di;
    const auto pack = hn::IndicesFromVec(d, hn::Load(di, Packing.pack[drawn[0]]));
    const int at = this->lanes, v = this->vectors;
    hn::StoreU(hn::TableLookupLanes(front, pack), d, this->front + at);
    hn::StoreU(hn::TableLookupLanes(back, pack), d, this->back + at);
    hn::StoreU(hn::TableLookupLanes(length, pack), d, this->length + at);
    this->lanes += static_cast<int>(hn::CountTrue(d, keep));
    this->Record(v, x, y, drawn[0], at, tile.light);
  }

  /// Wait for one fragment, at tile column x of image row y.
  void WaitOne(const TileTarget& tile, int x, int y, float front, float back, float length)
  {
    const int lanes = static_cast<int>(hn::Lanes(FragmentTag()));
    const int start = std::min(x, T - lanes);
    const int at = this->lanes;
    this->front[at] = front;
    this->back[at] = back;
    this->length[at] = length;
    ++this->lanes;
    this->Record(
      this->vectors, start, y, static_cast<std::uint8_t>(1u << (x - start)), at, tile.light);
  }

private:
  void Record(int v, int x, int y, std::uint8_t drawn, int at, const LightFactors* light)
  {
    this->x[v] = x;
    this->y[v] = y;
    this->bits[v] = drawn;
    this->first[v] = at;
    this->light[v] = light;
    ++this->vectors;
  }
};

/// Marks in `opaque` (per tile row, bit i: column i opaque) the pixels of the vector at tile
/// row j, column x whose alpha is `alpha` that are opaque (OpaqueAlpha).
HWY_INLINE void MarkOpaqueLanes(std::uint64_t* opaque, int j, int x, hn::Vec<FragmentTag> alpha)
{
  const FragmentTag d;
  const auto lanes = hn::Ge(alpha, hn::Set(d, OpaqueAlpha));
  if (!hn::AllFalse(d, lanes)) // mostly none, in a scene that is not opaque anywhere
  {
    std::uint8_t bits[(MaxLanes + 7) / 8] = {};
    hn::StoreMaskBits(d, lanes, bits);
    opaque[j] |= static_cast<std::uint64_t>(bits[0]) << x;
  }
}

/// Shades what waits (WaitingFragments), a full vector at a time, and blends each fragment
/// under the pixel it came from.
inline void ShadeWaiting(const RasterFrame& f, const TileTarget& tile, WaitingFragments& w)
{
  if (w.vectors == 0)
  {
    return;
  }
  const FragmentTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int n = w.lanes;
  for (int l = n; l % lanes != 0; ++l)
  {
    w.front[l] = w.back[l] = w.length[l] = 0.0f; // no segment
  }
  const SegmentTable table(f);
  for (int at = 0; at < n; at += lanes)
  {
    hn::Vec<FragmentTag> colour[3];
    const auto opacity = SegmentOfLanes(d, table, hn::Load(d, w.front + at),
      hn::Load(d, w.back + at), hn::Load(d, w.length + at), colour);
    hn::Store(opacity, d, w.opacity + at);
    for (int k = 0; k < 3; ++k)
    {
      hn::Store(colour[k], d, w.colour[k] + at);
    }
  }
  const hn::RebindToSigned<FragmentTag> di;
  for (int v = 0; v < w.vectors; ++v)
  {
    const int at = w.first[v], x = w.x[v];
    const auto index = hn::IndicesFromVec(d, hn::Load(di, Packing.unpack[w.bits[v]]));
    const auto opacity = hn::TableLookupLanes(hn::LoadU(d, w.opacity + at), index);
    hn::Vec<FragmentTag> colour[3];
    for (int k = 0; k < 3; ++k)
    {
      colour[k] = hn::TableLookupLanes(hn::LoadU(d, w.colour[k] + at), index);
    }
    const auto keep = hn::And(hn::LoadMaskBits(d, &w.bits[v]), hn::Gt(opacity, hn::Zero(d)));
    TileRow row = RowOf(tile, w.y[v]);
    row.light = w.light[v];
    const auto alpha = BlendUnder(d, row, x, opacity, colour, keep);
    if (w.opaque)
    {
      MarkOpaqueLanes(w.opaque, w.y[v] - tile.y0, x, alpha);
    }
  }
  w.vectors = 0;
  w.lanes = 0;
}

/**
 * The eye length of a perspective-exact fragment's segment (Mode::ExactIntegral) from the
 * faces' 1 / w, their difference deltaW = backW - frontW and the eye ray's length per unit of
 * depth: (1 / backW - 1 / frontW) ray = (-deltaW / frontW) / backW ray. Each factor keeps
 * float's relative precision: deltaW however thin the segment is against its depth, where
 * frontW - backW would keep only the last bits of the two; backW however deep the back face
 * lies behind the front one, where frontW + deltaW would keep only the last bits of the two.
 * 0 where that is not a length: where rounding left deltaW above 0, and where it is NaN
 * (planes that vanish in frames of extreme depth ranges).
 */
template <class V>
HWY_INLINE V ExactSegmentLength(V frontW, V backW, V deltaW, V ray)
{
  const V length = hn::Mul(hn::Div(hn::Div(hn::Neg(deltaW), frontW), backW), ray);
  return hn::IfThenElseZero(hn::Gt(length, hn::Zero(hn::DFromV<V>())), length);
}

/// ExactSegmentLength of one fragment, in double precision.
inline double ExactSegmentLength(double frontW, double backW, double deltaW, double ray)
{
  const double length = -deltaW / frontW / backW * ray;
  return length > 0.0 ? length : 0.0;
}

/// A fragment's ray segment: eye depths of its ends, eye length, and the scalars at its ends
/// (pre-integrated shading), from the planes at one pixel, and the pixel centre's NDC.
struct FragmentSegment
{
  double front, back, length, scalarFront = 0, scalarBack = 0, z, ndcX, ndcY;
};

inline FragmentSegment SegmentAt(
  const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p, int x, int y)
{
  const float i = static_cast<float>(x), j = static_cast<float>(y - tile.y0);
  auto value = [&](int k) { return p.base[k] + p.dx[k] * i + p.dy[k] * j; };
  FragmentSegment s;
  s.ndcX = 2.0 * (tile.x0 + x + 0.5) / f.width - 1.0;
  s.ndcY = 2.0 * (y + 0.5) / f.height - 1.0;
  if (mode == Mode::ExactIntegral)
  {
    const double frontW = value(1), backW = value(3), rayX = value(4), rayY = value(5);
    s.front = 1.0 / frontW;
    s.back = 1.0 / backW;
    s.scalarFront = value(0) / frontW;
    s.scalarBack = value(2) / backW;
    s.length =
      ExactSegmentLength(frontW, backW, value(7), std::sqrt(1.0 + rayX * rayX + rayY * rayY));
    s.z = value(6);
    return s;
  }
  const bool compatible = mode == Mode::Compatible;
  s.z = value(compatible ? 5 : 3);
  s.length = value(compatible ? 4 : 2);
  if (!compatible)
  {
    s.scalarFront = value(0);
    s.scalarBack = value(1);
  }
  s.front = f.clipping.EyeDepth(0.5 * (s.z + 1.0));
  s.back = s.front + s.length / f.clipping.RayLength(s.ndcX, s.ndcY);
  return s;
}

/**
 * The part [t0, t1] of fragment `s` at tile column x, row y that is drawn: inside the
 * pixel's depth range (depth peeling) or, without one, in front of the opaque depth; and,
 * for a fan that straddles a clipping plane (`cut`), kept by every plane.
 */
inline bool DrawnPart(const RasterFrame& f, const TileTarget& tile, const TileRow& row,
  const FragmentSegment& s, int x, int y, bool cut, double& t0, double& t1)
{
  if (s.z < -1.0 || s.z > 1.0)
  {
    return false; // clipped by the near or far plane
  }
  t0 = 0.0;
  t1 = 1.0;
  if (tile.range)
  {
    const float* range = tile.range + 2 * (static_cast<std::size_t>(y - tile.y0) * T + x);
    if (!f.clipping.Part(s.front, s.back, range[0], range[1], t0, t1))
    {
      return false;
    }
  }
  else if (row.depth && 0.5 * (s.z + 1.0) > row.depth[x])
  {
    return false; // behind opaque geometry, as every other fragment
  }
  if (!cut)
  {
    return true;
  }
  double front[3], back[3];
  f.clipping.EyePoint(s.ndcX, s.ndcY, s.front, front);
  f.clipping.EyePoint(s.ndcX, s.ndcY, s.back, back);
  return f.planes.Narrow(front, back, t0, t1);
}

/**
 * Depth peeling and clipping planes: the pixels [lo, hi] of row y, each fragment contributing
 * only the part of its segment inside its pixel's range of window depths (TileTarget::range,
 * DepthClipping) and, for a fan that straddles a clipping plane (`cut`), kept by the planes.
 * VTK-compatible fragments keep the segment's colour and attenuation over the part's
 * length; pre-integrated ones are queued with the part's scalars and length. One fragment
 * at a time: peeling frames are few, and their fragments straddle depth boundaries, as
 * straddling fans' fragments straddle a plane.
 */
inline void ShadeClipped(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p,
  int y, int lo, int hi, WaitingFragments& waiting, bool cut)
{
  if (mode != Mode::Compatible && !f.preIntegration->Covers(f.transferFunction))
  {
    return; // every segment transparent
  }
  const TileRow row = RowOf(tile, y);
  for (int x = lo - tile.x0; x <= hi - tile.x0; ++x)
  {
    if (!(row.a[x] < OpaqueAlpha))
    {
      continue; // as ShadeVector and the fan path: nothing behind can show
    }
    const FragmentSegment s = SegmentAt(f, tile, mode, p, x, y);
    double t0, t1;
    if (!DrawnPart(f, tile, row, s, x, y, cut, t0, t1))
    {
      continue;
    }
    const double part = (t1 - t0) * s.length;
    if (mode != Mode::Compatible)
    {
      waiting.WaitOne(tile, x, y,
        static_cast<float>(s.scalarFront + t0 * (s.scalarBack - s.scalarFront)),
        static_cast<float>(s.scalarFront + t1 * (s.scalarBack - s.scalarFront)),
        static_cast<float>(part));
      if (waiting.Full())
      {
        ShadeWaiting(f, tile, waiting);
      }
      continue;
    }
    const float i = static_cast<float>(x), j = static_cast<float>(y - tile.y0);
    auto value = [&](int k) { return p.base[k] + p.dx[k] * i + p.dy[k] * j; };
    const float opacity = static_cast<float>(-std::expm1(-value(3) * part * f.inverseUnit));
    if (!(opacity > 0.0f))
    {
      continue;
    }
    BlendUnderPixel(row, x, opacity, value(0), value(1), value(2));
  }
}

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_SEGMENTS_INL_H_
