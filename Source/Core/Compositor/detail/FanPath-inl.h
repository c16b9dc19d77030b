// SPDX-License-Identifier: BSD-3-Clause
// Internal: the fan path of the compositor's per-tile rasterizer.
//
// VTK-compatible shading of a whole fan at once. The triangle path sets up every triangle of
// a tetrahedron's fan on its own and shades its short spans, a vector each; at 512x512 a
// tetrahedron of the 1.08M-tetrahedron wavelet covers about 15 pixels over 3 or 4 triangles,
// so set-up and idle lanes cost more than the fragments. Here a fan is one convex polygon
// (its silhouette) split into triangles around its centre: each vector of a row is tested
// against the silhouette's edges, and each covered lane takes the values of the triangle it
// lies in, chosen by the spokes (centre to corner) and looked up lane by lane. The per-fan
// work is done a corner or a triangle per lane. The pixels are the triangle path's exactly,
// and each pixel's values are its triangle's up to rounding:
// - both tests are the triangle path's exact fixed-point edge functions (SetUpEdges) with
//   the top-left rule, which counts a point on an edge as if it were moved by (+e, -e^2),
//   e -> 0 (a left edge, inside to the right, owns it; a top edge, inside below, owns it);
//   so a pixel is in the union of the fan's triangles exactly when it is inside every
//   silhouette edge of a convex silhouette, and in triangle k exactly when it is on triangle
//   k's side of spoke k and not on triangle k + 1's side of spoke k + 1. Edge functions are
//   translation-invariant, so they are evaluated relative to the centre, on 32-bit lanes
//   (exact: FanExtentLimit);
// - the corners' values are ValueCorner's (the same table lookups, a corner per lane) and
//   the triangles' planes are set up four at a time in single precision from the same
//   snapped corners: they differ from the triangle path's (SetUpPlanes, in double
//   precision) by rounding, a few units in the last place of a float;
// - the fragment math is ShadeVector's, operation for operation, blended under what the tile
//   holds (BlendUnder; fans come front to back) where it is not yet opaque.
// Pre-integrated shading and the blend modes other than Composite take the same path with
// the corners' scalars instead of their colours (ScalarFanValues): each lane's segment is
// shaded by SegmentOfLanes (TileRaster.cxx) as the triangle path's are, the drawn lanes of
// the fan's vectors packed into full vectors first (WaitingFragments).
// Fans that are not convex, whose centre is not strictly inside (a triangle without area or
// folded over), that reach beyond the fixed-point range or are large (FanExtentLimit), single
// triangles (the slot entry point's), and fans with dependent components' colours take the
// triangle path.
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_FAN_PATH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_FAN_PATH_INL_H_
#undef MTPT_COMPOSITOR_FAN_PATH_INL_H_
#else
#define MTPT_COMPOSITOR_FAN_PATH_INL_H_
#endif

#include "detail/TileRaster.h"

#include "detail/RasterCorners-inl.h"
#include "detail/RasterPixels-inl.h"
#include "detail/Reductions-inl.h"
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

/// Fans at most this large (fixed point, the larger side of the bounding box) take the fan
/// path: over the pixels it tests (the box, widened by a vector's lanes across), every edge
/// function value, at most 2 * 256 W * 256 (W + 9) in magnitude for a box W pixels wide,
/// fits the 32-bit lanes of the coverage test exactly. Larger fans have fragments enough to
/// pay for setting up each triangle.
constexpr std::int64_t FanExtentLimit = 112 * 256;
static_assert(2 * FanExtentLimit * (FanExtentLimit + 9 * 256) < (std::int64_t{ 1 } << 31),
  "edge function values over a fan's box fit 32-bit lanes");

/// The most triangles of a fan (a quadrilateral projection).
constexpr int MaxFanTriangles = 4;

#if HWY_TARGET != HWY_SCALAR

/// Vectors of the per-fan work: one lane per boundary corner, or per triangle.
using CornerTag = hn::CappedTag<float, MaxFanTriangles>;
using CornerIntTag = hn::RebindToSigned<CornerTag>;

/// A fan's geometry in fixed point, relative to its centre: its corners, the edges that bound
/// it (edge k: boundary[k] -> boundary[k + 1]) and its spokes (spoke k: centre ->
/// boundary[k]), each E(p) = A p.x + B p.y + C positive inside its triangle (inside triangle
/// k for spoke k), owning the points on it by the top-left rule (SetUpEdges' rule).
struct FanGeometry
{
  int triangles = 0;
  std::int64_t cx = 0, cy = 0; ///< the centre, fixed point
  HWY_ALIGN std::int32_t x[MaxFanTriangles] = {}, y[MaxFanTriangles] = {}; ///< corners - centre
  HWY_ALIGN std::int32_t nextX[MaxFanTriangles] = {}, nextY[MaxFanTriangles] = {}; ///< corner k + 1
  std::int64_t boundA[MaxFanTriangles], boundB[MaxFanTriangles], boundC[MaxFanTriangles];
  std::int64_t spokeA[MaxFanTriangles], spokeB[MaxFanTriangles];
  std::int32_t cross[MaxFanTriangles]; ///< (boundary[k] - centre) x (boundary[k + 1] - centre)
  int x0, x1, y0, y1;                  ///< pixels of the tile in the fan's box (image)
};

/// The fixed-point window coordinate of NDC `ndc` (Snap, times SubpixelScale); false
/// beyond the fixed-point range (or not finite).
inline bool FixedCoordinate(float ndc, int size, std::int64_t& fixed)
{
  const double v = std::nearbyint((static_cast<double>(ndc) + 1.0) * 0.5 * size * SubpixelScale);
  if (!(std::fabs(v) < FixedPointLimit * SubpixelScale))
  {
    return false;
  }
  fixed = static_cast<std::int64_t>(v);
  return true;
}

/// The pixels of the tile whose centres lie in the box [lo, hi] (fixed point, one axis):
/// [ceil(lo / 256 - 0.5), floor(hi / 256 - 0.5)] within [first, last].
inline void PixelsOfBox(std::int64_t lo, std::int64_t hi, int first, int last, int& p0, int& p1)
{
  const std::int64_t a = -((-(lo - 128)) >> 8), b = (hi - 128) >> 8; // exact floor and ceil
  p0 = static_cast<int>(std::max<std::int64_t>(a, first));
  p1 = static_cast<int>(std::min<std::int64_t>(b, last));
}

/// The corners of `fan` in fixed point relative to its centre, and the tile's pixels in
/// its box; false if the fan is beyond the fixed-point range or FanExtentLimit.
inline bool PlaceFan(const RasterFrame& f, const TileTarget& tile, const Fan& fan, FanGeometry& g)
{
  const int n = fan.count;
  if (!FixedCoordinate(fan.centre.x, f.width, g.cx) ||
    !FixedCoordinate(fan.centre.y, f.height, g.cy))
  {
    return false;
  }
  std::int64_t minX = g.cx, maxX = g.cx, minY = g.cy, maxY = g.cy;
  for (int k = 0; k < n; ++k)
  {
    std::int64_t X, Y;
    if (!FixedCoordinate(fan.boundary[k].x, f.width, X) ||
      !FixedCoordinate(fan.boundary[k].y, f.height, Y))
    {
      return false;
    }
    minX = std::min(minX, X);
    maxX = std::max(maxX, X);
    minY = std::min(minY, Y);
    maxY = std::max(maxY, Y);
    g.x[k] = static_cast<std::int32_t>(X - g.cx); // within FanExtentLimit once checked
    g.y[k] = static_cast<std::int32_t>(Y - g.cy);
  }
  if (std::max(maxX - minX, maxY - minY) > FanExtentLimit)
  {
    return false;
  }
  PixelsOfBox(minX, maxX, tile.x0, tile.x0 + tile.width - 1, g.x0, g.x1);
  PixelsOfBox(minY, maxY, tile.y0, tile.y0 + tile.height - 1, g.y0, g.y1);
  return true;
}

/**
 * The edges of a placed fan of n corners, if the fan path can draw it: every triangle with
 * area and all turning the same way, the silhouette convex (so the centre lies strictly
 * inside it). Products of coordinates relative to the centre are exact in 64 bits.
 */
inline bool FanEdges(int n, FanGeometry& g)
{
  std::int64_t turn[MaxFanTriangles], area[MaxFanTriangles];
  for (int k = 0; k < n; ++k)
  {
    const int next = k + 1 < n ? k + 1 : 0, previous = k > 0 ? k - 1 : n - 1;
    const std::int64_t x = g.x[k], y = g.y[k], xn = g.x[next], yn = g.y[next];
    area[k] = x * yn - y * xn; // triangle (boundary[k], boundary[k + 1], centre)
    turn[k] = (x - g.x[previous]) * (yn - y) - (y - g.y[previous]) * (xn - x);
    g.boundA[k] = y - yn;
    g.boundB[k] = xn - x;
    g.boundC[k] = area[k];
    g.spokeA[k] = -y;
    g.spokeB[k] = x;
    g.nextX[k] = g.x[next];
    g.nextY[k] = g.y[next];
  }
  const std::int64_t sign = area[0] > 0 ? 1 : -1;
  for (int k = 0; k < n; ++k)
  {
    if (area[k] * sign <= 0 || turn[k] * sign < 0)
    {
      return false;
    }
    // Clockwise: every edge reversed, so that the inside is positive.
    g.boundA[k] *= sign;
    g.boundB[k] *= sign;
    g.boundC[k] *= sign;
    g.spokeA[k] *= sign;
    g.spokeB[k] *= sign;
    g.cross[k] = static_cast<std::int32_t>(area[k]);
  }
  g.triangles = n;
  return true;
}

/// One edge function over the lanes of a vector: its values at the lanes (exact, see
/// FanExtentLimit), stepped a row up or a vector right by adding a constant.
template <class D>
struct EdgeLanes
{
  using DI = hn::RebindToSigned<D>;
  hn::Vec<DI> value;   ///< E at the lanes of the current row's first vector
  hn::Vec<DI> least;   ///< least - 1: inside where value > least - 1
  std::int32_t step;   ///< E's change per pixel to the right
  std::int32_t perRow; ///< E's change per row up

  /// The edge A p.x + B p.y + C (relative to the centre) at the lanes of a vector whose
  /// first pixel centre is (sx, sy) from the centre (fixed point); `iota` 0, 1, 2, ...
  void Start(std::int64_t A, std::int64_t B, std::int64_t C, std::int64_t sx, std::int64_t sy,
    hn::Vec<DI> iota)
  {
    const DI di;
    this->step = static_cast<std::int32_t>(A * 256);
    this->perRow = static_cast<std::int32_t>(B * 256);
    this->value = hn::Add(hn::Set(di, static_cast<std::int32_t>(A * sx + B * sy + C)),
      hn::Mul(iota, hn::Set(di, this->step)));
    // Top-left rule (SetUpEdges): the edge owns its points if it goes down, or left.
    this->least = hn::Set(di, A > 0 || (A == 0 && B < 0) ? -1 : 0);
  }

  /// The lanes inside the edge, `offset` pixels right of the row's first vector.
  HWY_INLINE hn::Mask<D> Inside(D d, int offset) const
  {
    const DI di;
    const auto at =
      offset == 0 ? this->value : hn::Add(this->value, hn::Set(di, offset * this->step));
    return hn::RebindMask(d, hn::Gt(at, this->least));
  }

  HWY_INLINE void NextRow() { this->value = hn::Add(this->value, hn::Set(DI(), this->perRow)); }
};

/// A 4-lane vector as a vector of the fragment loops (the lanes past 4 zero).
template <class DF, class V4>
HWY_INLINE hn::Vec<DF> Widen(DF df, V4 v)
{
  if constexpr (hwy::IsSame<hn::Vec<DF>, V4>())
  {
    (void)df;
    return v;
  }
  else
  {
    return hn::ZeroExtendVector(df, v);
  }
}

/// The transpose of the 4 x 4 matrix of rows r[0..3]: out[c] holds column c.
template <class V>
HWY_INLINE void Transpose4(const V r[4], V out[4])
{
  const CornerTag d;
  const hn::Repartition<std::uint64_t, CornerTag> d64;
  const auto t0 = hn::BitCast(d64, hn::InterleaveLower(r[0], r[1])); // r0.0 r1.0 r0.1 r1.1
  const auto t1 = hn::BitCast(d64, hn::InterleaveLower(r[2], r[3]));
  const auto t2 = hn::BitCast(d64, hn::InterleaveUpper(d, r[0], r[1])); // r0.2 r1.2 r0.3 r1.3
  const auto t3 = hn::BitCast(d64, hn::InterleaveUpper(d, r[2], r[3]));
  out[0] = hn::BitCast(d, hn::InterleaveLower(t0, t1));
  out[1] = hn::BitCast(d, hn::InterleaveUpper(d64, t0, t1));
  out[2] = hn::BitCast(d, hn::InterleaveLower(t2, t3));
  out[3] = hn::BitCast(d, hn::InterleaveUpper(d64, t2, t3));
}

/// TransferFunctionTable::Lookup for four scalars at once: out[l] the RGBA of scalar l.
/// The same operations as Lookup's (its constants computed once per tile).
struct TableLookup
{
  const float* table;
  int size;
  float low, scale, last;

  explicit TableLookup(const TransferFunctionTable& tf)
    : table(tf.table)
    , size(tf.size)
    , low(static_cast<float>(tf.low))
    , scale(static_cast<float>((tf.size - 1) / (tf.high > tf.low ? tf.high - tf.low : 1.0)))
    , last(static_cast<float>(tf.size - 1))
  {
  }

  HWY_INLINE void operator()(hn::Vec<CornerTag> scalars, hn::Vec<CornerTag> rgba[4]) const
  {
    const CornerTag d;
    const CornerIntTag di;
    auto t = hn::Mul(hn::Sub(scalars, hn::Set(d, this->low)), hn::Set(d, this->scale));
    t = hn::IfThenElseZero(hn::Gt(t, hn::Zero(d)), hn::Min(t, hn::Set(d, this->last))); // NaN: 0
    const auto i = hn::ConvertTo(di, t);
    HWY_ALIGN std::int32_t at[4], next[4];
    HWY_ALIGN float fraction[4];
    hn::Store(i, di, at);
    hn::Store(hn::Min(hn::Add(i, hn::Set(di, 1)), hn::Set(di, this->size - 1)), di, next);
    hn::Store(hn::Sub(t, hn::ConvertTo(d, i)), d, fraction);
    for (int l = 0; l < 4; ++l)
    {
      const auto a = hn::LoadU(d, this->table + 4 * at[l]);
      const auto b = hn::LoadU(d, this->table + 4 * next[l]);
      rgba[l] = hn::MulAdd(hn::Set(d, fraction[l]), hn::Sub(b, a), a);
    }
  }
};

/**
 * ValueCorner's VTK-compatible values of the fan's corners, one attribute per vector, one
 * corner per lane: value[a] for attribute a (r, g, b, attenuation, length, z) at
 * boundary[l], and the centre's in every lane of centre[a].
 */
inline void FanValues(const TableLookup& lookup, const Fan& fan, hn::Vec<CornerTag> value[6],
  hn::Vec<CornerTag> centre[6])
{
  const CornerTag d;
  // z, front scalar, back scalar, thickness: four consecutive floats of a record.
  static_assert(offsetof(TetVertex, thickness) == offsetof(TetVertex, z) + 3 * sizeof(float),
    "z to thickness are consecutive");
  hn::Vec<CornerTag> records[4], fields[4], rgba[4], back[4];
  for (int k = 0; k < 4; ++k)
  {
    records[k] = hn::LoadU(d, &fan.boundary[k < fan.count ? k : 0].z);
  }
  Transpose4(records, fields); // z, front, back, thickness: a corner per lane
  // Vertex classification: the mean of the table at the front and back scalars.
  lookup(fields[1], rgba);
  if (!hn::AllTrue(d, hn::Eq(fields[1], fields[2])))
  {
    lookup(fields[2], back);
    for (int k = 0; k < 4; ++k)
    {
      rgba[k] = hn::Mul(hn::Set(d, 0.5f), hn::Add(rgba[k], back[k]));
    }
  }
  Transpose4(rgba, value); // r, g, b, attenuation: a corner per lane
  value[4] = fields[3];
  value[5] = fields[0];
  // The centre: its front and back scalars looked up together.
  const auto own = hn::LoadU(d, &fan.centre.z);
  hn::Vec<CornerTag> ends[4];
  lookup(hn::InterleaveLower(hn::Broadcast<1>(own), hn::Broadcast<2>(own)), ends);
  const auto mean = hn::Mul(hn::Set(d, 0.5f), hn::Add(ends[0], ends[1]));
  centre[0] = hn::Broadcast<0>(mean);
  centre[1] = hn::Broadcast<1>(mean);
  centre[2] = hn::Broadcast<2>(mean);
  centre[3] = hn::Broadcast<3>(mean);
  centre[4] = hn::Broadcast<3>(own);
  centre[5] = hn::Broadcast<0>(own);
}

/**
 * Blend modes other than Composite: the fan's corners' values as the triangle path's
 * ValueCorner gives them for `mode`, arranged so that front = value[0] / value[1] and
 * back = value[2] / value[3] (Mode::Integrated: the scalars over 1; Mode::ExactIntegral: the
 * scalars times 1 / w over 1 / w, affine in screen space), value[4] = the segment's length
 * (Mode::Integrated) or the back face's 1 / w less the front face's (Mode::ExactIntegral,
 * whose LaneSegments finds the length from it), value[5] = z.
 */
inline void ScalarFanValues(const RasterFrame& f, Mode mode, const Fan& fan,
  hn::Vec<CornerTag> value[6], hn::Vec<CornerTag> centre[6])
{
  const CornerTag d;
  HWY_ALIGN float corners[6][MaxFanTriangles] = {};
  float own[6] = {};
  for (int k = 0; k <= MaxFanTriangles; ++k)
  {
    Corner c;
    c.vertex = k < MaxFanTriangles ? &fan.boundary[k < fan.count ? k : 0] : &fan.centre;
    ValueCorner(f, mode, c);
    const bool exact = mode == Mode::ExactIntegral;
    const double v[6] = { c.values[0], exact ? c.values[1] : 1.0,
      exact ? c.values[2] : c.values[1], exact ? c.values[3] : 1.0,
      exact ? c.values[7] : c.values[2], exact ? c.values[6] : c.values[3] };
    for (int a = 0; a < 6; ++a)
    {
      (k < MaxFanTriangles ? corners[a][k] : own[a]) = static_cast<float>(v[a]);
    }
  }
  for (int a = 0; a < 6; ++a)
  {
    value[a] = hn::Load(d, corners[a]);
    centre[a] = hn::Set(d, own[a]);
  }
}

/// Double-precision vectors of the plane set-up: a triangle per lane, 4 (or 2) at a time.
using PlaneTag = hn::CappedTag<double, MaxFanTriangles>;

/**
 * The planes of a fan's triangles, arranged for lane lookups: for each attribute, the
 * triangles' values (one triangle per lane) at the centre of the tile's first pixel, per
 * column and per row, and at column 0 of the current row.
 */
struct FanPlanes
{
  HWY_ALIGN float base[6][MaxLanes];
  HWY_ALIGN float dx[6][MaxLanes];
  HWY_ALIGN float dy[6][MaxLanes];
  HWY_ALIGN float start[6][MaxLanes];
  int triangles = 0;
  /// Whether every value and gradient lies within PlaneLimit: a fan's values evaluated
  /// over the tile then stay finite in float. Scalars near the largest float (1e38) or
  /// corners of 1e30 can give planes beyond it; such fans are drawn as triangles.
  bool representable = true;
  static constexpr double PlaneLimit = 1e30;

  /// Every lane 0, before the first SetUp (which writes the first 4 lanes).
  void Clear()
  {
    std::fill(&this->base[0][0], &this->base[0][0] + 6 * MaxLanes, 0.0f);
    std::fill(&this->dx[0][0], &this->dx[0][0] + 6 * MaxLanes, 0.0f);
    std::fill(&this->dy[0][0], &this->dy[0][0] + 6 * MaxLanes, 0.0f);
  }

  /**
   * Triangle k is (boundary[k], boundary[k + 1], centre) = (P0, P1, P2). With e1 = P0 - P2,
   * e2 = P1 - P2 (fixed point) and an attribute's differences d1 = v0 - v2, d2 = v1 - v2,
   * its gradient is (d1 e2.y - d2 e1.y, d2 e1.x - d1 e2.x) / (e1 x e2) per fixed-point unit,
   * 256 times that per pixel, and its value at the tile's first pixel centre o is
   * v2 + gradient . (o - P2). In double precision, as SetUpPlanes: thin triangles have
   * large gradients across them, whose rounding the values far from them would show.
   */
  void SetUp(const TileTarget& tile, const FanGeometry& g, const hn::Vec<CornerTag> value[6],
    const hn::Vec<CornerTag> centre[6])
  {
    const CornerTag d;
    const CornerIntTag di;
    // Lane k + 1 of a corner vector to lane k (the next corner; cyclic over the fan).
    HWY_ALIGN static constexpr std::int32_t rotate3[4] = { 1, 2, 0, 3 },
                                            rotate4[4] = { 1, 2, 3, 0 };
    const auto next = hn::IndicesFromVec(d, hn::Load(di, g.triangles == 3 ? rotate3 : rotate4));
    HWY_ALIGN float here[6][MaxFanTriangles], there[6][MaxFanTriangles], own[6][MaxFanTriangles];
    for (int a = 0; a < 6; ++a)
    {
      hn::Store(value[a], d, here[a]);
      hn::Store(hn::TableLookupLanes(value[a], next), d, there[a]);
      hn::Store(centre[a], d, own[a]);
    }
    const PlaneTag dd;
    const int lanes = static_cast<int>(hn::Lanes(dd));
    this->representable = true;
    for (int k = 0; k < g.triangles; k += lanes)
    {
      this->SetUpLanes(dd, tile, g, k, here, there, own);
    }
    this->triangles = g.triangles;
  }

  /// SetUp's planes of triangles [k, k + Lanes(dd)).
  template <class DD>
  HWY_INLINE void SetUpLanes(DD dd, const TileTarget& tile, const FanGeometry& g, int k,
    const float (*here)[MaxFanTriangles], const float (*there)[MaxFanTriangles],
    const float (*own)[MaxFanTriangles])
  {
    const hn::Rebind<float, DD> df;
    const hn::Rebind<std::int32_t, DD> di;
    auto promote = [&](const std::int32_t* v) { return hn::PromoteTo(dd, hn::LoadU(di, v + k)); };
    const auto e1x = promote(g.x), e1y = promote(g.y), e2x = promote(g.nextX),
               e2y = promote(g.nextY);
    // 256 / (e1 x e2); lanes past the triangles (zero vectors) divide by 1 instead of 0.
    const auto cross = hn::Sub(hn::Mul(e1x, e2y), hn::Mul(e1y, e2x));
    const auto perPixel = hn::Div(
      hn::Set(dd, 256.0), hn::IfThenElse(hn::Eq(cross, hn::Zero(dd)), hn::Set(dd, 1.0), cross));
    const auto ox = hn::Set(dd, (tile.x0 * 256.0 + 128 - static_cast<double>(g.cx)) / 256);
    const auto oy = hn::Set(dd, (tile.y0 * 256.0 + 128 - static_cast<double>(g.cy)) / 256);
    const auto limit = hn::Set(dd, PlaneLimit);
    auto within = hn::Eq(limit, limit); // NaN compares false below, so it is not within
    for (int a = 0; a < 6; ++a)
    {
      const auto v2 = hn::PromoteTo(dd, hn::LoadU(df, own[a] + k));
      const auto d1 = hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, here[a] + k)), v2);
      const auto d2 = hn::Sub(hn::PromoteTo(dd, hn::LoadU(df, there[a] + k)), v2);
      const auto gx = hn::Mul(hn::Sub(hn::Mul(d1, e2y), hn::Mul(d2, e1y)), perPixel);
      const auto gy = hn::Mul(hn::Sub(hn::Mul(d2, e1x), hn::Mul(d1, e2x)), perPixel);
      const auto base = hn::MulAdd(gy, oy, hn::MulAdd(gx, ox, v2));
      within = hn::And(within,
        hn::And(hn::Le(hn::Abs(base), limit),
          hn::And(hn::Le(hn::Abs(gx), limit), hn::Le(hn::Abs(gy), limit))));
      hn::StoreU(hn::DemoteTo(df, base), df, this->base[a] + k);
      hn::StoreU(hn::DemoteTo(df, gx), df, this->dx[a] + k);
      hn::StoreU(hn::DemoteTo(df, gy), df, this->dy[a] + k);
    }
    // Lanes past the fan's triangles hold zero vectors: their planes are 0.
    this->representable = this->representable && hn::AllTrue(dd, within);
  }

  /// Each triangle's values at column 0 of tile row j (RowStart's).
  template <class D>
  HWY_INLINE void Row(D d, int j)
  {
    const auto row = hn::Set(d, static_cast<float>(j));
    for (int a = 0; a < 6; ++a)
    {
      hn::Store(
        hn::MulAdd(hn::Load(d, this->dy[a]), row, hn::Load(d, this->base[a])), d, this->start[a]);
    }
  }
};

/// ShadeVector's fragment math on values given per lane: r, g, b, attenuation, length, z.
/// Returns the lanes' alpha after it (BlendUnder).
template <class D>
HWY_INLINE hn::Vec<D> ShadeLanes(
  D d, const RasterFrame& f, const TileRow& row, int x, const hn::Vec<D> value[6], hn::Mask<D> keep)
{
  const auto one = hn::Set(d, 1.0f);
  const auto z = value[5];
  keep = hn::And(keep, hn::And(hn::Ge(z, hn::Set(d, -1.0f)), hn::Le(z, one)));
  if (row.depth)
  {
    const auto depth = hn::MulAdd(z, hn::Set(d, 0.5f), hn::Set(d, 0.5f));
    keep = hn::And(keep, hn::Le(depth, hn::LoadU(d, row.depth + x)));
  }
  const auto opacity =
    OpacityOfDensity(d, hn::Mul(hn::Mul(value[3], value[4]), hn::Set(d, f.inverseUnit)));
  keep = hn::And(keep, hn::Gt(opacity, hn::Zero(d)));
  return BlendUnder(d, row, x, opacity, value, keep);
}

/// The triangle each lane lies in (of the lanes inside the silhouette): triangle k when the
/// lane is on its side of spoke k and not on triangle k + 1's side of spoke k + 1.
template <class D>
HWY_INLINE hn::Vec<hn::RebindToSigned<D>> TriangleOfLanes(
  D d, const EdgeLanes<D>* spokes, int triangles, int offset)
{
  const hn::RebindToSigned<D> di;
  auto index = hn::Zero(di);
  hn::Mask<D> side[MaxFanTriangles + 1];
  for (int k = 0; k < triangles; ++k)
  {
    side[k] = spokes[k].Inside(d, offset);
  }
  side[triangles] = side[0];
  for (int k = 1; k < triangles; ++k)
  {
    const auto in = hn::AndNot(side[k + 1], side[k]);
    index = hn::IfThenElse(hn::RebindMask(di, in), hn::Set(di, k), index);
  }
  return index;
}

/// The values of the vector at tile column x, `offset` columns right of the row's first
/// vector: each lane's from the planes of the triangle it lies in.
template <class D>
HWY_INLINE void FanLaneValues(
  D d, const FanPlanes& p, const EdgeLanes<D>* spokes, int x, int offset, hn::Vec<D> value[6])
{
  const auto i = hn::Iota(d, static_cast<float>(x));
  const auto which = hn::IndicesFromVec(d, TriangleOfLanes(d, spokes, p.triangles, offset));
  for (int a = 0; a < 6; ++a)
  {
    const auto dx = hn::TableLookupLanes(hn::Load(d, p.dx[a]), which);
    const auto start = hn::TableLookupLanes(hn::Load(d, p.start[a]), which);
    value[a] = hn::MulAdd(dx, i, start);
  }
}

/// Shades the lanes `keep` of the vector at tile column x of row `row`, `offset` columns
/// right of the row's first vector: each lane with the values of its triangle's planes.
/// Returns the lanes' alpha after it.
template <class D>
HWY_INLINE hn::Vec<D> ShadeFanLanes(D d, const RasterFrame& f, const TileRow& row,
  const FanPlanes& p, const EdgeLanes<D>* spokes, int x, int offset, hn::Mask<D> keep)
{
  hn::Vec<D> value[6];
  FanLaneValues(d, p, spokes, x, offset, value);
  return ShadeLanes(d, f, row, x, value, keep);
}

/**
 * The ray segments of the lanes of the vector at tile column x of tile row y (image), from
 * the values of their triangles' planes (ScalarFanValues): the scalars at the front and the
 * back and, unless `scalarsOnly`, the segment's eye length.
 */
template <class D>
HWY_INLINE void LaneSegments(D d, const RasterFrame& f, const TileTarget& tile, Mode mode,
  const hn::Vec<D> value[6], int x, int y, bool scalarsOnly, hn::Vec<D>& front, hn::Vec<D>& back,
  hn::Vec<D>& length)
{
  // Mode::Integrated's denominators are 1.
  front = mode == Mode::ExactIntegral ? hn::Div(value[0], value[1]) : value[0];
  back = mode == Mode::ExactIntegral ? hn::Div(value[2], value[3]) : value[2];
  length = value[4];
  if (mode == Mode::ExactIntegral && !scalarsOnly)
  {
    // The eye ray through the lanes' pixel centres (PerspectiveInterpolation), and the
    // segment between the faces' depths 1 / value[1] and 1 / value[3].
    const PerspectiveInterpolation& view = f.interpolation;
    const auto i = hn::Iota(d, static_cast<float>(x));
    const auto ndcX = hn::MulAdd(
      hn::Add(i, hn::Set(d, tile.x0 + 0.5f)), hn::Set(d, 2.0f / f.width), hn::Set(d, -1.0f));
    const float ndcY = 2.0f * (y + 0.5f) / f.height - 1.0f;
    const auto rayX = hn::Mul(hn::Add(ndcX, hn::Set(d, static_cast<float>(view.shiftX))),
      hn::Set(d, static_cast<float>(view.scaleX)));
    const auto rayY = hn::Set(d, static_cast<float>((ndcY + view.shiftY) * view.scaleY));
    const auto ray = hn::Sqrt(hn::MulAdd(rayX, rayX, hn::MulAdd(rayY, rayY, hn::Set(d, 1.0f))));
    length = ExactSegmentLength(value[1], value[3], value[4], ray);
  }
}

/**
 * A blend mode other than Composite: folds the lanes `keep` of the vector at tile column x
 * of tile row y (image), `offset` columns right of the row's first vector, each with the
 * values of its triangle's planes (ScalarFanValues).
 */
template <class D>
HWY_INLINE void ReduceFanLanes(D d, const RasterFrame& f, const TileTarget& tile, Mode mode,
  const TileRow& row, const FanPlanes& p, const EdgeLanes<D>* spokes, int x, int y, int offset,
  hn::Mask<D> keep)
{
  hn::Vec<D> value[6];
  FanLaneValues(d, p, spokes, x, offset, value);
  const bool extremes =
    f.blendMode == BlendMode::MaximumIntensity || f.blendMode == BlendMode::MinimumIntensity;
  hn::Vec<D> front, back, length;
  LaneSegments(d, f, tile, mode, value, x, y, extremes, front, back, length);
  if (extremes)
  {
    FoldExtremes(d, f, row, x, front, back, value[5], keep);
    return;
  }
  FoldIntegrals(d, f, row, x, front, back, length, value[5], keep);
}

/**
 * The segments of the lanes `keep` of the vector at tile column x of tile row y (image),
 * `offset` columns right of the row's first vector, from their triangles' planes
 * (ScalarFanValues), waiting to be shaded (WaitingFragments) where they are inside the depth
 * range.
 */
template <class D>
HWY_INLINE void WaitFanLanes(D d, const RasterFrame& f, const TileTarget& tile, Mode mode,
  const TileRow& row, const FanPlanes& p, const EdgeLanes<D>* spokes, int x, int y, int offset,
  hn::Mask<D> keep, WaitingFragments& waiting)
{
  hn::Vec<D> value[6];
  FanLaneValues(d, p, spokes, x, offset, value);
  const auto z = value[5];
  keep = hn::And(keep, hn::And(hn::Ge(z, hn::Set(d, -1.0f)), hn::Le(z, hn::Set(d, 1.0f))));
  if (row.depth)
  {
    const auto depth = hn::MulAdd(z, hn::Set(d, 0.5f), hn::Set(d, 0.5f));
    keep = hn::And(keep, hn::Le(depth, hn::LoadU(d, row.depth + x)));
  }
  if (hn::AllFalse(d, keep))
  {
    return; // clipped or behind opaque geometry: no segment to shade
  }
  hn::Vec<D> front, back, length;
  LaneSegments(d, f, tile, mode, value, x, y, false, front, back, length);
  waiting.Wait(d, tile, x, y, front, back, length, keep);
}

/**
 * The fan path over one tile (see the file comment): what the tile's fans share, and Draw.
 * Thread safety: one object per tile being drawn.
 */
class FanPath
{
public:
  /// `waiting`: the tile's pre-integrated fragments, the fan path's and the triangle
  /// path's, shaded in the order they came (WaitingFragments).
  FanPath(const RasterFrame& f, const TileTarget& tile, Mode mode, WaitingFragments& waiting)
    : Frame(f)
    , Target(tile)
    , Waiting(waiting)
    , Lookup(f.transferFunction)
    , FanMode(mode)
    , Reduces(ReducesInAnyOrder(f.blendMode))
    , Integrates(!this->Reduces && mode != Mode::Compatible)
    , Applies(f.fanPath && !f.vertexColours && !f.clipToRange &&
        hn::Lanes(FragmentTag()) >= MaxFanTriangles &&
        (!this->Integrates || f.preIntegration->Covers(f.transferFunction)))
  {
    this->Planes.Clear();
    if (this->Applies)
    {
      this->Waiting.opaque = this->Opaque; // pre-integrated fragments mark what they make opaque
    }
    for (int j = 0; j < T && this->Applies; ++j)
    {
      this->Opaque[j] = 0;
      for (int x = 0; x < T && !this->Reduces; x += static_cast<int>(hn::Lanes(FragmentTag())))
      {
        this->MarkOpaque(j, x, hn::LoadU(FragmentTag(), this->Target.rgba + 3 * T * T + j * T + x));
      }
    }
  }

  /**
   * VTK-compatible or pre-integrated shading of `fan` into the tile, or its reduction in a
   * blend mode other than Composite, as its triangles would be drawn. Returns false, having
   * drawn nothing, when the fan path does not apply or the fan's planes are not
   * representable in float: the caller draws the triangles instead.
   */
  bool Draw(const Fan& fan, RasterCounts& counts)
  {
    FanGeometry g;
    if (!this->Applies || !fan.closed || fan.count < 3 ||
      !PlaceFan(this->Frame, this->Target, fan, g))
    {
      return false;
    }
    if (g.x0 > g.x1 || g.y0 > g.y1)
    {
      return true; // no pixel centre of the tile in the box: nothing to draw either way
    }
    if (this->Hidden(g))
    {
      ++counts.hidden;
      return true; // every pixel of its box opaque: nothing of it can show
    }
    if (!FanEdges(fan.count, g))
    {
      return false;
    }
    return this->Rows(fan, g, counts);
  }

private:
  /// The rows of the fan's box in the tile, vector by vector; false, having drawn and
  /// counted nothing, if its planes are not representable.
  bool Rows(const Fan& fan, const FanGeometry& g, RasterCounts& counts)
  {
    const RasterCounts before = counts;
    const FragmentTag d;
    const int lanes = static_cast<int>(hn::Lanes(d));
    const TileTarget& tile = this->Target;
    const int first = g.x0 - tile.x0, last = g.x1 - tile.x0;
    // Vectors start at the box's first column, the last moved back so as not to reach past
    // the row's end (see ShadeCompatible); the edges are evaluated from the first one.
    const int start = std::min(first, T - lanes);
    EdgeLanes<FragmentTag> bounding[MaxFanTriangles], spokes[MaxFanTriangles];
    StartEdges(g, tile.x0 + start, bounding, spokes);
    bool ready = false;
    const auto lastLane = hn::Set(d, static_cast<float>(last));
    for (int y = g.y0; y <= g.y1; ++y)
    {
      const TileRow row = RowOf(tile, y);
      bool rowReady = false;
      for (int from = first; from <= last; from += lanes)
      {
        const int x = std::min(from, T - lanes);
        const auto i = hn::Iota(d, static_cast<float>(x));
        auto keep = hn::And(hn::Ge(i, hn::Set(d, static_cast<float>(from))), hn::Le(i, lastLane));
        for (int k = 0; k < g.triangles; ++k)
        {
          keep = hn::And(keep, bounding[k].Inside(d, x - start));
        }
        const std::size_t covered = hn::CountTrue(d, keep);
        counts.fragments += covered;
        ++counts.fanVectors;
        // Fragments behind opaque pixels are skipped; a fan all behind them is not set up.
        // (In a reduction the alpha plane says only that a fragment came.)
        keep = this->Reduces ? keep : hn::And(keep, Transparent(d, row, x));
        if (hn::AllFalse(d, keep))
        {
          continue;
        }
        if (!ready)
        {
          ShadeWaiting(this->Frame, tile, this->Waiting); // what came before, first
          if (!this->SetUp(fan, g))
          {
            counts = before;
            return false;
          }
          ready = true;
          counts.triangles += static_cast<std::size_t>(g.triangles);
        }
        if (!rowReady)
        {
          this->Planes.Row(d, y - tile.y0);
          rowReady = true;
        }
        this->DrawLanes(row, spokes, x, y, x - start, keep);
      }
      for (int k = 0; k < g.triangles; ++k)
      {
        bounding[k].NextRow();
        spokes[k].NextRow();
      }
    }
    ShadeWaiting(this->Frame, tile, this->Waiting); // before the next fan is drawn
    return true;
  }

  /// The edges of the fan's box at its first row, from window column `x` (a vector's lanes
  /// across): its silhouette's (`bounding`) and its spokes.
  static HWY_INLINE void StartEdges(const FanGeometry& g, int x,
    EdgeLanes<FragmentTag> bounding[MaxFanTriangles],
    EdgeLanes<FragmentTag> spokes[MaxFanTriangles])
  {
    const auto iota = hn::Iota(hn::RebindToSigned<FragmentTag>(), 0);
    const std::int64_t sx = x * std::int64_t{ 256 } + 128 - g.cx;
    const std::int64_t sy = g.y0 * std::int64_t{ 256 } + 128 - g.cy;
    for (int k = 0; k < g.triangles; ++k)
    {
      bounding[k].Start(g.boundA[k], g.boundB[k], g.boundC[k], sx, sy, iota);
      spokes[k].Start(g.spokeA[k], g.spokeB[k], 0, sx, sy, iota);
    }
  }

  /// The lanes `keep` of the vector at tile column x of window row y (`column` from the box's
  /// first vector, the spokes' origin), the fan set up: reduced, shaded, or left waiting to
  /// be shaded, by the fan's mode.
  HWY_INLINE void DrawLanes(const TileRow& row, const EdgeLanes<FragmentTag>* spokes, int x, int y,
    int column, hn::Mask<FragmentTag> keep)
  {
    const FragmentTag d;
    const TileTarget& tile = this->Target;
    if (this->Reduces)
    {
      ReduceFanLanes(
        d, this->Frame, tile, this->FanMode, row, this->Planes, spokes, x, y, column, keep);
      return;
    }
    if (!this->Integrates)
    {
      this->MarkOpaque(
        y - tile.y0, x, ShadeFanLanes(d, this->Frame, row, this->Planes, spokes, x, column, keep));
      return;
    }
    WaitFanLanes(d, this->Frame, tile, this->FanMode, row, this->Planes, spokes, x, y, column, keep,
      this->Waiting);
    if (this->Waiting.Full())
    {
      ShadeWaiting(this->Frame, tile, this->Waiting);
    }
  }

  /// Marks the opaque pixels among the vector's at tile row j, column x, whose alpha is `alpha`.
  HWY_INLINE void MarkOpaque(int j, int x, hn::Vec<FragmentTag> alpha)
  {
    MarkOpaqueLanes(this->Opaque, j, x, alpha);
  }

  /// Whether every pixel of the fan's box in the tile is opaque (Opaque is conservative: only
  /// the fan path and the pre-integrated fragments (WaitingFragments) mark what they make
  /// opaque, besides what was opaque when the tile started).
  bool Hidden(const FanGeometry& g) const
  {
    const int first = g.x0 - this->Target.x0, width = g.x1 - g.x0 + 1;
    const std::uint64_t span =
      (width >= T ? ~std::uint64_t{ 0 } : ((std::uint64_t{ 1 } << width) - 1)) << first;
    for (int y = g.y0; y <= g.y1; ++y)
    {
      if ((this->Opaque[y - this->Target.y0] & span) != span)
      {
        return false;
      }
    }
    return true;
  }

  /// The corners' values and the triangles' planes, once the fan covers a pixel; false if
  /// the planes are not representable (FanPlanes::representable).
  bool SetUp(const Fan& fan, const FanGeometry& g)
  {
    hn::Vec<CornerTag> value[6], centre[6];
    if (this->FanMode != Mode::Compatible)
    {
      ScalarFanValues(this->Frame, this->FanMode, fan, value, centre);
    }
    else
    {
      FanValues(this->Lookup, fan, value, centre);
    }
    this->Planes.SetUp(this->Target, g, value, centre);
    return this->Planes.representable;
  }

  const RasterFrame& Frame;
  const TileTarget& Target;
  WaitingFragments& Waiting;
  const TableLookup Lookup;
  const Mode FanMode;
  const bool Reduces;    ///< a blend mode other than Composite
  const bool Integrates; ///< pre-integrated shading (else, composite: VTK-compatible)
  const bool Applies;
  FanPlanes Planes;
  std::uint64_t Opaque[T]; ///< per tile row, bit i: column i opaque (OpaqueAlpha)
};

#else // HWY_SCALAR: one lane, no lookups across lanes; every fan takes the triangle path

class FanPath
{
public:
  FanPath(const RasterFrame&, const TileTarget&, Mode, WaitingFragments&) {}
  bool Draw(const Fan&, RasterCounts&) { return false; }
};

#endif

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_FAN_PATH_INL_H_
