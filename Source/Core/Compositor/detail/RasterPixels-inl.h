// SPDX-License-Identifier: BSD-3-Clause
// Internal: the rasterizer's pixels. A tile's rows, a fragment's opacity from its density,
// the blending of fragments under what a tile holds (front to back), and VTK-compatible
// shading of a vector of a row from a triangle's planes, the OpenGL path's fragment math.
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_RASTER_PIXELS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_RASTER_PIXELS_INL_H_
#undef MTPT_COMPOSITOR_RASTER_PIXELS_INL_H_
#else
#define MTPT_COMPOSITOR_RASTER_PIXELS_INL_H_
#endif

#include "mtpt/OpaquePixels.h"

#include "detail/TileRaster.h"

#include "detail/RasterCorners-inl.h"

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

/// The tile's row y (image coordinates) of each plane.
struct TileRow
{
  float* r;
  float* g;
  float* b;
  float* a;
  const float* depth;        ///< null: no opaque depth
  const LightFactors* light; ///< the fan's lighting (TileTarget::light); null: unlit
};

inline TileRow RowOf(const TileTarget& tile, int y)
{
  const int j = y - tile.y0;
  float* r = tile.rgba + j * T;
  return { r, r + T * T, r + 2 * T * T, r + 3 * T * T, tile.depth ? tile.depth + j * T : nullptr,
    tile.light };
}

/// The vector type of the fragment loops: 8 lanes where the processor has them (AVX2 and
/// AVX-512 alike: wider vectors only add idle lanes to the short spans of small triangles).
using FragmentTag = hn::CappedTag<float, 8>;
constexpr std::size_t MaxLanes = 8;

/**
 * A fragment's opacity 1 - exp(-density), with no cancellation for thin segments: with
 * -density = q ln 2 + r (q whole, |r| <= ln 2 / 2) and s = 2^q, it is (1 - s) - s expm1(r),
 * which for q = 0 is -expm1(r) itself and otherwise subtracts nothing close. expm1(r) is its
 * Taylor polynomial of degree 7 (the remainder is below 2e-8 relative on that interval),
 * evaluated as r times pairs of terms in powers of r^2 (Estrin's scheme); the
 * densities are clamped to [-87, 88], where 2^q is a normal float and the opacity already 1
 * in float at the top. NaN stays NaN. Within 4 units in the last place of the float result
 * (tested against std::expm1 by the core tests through OpacitiesOfDensities), at about half
 * the operations of a general exponential.
 */
template <class D, class V>
HWY_INLINE V OpacityOfDensity(D d, V density)
{
  const hn::RebindToSigned<D> di;
  const V x = hn::Min(hn::Max(density, hn::Set(d, -87.0f)), hn::Set(d, 88.0f));
  const V q = hn::Round(hn::Mul(x, hn::Set(d, -1.44269504088896341f)));
  // r = -x - q ln 2, ln 2 in two parts (Cody and Waite) so that q ln 2 is exact enough.
  const V r = hn::NegMulAdd(
    q, hn::Set(d, 1.42860682e-6f), hn::NegMulAdd(q, hn::Set(d, 0.693145752f), hn::Neg(x)));
  // The degree-6 polynomial in powers of r^2 (three pairs) rather than Horner's seven steps:
  // a shorter chain of dependent multiply-adds in the fragment loop.
  const V r2 = hn::Mul(r, r);
  const V e0 = hn::MulAdd(hn::Set(d, 0.5f), r, hn::Set(d, 1.0f));
  const V e1 = hn::MulAdd(hn::Set(d, 1.0f / 24), r, hn::Set(d, 1.0f / 6));
  const V e2 = hn::MulAdd(hn::Set(d, 1.0f / 720), r, hn::Set(d, 1.0f / 120));
  V p = hn::MulAdd(hn::Set(d, 1.0f / 5040), r2, e2);
  p = hn::MulAdd(p, r2, e1);
  p = hn::MulAdd(p, r2, e0);
  p = hn::Mul(p, r); // expm1(r)
  const V s = hn::BitCast(d, hn::ShiftLeft<23>(hn::Add(hn::ConvertTo(di, q), hn::Set(di, 127))));
  const V opacity = hn::NegMulAdd(s, p, hn::Sub(hn::Set(d, 1.0f), s));
  return hn::IfThenElse(hn::Eq(density, density), opacity, density);
}

/**
 * A pixel whose coverage alpha reached mtpt::OpaqueAlpha (OpaquePixels.h) hides what lies
 * behind it: fragments drawn there later (farther: fans are drawn front to back) are
 * skipped. They could add at most 2^-11 of full intensity to the pixel, an eighth of an
 * 8-bit step.
 */
using mtpt::OpaqueAlpha;

/// The lanes of the vector at tile column x of `row` that are not yet opaque.
template <class D>
HWY_INLINE hn::Mask<D> Transparent(D d, const TileRow& row, int x)
{
  return hn::Lt(hn::LoadU(d, row.a + x), hn::Set(d, OpaqueAlpha));
}

/**
 * Blends fragments of opacity a and colour c under what the lanes `keep` of the vector at
 * tile column x of `row` hold (premultiplied colour C, coverage alpha A), front to back:
 * C += (1 - A) a c, A += (1 - A) a, with c lit first by the row's fan (TileRow::light:
 * clamp(scale c + offset, 0, 1)). Back to front with OpenGL's blending (VTK's PT's, over)
 * gives the same image up to rounding. Returns the lanes' alpha after the blend: a caller that
 * reads it again gets it from a register, not from the store just made (a masked store, which
 * the processor cannot forward to a load).
 */
template <class D>
HWY_INLINE hn::Vec<D> BlendUnder(
  D d, const TileRow& row, int x, hn::Vec<D> opacity, const hn::Vec<D> colour[3], hn::Mask<D> keep)
{
  const auto alpha = hn::LoadU(d, row.a + x);
  const auto weight = hn::Mul(hn::Sub(hn::Set(d, 1.0f), alpha), opacity);
  float* planes[3] = { row.r, row.g, row.b };
  for (int k = 0; k < 3; ++k)
  {
    auto c = colour[k];
    if (row.light)
    {
      c = hn::MulAdd(hn::Set(d, row.light->scale[k]), c, hn::Set(d, row.light->offset[k]));
      c = hn::Min(hn::Max(c, hn::Zero(d)), hn::Set(d, 1.0f));
    }
    const auto in = hn::LoadU(d, planes[k] + x);
    hn::StoreU(hn::IfThenElse(keep, hn::MulAdd(weight, c, in), in), d, planes[k] + x);
  }
  const auto blended = hn::IfThenElse(keep, hn::Add(alpha, weight), alpha);
  hn::StoreU(blended, d, row.a + x);
  return blended;
}

/// BlendUnder for one pixel: a fragment of opacity a and colour (r, g, b), lit as there,
/// under what pixel x of `row` holds.
inline void BlendUnderPixel(const TileRow& row, int x, float a, float r, float g, float b)
{
  if (row.light)
  {
    const LightFactors& l = *row.light;
    auto lit = [](float s, float c, float o) { return std::min(std::max(s * c + o, 0.0f), 1.0f); };
    r = lit(l.scale[0], r, l.offset[0]);
    g = lit(l.scale[1], g, l.offset[1]);
    b = lit(l.scale[2], b, l.offset[2]);
  }
  const float weight = (1.0f - row.a[x]) * a;
  row.r[x] += weight * r;
  row.g[x] += weight * g;
  row.b[x] += weight * b;
  row.a[x] += weight;
}

/// VTK-compatible shading of the lanes `keep` of the vector at tile column x of `row`, with
/// the OpenGL path's fragment math. start[k]: plane k at the row's column 0.
template <class D>
void ShadeVector(D d, const RasterFrame& f, const TileRow& row, const Planes& p,
  const float start[6], int x, hn::Mask<D> keep)
{
  const auto one = hn::Set(d, 1.0f);
  const auto i = hn::Iota(d, static_cast<float>(x));
  const auto z = hn::MulAdd(hn::Set(d, p.dx[5]), i, hn::Set(d, start[5]));
  keep = hn::And(keep, hn::And(hn::Ge(z, hn::Set(d, -1.0f)), hn::Le(z, one)));
  if (row.depth)
  {
    const auto depth = hn::MulAdd(z, hn::Set(d, 0.5f), hn::Set(d, 0.5f));
    keep = hn::And(keep, hn::Le(depth, hn::LoadU(d, row.depth + x)));
  }
  keep = hn::And(keep, Transparent(d, row, x));
  if (hn::AllFalse(d, keep))
  {
    return;
  }
  const auto attenuation = hn::MulAdd(hn::Set(d, p.dx[3]), i, hn::Set(d, start[3]));
  const auto length = hn::MulAdd(hn::Set(d, p.dx[4]), i, hn::Set(d, start[4]));
  const auto opacity =
    OpacityOfDensity(d, hn::Mul(hn::Mul(attenuation, length), hn::Set(d, f.inverseUnit)));
  keep = hn::And(keep, hn::Gt(opacity, hn::Zero(d)));
  hn::Vec<D> colour[3];
  for (int k = 0; k < 3; ++k)
  {
    colour[k] = hn::MulAdd(hn::Set(d, p.dx[k]), i, hn::Set(d, start[k]));
  }
  BlendUnder(d, row, x, opacity, colour, keep);
}

/// The planes' values at column 0 of tile row j.
inline void RowStart(const Planes& p, int j, float start[6])
{
  for (int k = 0; k < 6; ++k)
  {
    start[k] = p.base[k] + p.dy[k] * static_cast<float>(j);
  }
}

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_RASTER_PIXELS_INL_H_
