// SPDX-License-Identifier: BSD-3-Clause
// The compositor's per-tile rasterizer (detail/TileRaster.h). Google Highway compiles this
// file once per instruction set (foreach_target.h includes it again for each); the
// dispatch at the end picks the best the processor has, once per tile.
//
// Per triangle: vertices snapped to 1/256 pixel; coverage from exact 64-bit edge functions,
// as the row spans they bound (no per-pixel test); attributes as planes over the tile, set
// up in double precision from the snapped vertices and evaluated in float relative to the
// tile's corner. A triangle with a vertex beyond the fixed-point range is clipped to a
// guard band first; its planes stay those of the whole triangle.
#include "detail/TileRaster.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "TileRaster.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

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

constexpr int T = TileSize;
static_assert(T % 8 == 0, "tile rows hold whole vectors of the widest lane count used");
/// Sub-pixel precision of the fixed-point rasterizer (as GPUs and Mesa snap vertices).
constexpr double SubpixelScale = 256.0;
/// Window coordinates within +-2^22 pixels keep every edge-function product below 2^62.
constexpr double FixedPointLimit = 4194304.0;
/// Triangles reaching beyond the fixed-point range are clipped this far around the image.
constexpr double GuardBand = 1 << 20;
/// Attributes interpolated per triangle, at most.
constexpr int MaxAttributes = 7;

/// What is interpolated, per shading mode (the layout of Corner::values and Planes).
enum class Mode
{
  Compatible,   ///< r, g, b, attenuation, length, z
  Integrated,   ///< front scalar, back scalar, length, z (linear in screen space)
  ExactIntegral ///< front scalar / w, 1 / w, back scalar / w, 1 / w, ray x, ray y, z
};

int AttributeCount(Mode mode)
{
  return mode == Mode::Compatible ? 6 : (mode == Mode::Integrated ? 4 : 7);
}

/// A fan vertex as the rasterizer uses it. Its attribute values are computed when the
/// first triangle that uses it covers a pixel (most triangles of a fine mesh cover none).
struct Corner
{
  double X = 0, Y = 0; ///< window coordinates, snapped
  const TetVertex* vertex = nullptr;
  bool valued = false; ///< `values` hold the vertex's attributes
  double values[MaxAttributes] = {};
};

/// An attribute as planes over a tile: value = base + dx * i + dy * j at the pixel (i, j)
/// of the tile.
struct Planes
{
  float base[MaxAttributes], dx[MaxAttributes], dy[MaxAttributes];
};

/// The snapped window coordinate of NDC `ndc` in an image `size` pixels wide.
inline double Snap(float ndc, int size)
{
  return std::nearbyint((static_cast<double>(ndc) + 1.0) * 0.5 * size * SubpixelScale) /
    SubpixelScale;
}

/// `v` as a corner, its position only; false if that is not finite.
bool PlaceCorner(const RasterFrame& f, const TetVertex& v, Corner& c)
{
  c.X = Snap(v.x, f.width);
  c.Y = Snap(v.y, f.height);
  c.vertex = &v;
  c.valued = false;
  return std::isfinite(c.X) && std::isfinite(c.Y);
}

/// The attribute values of a placed corner, per shading mode (see Mode).
void ValueCorner(const RasterFrame& f, Mode mode, Corner& c)
{
  const TetVertex& v = *c.vertex;
  c.valued = true;
  if (mode == Mode::Compatible && f.vertexColours)
  {
    // Dependent components: the decomposition classified the vertex already.
    float rgba[4];
    LoadVertexColour(v, rgba);
    std::copy(rgba, rgba + 4, c.values);
    c.values[4] = v.thickness;
    c.values[5] = v.z;
    return;
  }
  if (mode == Mode::Compatible)
  {
    // Vertex classification: the mean of the transfer function at the front and back
    // scalars (VTK's PT; the OpenGL path's vertex shader).
    float front[4], back[4];
    f.transferFunction.Lookup(v.scalarFront, front);
    if (v.scalarBack == v.scalarFront)
    {
      std::copy(front, front + 4, back);
    }
    else
    {
      f.transferFunction.Lookup(v.scalarBack, back);
    }
    for (int k = 0; k < 4; ++k)
    {
      c.values[k] = 0.5f * (front[k] + back[k]);
    }
    c.values[4] = v.thickness;
    c.values[5] = v.z;
    return;
  }
  if (mode == Mode::Integrated)
  {
    c.values[0] = v.scalarFront;
    c.values[1] = v.scalarBack;
    c.values[2] = v.thickness;
    c.values[3] = v.z;
    return;
  }
  // Perspective-exact: 1 / w of the front and back faces and the eye ray are affine in
  // screen space over each triangle (PerspectiveInterpolation).
  const PerspectiveInterpolation& view = f.interpolation;
  const double rayX = (v.x + view.shiftX) * view.scaleX;
  const double rayY = (v.y + view.shiftY) * view.scaleY;
  const double ray = std::sqrt(1.0 + rayX * rayX + rayY * rayY);
  const double w = 1.0 / (view.inverseWScale * v.z + view.inverseWOffset);
  const double frontW = 1.0 / w, backW = 1.0 / (w + v.thickness / ray);
  c.values[0] = frontW * v.scalarFront;
  c.values[1] = frontW;
  c.values[2] = backW * v.scalarBack;
  c.values[3] = backW;
  c.values[4] = rayX;
  c.values[5] = rayY;
  c.values[6] = v.z;
}

/// The planes of the triangle (a, b, c) over the tile; false for a triangle without area.
bool SetUpPlanes(const TileTarget& tile, int attributes, const Corner* const v[3], Planes& p)
{
  const double area2 =
    (v[1]->X - v[0]->X) * (v[2]->Y - v[0]->Y) - (v[1]->Y - v[0]->Y) * (v[2]->X - v[0]->X);
  if (!(std::fabs(area2) > 0.0) || !std::isfinite(area2))
  {
    return false;
  }
  // Barycentric weight of vertex j at P: cross(V[j+1] - P, V[j+2] - P) / area2, taken at the
  // centre of the tile's first pixel and per pixel step.
  const double ox = tile.x0 + 0.5, oy = tile.y0 + 0.5;
  double weight[3], gx[3], gy[3];
  for (int j = 0; j < 3; ++j)
  {
    const Corner& a = *v[(j + 1) % 3];
    const Corner& b = *v[(j + 2) % 3];
    weight[j] = ((a.X - ox) * (b.Y - oy) - (a.Y - oy) * (b.X - ox)) / area2;
    gx[j] = (a.Y - b.Y) / area2;
    gy[j] = (b.X - a.X) / area2;
  }
  for (int k = 0; k < attributes; ++k)
  {
    double base = 0, dx = 0, dy = 0;
    for (int j = 0; j < 3; ++j)
    {
      base += v[j]->values[k] * weight[j];
      dx += v[j]->values[k] * gx[j];
      dy += v[j]->values[k] * gy[j];
    }
    p.base[k] = static_cast<float>(base);
    p.dx[k] = static_cast<float>(dx);
    p.dy[k] = static_cast<float>(dy);
  }
  return true;
}

/// One edge of a triangle for one row: E(x) = step * x + offset (fixed point) must be >=
/// `least` for pixel x to be inside (least 0 where the edge owns its points: top-left rule).
struct EdgeRow
{
  std::int64_t step, offset, offsetPerRow, least;
  double inverseStep;

  bool Inside(std::int64_t x) const { return this->step * x + this->offset >= this->least; }
};

/// Narrows [lo, hi] to the pixels of this row inside `e`, exactly: an estimate in double
/// precision, corrected by exact tests (the estimate is off by at most a few pixels).
inline void Narrow(const EdgeRow& e, int& lo, int& hi)
{
  if (e.step == 0)
  {
    if (!(e.offset >= e.least))
    {
      hi = lo - 1;
    }
    return;
  }
  const double bound = static_cast<double>(e.least - e.offset) * e.inverseStep;
  if (e.step > 0) // inside from the bound rightwards
  {
    int x = static_cast<int>(std::min(std::max(std::ceil(bound), lo - 1.0), hi + 1.0));
    while (x > lo && e.Inside(x - 1))
    {
      --x;
    }
    while (x <= hi && !e.Inside(x))
    {
      ++x;
    }
    lo = std::max(lo, x);
  }
  else // inside from the bound leftwards
  {
    int x = static_cast<int>(std::min(std::max(std::floor(bound), lo - 1.0), hi + 1.0));
    while (x < hi && e.Inside(x + 1))
    {
      ++x;
    }
    while (x >= lo && !e.Inside(x))
    {
      --x;
    }
    hi = std::min(hi, x);
  }
}

/// A triangle's edges in fixed point: E_k(p) = A p.x + B p.y + C, positive inside, and
/// whether each owns the points exactly on it (the top-left rule).
struct Edges
{
  std::int64_t A[3], B[3], C[3];
  bool owns[3];
  std::int64_t extent; ///< the larger side of the bounding box, fixed point
};

/// The edges of the triangle (X, Y) snapped to the 1/256-pixel grid; false without area.
/// Every coordinate must lie within FixedPointLimit.
bool SetUpEdges(const double X[3], const double Y[3], Edges& e)
{
  std::int64_t fx[3], fy[3];
  for (int k = 0; k < 3; ++k)
  {
    fx[k] = static_cast<std::int64_t>(std::nearbyint(X[k] * SubpixelScale));
    fy[k] = static_cast<std::int64_t>(std::nearbyint(Y[k] * SubpixelScale));
  }
  const std::int64_t area2 = (fx[1] - fx[0]) * (fy[2] - fy[0]) - (fy[1] - fy[0]) * (fx[2] - fx[0]);
  if (area2 == 0)
  {
    return false;
  }
  for (int k = 0; k < 3; ++k)
  {
    // Edge from a to b, oriented so that the inside is positive.
    int a = (k + 1) % 3, b = (k + 2) % 3;
    if (area2 < 0)
    {
      std::swap(a, b);
    }
    e.A[k] = fy[a] - fy[b];
    e.B[k] = fx[b] - fx[a];
    e.C[k] = fx[a] * fy[b] - fy[a] * fx[b];
    // Top-left rule for counter-clockwise triangles, y up: a left edge goes down, a top edge
    // is horizontal and goes left.
    e.owns[k] = fy[b] < fy[a] || (fy[b] == fy[a] && fx[b] < fx[a]);
  }
  const auto [minX, maxX] = std::minmax({ fx[0], fx[1], fx[2] });
  const auto [minY, maxY] = std::minmax({ fy[0], fy[1], fy[2] });
  e.extent = std::max(maxX - minX, maxY - minY);
  return true;
}

/// E_k at the centre of pixel (x, y).
inline std::int64_t EdgeAt(const Edges& e, int k, int x, int y)
{
  constexpr std::int64_t Step = 256, Half = 128;
  return e.A[k] * (x * Step + Half) + e.B[k] * (y * Step + Half) + e.C[k];
}

/**
 * Calls span(y, lo, hi) for every row y in [y0, y1] with the pixels [lo, hi] (within
 * [x0, x1]) whose centres the triangle covers by the top-left rule on the 1/256-pixel grid.
 */
template <typename Span>
void CoverSpans(const Edges& edges, int x0, int x1, int y0, int y1, Span&& span)
{
  constexpr std::int64_t Step = 256;
  EdgeRow rows[3];
  for (int k = 0; k < 3; ++k)
  {
    EdgeRow& e = rows[k];
    e.step = edges.A[k] * Step;
    e.offset = EdgeAt(edges, k, 0, y0);
    e.offsetPerRow = edges.B[k] * Step;
    e.least = edges.owns[k] ? 0 : 1;
    e.inverseStep = e.step != 0 ? 1.0 / static_cast<double>(e.step) : 0.0;
  }
  for (int y = y0; y <= y1; ++y)
  {
    int lo = x0, hi = x1;
    for (int k = 0; k < 3 && lo <= hi; ++k)
    {
      Narrow(rows[k], lo, hi);
    }
    if (lo <= hi)
    {
      span(y, lo, hi);
    }
    for (EdgeRow& e : rows)
    {
      e.offset += e.offsetPerRow;
    }
  }
}

/**
 * Clips the triangle (X, Y) to the box [lo, hiX] x [lo, hiY] (Sutherland-Hodgman), writing
 * the polygon's vertices to px, py (at most 7, inside the box) and returning their number;
 * 0 where a crossing overflows (coordinates near the largest double).
 */
int ClipToBox(const double X[3], const double Y[3], double lo, double hiX, double hiY, double px[9],
  double py[9])
{
  double ax[9], ay[9];
  int n = 3;
  std::copy(X, X + 3, px);
  std::copy(Y, Y + 3, py);
  for (int plane = 0; plane < 4 && n > 0; ++plane)
  {
    auto distance = [plane, lo, hiX, hiY](double u, double v)
    { return plane == 0 ? u - lo : (plane == 1 ? hiX - u : (plane == 2 ? v - lo : hiY - v)); };
    int m = 0;
    for (int i = 0; i < n; ++i)
    {
      const int j = (i + 1) % n;
      const double di = distance(px[i], py[i]), dj = distance(px[j], py[j]);
      if (di >= 0)
      {
        ax[m] = px[i];
        ay[m++] = py[i];
      }
      if ((di >= 0) != (dj >= 0))
      {
        // The crossing, stepped from the end inside: from the far end (a corner of a near
        // plane's piece may lie 1e15 pixels off) the step would round it far off the plane.
        // Its coordinate across the plane is the plane's.
        const int in = di >= 0 ? i : j, out = di >= 0 ? j : i;
        const double dIn = di >= 0 ? di : dj, dOut = di >= 0 ? dj : di;
        const double t = dIn / (dIn - dOut);
        double x = px[in] + t * (px[out] - px[in]), y = py[in] + t * (py[out] - py[in]);
        if (!std::isfinite(x) || !std::isfinite(y))
        {
          return 0;
        }
        if (plane < 2)
        {
          x = plane == 0 ? lo : hiX;
        }
        else
        {
          y = plane == 2 ? lo : hiY;
        }
        ax[m] = x;
        ay[m++] = y;
      }
    }
    n = m;
    std::copy(ax, ax + n, px);
    std::copy(ay, ay + n, py);
  }
  return n;
}

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
 * A pixel whose coverage alpha reached this hides what lies behind it: fragments drawn there
 * later (farther: fans are drawn front to back) are skipped. They could add at most
 * 1 - OpaqueAlpha = 2^-11 of full intensity to the pixel, an eighth of an 8-bit step.
 */
constexpr float OpaqueAlpha = 1.0f - 1.0f / 2048;

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

/// VTK-compatible shading of the pixels [lo, hi] of row y.
void ShadeCompatible(
  const RasterFrame& f, const TileTarget& tile, const Planes& p, int y, int lo, int hi)
{
  const FragmentTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const TileRow row = RowOf(tile, y);
  float start[6];
  RowStart(p, y - tile.y0, start);
  const int first = lo - tile.x0, last = hi - tile.x0;
  const auto lastLane = hn::Set(d, static_cast<float>(last));
  // Vectors start at the span's first pixel (not at a multiple of the lane count: fewer
  // idle lanes on short spans), moved back so as not to reach past the row's end; lanes
  // before `from` are done already (or not in the span) and stay as they are.
  for (int from = first; from <= last; from += lanes)
  {
    const int x = std::min(from, T - lanes);
    const auto i = hn::Iota(d, static_cast<float>(x));
    ShadeVector(d, f, row, p, start, x,
      hn::And(hn::Ge(i, hn::Set(d, static_cast<float>(from))), hn::Le(i, lastLane)));
  }
}

/// Triangles at most this many pixels across take the small path (see ShadeSmall).
constexpr std::int64_t SmallTriangle = 8 * 256;

/**
 * A small triangle (SmallTriangle) over rows [y0, y1] and columns [x0, x1], a row's lanes at
 * once: shade(row, planes, y, x, keep) for each vector with a covered lane. Coverage is
 * tested per lane, exactly: within 15 pixels of such a triangle every edge function value is
 * an integer below 2^24 in magnitude, which float holds exactly, so the float sums and
 * comparisons decide as the 64-bit ones do.
 */
template <typename GetPlanes, typename Shade>
void ShadeSmall(const TileTarget& tile, const Edges& edges, GetPlanes&& planes, int x0, int x1,
  int y0, int y1, RasterCounts& counts, Shade&& shade)
{
  const FragmentTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int first = x0 - tile.x0, last = x1 - tile.x0;
  const int begin = std::min(first, T - lanes); // see ShadeCompatible
  float edgeRow[3], stepX[3], stepY[3], least[3];
  for (int k = 0; k < 3; ++k)
  {
    edgeRow[k] = static_cast<float>(EdgeAt(edges, k, tile.x0 + begin, y0));
    stepX[k] = static_cast<float>(edges.A[k] * 256);
    stepY[k] = static_cast<float>(edges.B[k] * 256);
    least[k] = edges.owns[k] ? 0.0f : 1.0f;
  }
  const auto lastLane = hn::Set(d, static_cast<float>(last));
  for (int y = y0; y <= y1; ++y)
  {
    const TileRow row = RowOf(tile, y);
    const Planes* p = nullptr; // set up when the row has a covered pixel
    for (int from = first; from <= last; from += lanes)
    {
      const int x = std::min(from, T - lanes);
      const auto i = hn::Iota(d, static_cast<float>(x));
      const auto offset = hn::Iota(d, static_cast<float>(x - begin));
      auto keep = hn::And(hn::Ge(i, hn::Set(d, static_cast<float>(from))), hn::Le(i, lastLane));
      for (int k = 0; k < 3; ++k)
      {
        const auto e = hn::MulAdd(hn::Set(d, stepX[k]), offset, hn::Set(d, edgeRow[k]));
        keep = hn::And(keep, hn::Ge(e, hn::Set(d, least[k])));
      }
      if (hn::AllFalse(d, keep))
      {
        continue;
      }
      if (!p)
      {
        p = planes();
        if (!p)
        {
          return; // no area: nothing to draw
        }
      }
      counts.fragments += hn::CountTrue(d, keep);
      shade(row, *p, y, x, keep);
    }
    for (int k = 0; k < 3; ++k)
    {
      edgeRow[k] += stepY[k];
    }
  }
}

/// Scalars in entry coordinates of `tf`, not clamped (NaN gives 0, as EntryCoordinate).
template <class D, class V = hn::Vec<D>>
HWY_INLINE V EntryLanes(D d, const TransferFunctionTable& tf, V scalar)
{
  const double scale = (tf.size - 1) / (tf.high > tf.low ? tf.high - tf.low : 1.0);
  const V u = hn::MulAdd(scalar, hn::Set(d, static_cast<float>(scale)),
    hn::Set(d, static_cast<float>(-tf.low * scale)));
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
  return hn::Min(hn::Max(EntryLanes(d, t.tf, scalar), hn::Zero(d)),
    hn::Set(d, static_cast<float>(t.last)));
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

/// Partial per lane: integrals of tau and c tau from the interval's start to fraction f.
template <class D, class V = hn::Vec<D>>
HWY_INLINE void PartialLanes(D d, const IntervalLanes<D>& v, V f, V& t, V e[3])
{
  const V half = hn::Set(d, 0.5f), third = hn::Set(d, 1.0f / 3.0f);
  t = hn::Mul(f, hn::Add(v.tau, hn::Mul(hn::Mul(half, f), v.dTau)));
  for (int k = 0; k < 3; ++k)
  {
    const V linear =
      hn::Mul(hn::Mul(half, f), hn::Add(hn::Mul(v.c[k], v.dTau), hn::Mul(v.dC[k], v.tau)));
    const V quadratic = hn::Mul(hn::Mul(hn::Mul(hn::Mul(f, f), v.dC[k]), v.dTau), third);
    e[k] = hn::Mul(f, hn::Add(hn::Add(hn::Mul(v.c[k], v.tau), linear), quadratic));
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
    // Across intervals: the prefix integrals' difference and the two partial intervals.
    V t0, t1, e0[3], e1[3], sums[4];
    PartialLanes(d, v0, f0, t0, e0);
    PartialLanes(d, v1, f1, t1, e1);
    r.IntegralsBetween(d, i0, i1, sums);
    const V inverse = hn::Div(hn::Set(d, 1.0f), hn::Sub(u1, u0)); // 1 / 0 where same
    step.tau = hn::Mul(hn::Sub(hn::Add(sums[0], t1), t0), inverse);
    for (int k = 0; k < 3; ++k)
    {
      e[k] = hn::Mul(hn::Sub(hn::Add(sums[1 + k], e1[k]), e0[k]), inverse);
    }
  }
  if (!hn::AllFalse(d, same))
  {
    // Means inside one interval in factored form, exact as u1 -> u0 (SpanMeans).
    const V s1 = hn::Mul(hn::Set(d, 0.5f), hn::Add(f0, f1));
    const V s2 = hn::Mul(hn::Add(hn::Add(hn::Mul(f0, f0), hn::Mul(f0, f1)), hn::Mul(f1, f1)),
      hn::Set(d, 1.0f / 3.0f));
    const V tau = hn::Add(v0.tau, hn::Mul(s1, v0.dTau));
    step.tau = oneInterval ? tau : hn::IfThenElse(same, tau, step.tau);
    for (int k = 0; k < 3; ++k)
    {
      const V inside =
        hn::Add(hn::Add(hn::Mul(v0.c[k], v0.tau),
                  hn::Mul(s1, hn::Add(hn::Mul(v0.c[k], v0.dTau), hn::Mul(v0.dC[k], v0.tau)))),
          hn::Mul(hn::Mul(s2, v0.dC[k]), v0.dTau));
      e[k] = oneInterval ? inside : hn::IfThenElse(same, inside, e[k]);
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
    const V thick = hn::Div(hn::NegMulAdd(stepDepth, hn::Sub(one, opacity), opacity),
      hn::Mul(stepDepth, opacity));
    h = hn::IfThenElse(thin, series, thick);
  }
  const V shift = hn::Sub(half, h);
  const V inverseTau = hn::Div(one, hn::IfThenElse(seen, step.tau, one));
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
  const V wanted = hn::Ceil(hn::Mul(hn::Mul(whole.tau, depth),
    hn::Set(d, static_cast<float>(1.0 / PreIntegrationStepDepth))));
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
void ShadeWaiting(const RasterFrame& f, const TileTarget& tile, WaitingFragments& w)
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

/// A fragment's ray segment: eye depths of its ends, eye length, and the scalars at its ends
/// (pre-integrated shading), from the planes at one pixel, and the pixel centre's NDC.
struct FragmentSegment
{
  double front, back, length, scalarFront = 0, scalarBack = 0, z, ndcX, ndcY;
};

FragmentSegment SegmentAt(
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
    s.length = std::max(0.0, s.back - s.front) * std::sqrt(1.0 + rayX * rayX + rayY * rayY);
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
bool DrawnPart(const RasterFrame& f, const TileTarget& tile, const TileRow& row,
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
void ShadeClipped(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p, int y,
  int lo, int hi, WaitingFragments& waiting, bool cut)
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

/**
 * A blend mode other than Composite: folds the fragment at column x whose drawn part runs
 * from entry coordinate u0 to u1 (not clamped) over eye length `length` into the pixel
 * (TileTarget). The average's range (RasterFrame::averageRange) is open beyond the table
 * where it reaches the table's ends, as it applies to the clamped scalar.
 */
void ReduceFragment(const RasterFrame& f, const TileRow& row, int x, double u0, double u1,
  double length)
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
HWY_INLINE void WholeFragments(D d, Mode mode, const Planes& p, V i, float j, V& front, V& back,
  V& length, V& z)
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
  length = hn::Mul(hn::ZeroIfNegative(hn::Sub(hn::Div(hn::Set(d, 1.0f), backW),
                     hn::Div(hn::Set(d, 1.0f), frontW))), ray);
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
  const V across = hn::Add(sums, hn::Sub(IntervalIntegralLanes(d, k, a1, d1, b1, zero, f1),
                                   IntervalIntegralLanes(d, k, a0, d0, b0, zero, f0)));
  const V steps = hn::Sub(b1, b0);
  const V inside = hn::IfThenElse(hn::Eq(steps, zero), within,
    hn::IfThenElse(hn::Eq(steps, one), neighbours, across));
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
HWY_INLINE void FoldIntegrals(D d, const RasterFrame& f, const TileRow& row, int x, V front,
  V back, V length, V z, hn::Mask<D> keep)
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
    weighted = hn::IfThenElseZero(hn::Gt(fraction, zero),
      hn::Mul(counted, IntensityMeanLanes(d, f, from, hn::Max(from, to))));
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
void ReduceWhole(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p,
  int y, int lo, int hi)
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
void ReduceSpan(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p, int y,
  int lo, int hi, bool cut)
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

/// Pre-integrated shading of the pixels [lo, hi] of row y: each fragment's scalars and
/// length from the planes, a vector at a time, waiting in `waiting` to be shaded.
void ShadeIntegrated(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p,
  int y, int lo, int hi, WaitingFragments& waiting)
{
  if (!f.preIntegration->Covers(f.transferFunction))
  {
    return; // every segment transparent
  }
  const FragmentTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const TileRow row = RowOf(tile, y);
  const float j = static_cast<float>(y - tile.y0);
  const int first = lo - tile.x0, last = hi - tile.x0;
  const auto lastLane = hn::Set(d, static_cast<float>(last));
  for (int from = first; from <= last; from += lanes) // see ShadeCompatible
  {
    const int x = std::min(from, T - lanes);
    const auto i = hn::Iota(d, static_cast<float>(x));
    // As the fan path: nothing behind an opaque pixel can show.
    auto keep =
      hn::And(hn::And(hn::Ge(i, hn::Set(d, static_cast<float>(from))), hn::Le(i, lastLane)),
        Transparent(d, row, x));
    if (hn::AllFalse(d, keep))
    {
      continue;
    }
    hn::Vec<FragmentTag> front, back, length, z;
    WholeFragments(d, mode, p, i, j, front, back, length, z);
    keep = DrawnLanes(d, row, x, z, keep); // clipped, or behind opaque geometry
    if (hn::AllFalse(d, keep))
    {
      continue;
    }
    waiting.Wait(d, tile, x, y, front, back, length, keep);
    if (waiting.Full())
    {
      ShadeWaiting(f, tile, waiting);
    }
  }
}

/// Shades the covered pixels lo..hi of row y by the mode's path, or cut by the depth range
/// or (`cut`) the clipping planes; or reduces them (a blend mode other than Composite).
void ShadeSpan(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p, int y,
  int lo, int hi, WaitingFragments& waiting, bool cut)
{
  if (ReducesInAnyOrder(f.blendMode))
  {
    ReduceSpan(f, tile, mode, p, y, lo, hi, cut);
  }
  else if (f.clipToRange || cut)
  {
    ShadeClipped(f, tile, mode, p, y, lo, hi, waiting, cut);
  }
  else if (mode == Mode::Compatible)
  {
    ShadeCompatible(f, tile, p, y, lo, hi);
  }
  else
  {
    ShadeIntegrated(f, tile, mode, p, y, lo, hi, waiting);
  }
}

/// Covers a triangle (X, Y) beyond the fixed-point range (a near-plane piece far off
/// screen): clipped to a guard band, as OpenGL does, and its pieces covered with `span`,
/// whose planes stay those of the whole triangle.
template <class Span>
void CoverGuardBand(const RasterFrame& f, const double X[3], const double Y[3], int x0, int x1,
  int y0, int y1, Span& span)
{
  double px[9], py[9];
  const int n = ClipToBox(X, Y, -GuardBand, f.width + GuardBand, f.height + GuardBand, px, py);
  Edges edges;
  for (int k = 1; k + 1 < n; ++k)
  {
    const double fanX[3] = { px[0], px[k], px[k + 1] }, fanY[3] = { py[0], py[k], py[k + 1] };
    if (SetUpEdges(fanX, fanY, edges))
    {
      CoverSpans(edges, x0, x1, y0, y1, span);
    }
  }
}

/**
 * A small triangle (ShadeSmall) whose fragments are whole: VTK-compatible shading or a blend
 * mode other than Composite; false, having drawn nothing, in pre-integrated shading.
 */
template <typename GetPlanes>
bool DrawSmall(const RasterFrame& f, const TileTarget& tile, Mode mode, const Edges& edges,
  GetPlanes& getPlanes, int x0, int x1, int y0, int y1, RasterCounts& counts)
{
  if (!ReducesInAnyOrder(f.blendMode) && mode != Mode::Compatible)
  {
    return false;
  }
  if (mode == Mode::Compatible)
  {
    ShadeSmall(tile, edges, getPlanes, x0, x1, y0, y1, counts,
      [&](const TileRow& row, const Planes& p, int y, int x, auto keep)
      {
        float start[6];
        RowStart(p, y - tile.y0, start);
        ShadeVector(FragmentTag(), f, row, p, start, x, keep);
      });
    return true;
  }
  ShadeSmall(tile, edges, getPlanes, x0, x1, y0, y1, counts,
    [&](const TileRow& row, const Planes& p, int y, int x, auto keep)
    { ReduceVector(FragmentTag(), f, mode, row, p, static_cast<float>(y - tile.y0), x, keep); });
  return true;
}

/**
 * Rasterizes the triangle of corners v into the tile. Coverage comes first: the corners'
 * values and the attribute planes are set up only once a pixel is known to be covered.
 */
void DrawTriangle(const RasterFrame& f, const TileTarget& tile, Mode mode, Corner* const v[3],
  WaitingFragments& waiting, RasterCounts& counts, bool cut)
{
  double minX = v[0]->X, maxX = minX, minY = v[0]->Y, maxY = minY;
  for (int k = 1; k < 3; ++k)
  {
    minX = std::min(minX, v[k]->X);
    maxX = std::max(maxX, v[k]->X);
    minY = std::min(minY, v[k]->Y);
    maxY = std::max(maxY, v[k]->Y);
  }
  // Pixel centres x + 0.5 within the bounding box and the tile.
  const double tx0 = tile.x0, tx1 = tile.x0 + tile.width - 1.0;
  const double ty0 = tile.y0, ty1 = tile.y0 + tile.height - 1.0;
  const double bx0 = std::max(tx0, std::ceil(minX - 0.5)),
               bx1 = std::min(tx1, std::floor(maxX - 0.5));
  const double by0 = std::max(ty0, std::ceil(minY - 0.5)),
               by1 = std::min(ty1, std::floor(maxY - 0.5));
  if (!(bx0 <= bx1 && by0 <= by1))
  {
    return;
  }
  Planes planes;
  int state = 0; // 0: not set up yet, 1: set up, -1: no area
  auto getPlanes = [&]() -> const Planes*
  {
    if (state == 0)
    {
      for (int k = 0; k < 3; ++k)
      {
        if (!v[k]->valued)
        {
          ValueCorner(f, mode, *v[k]);
        }
      }
      const Corner* const corners[3] = { v[0], v[1], v[2] };
      state = SetUpPlanes(tile, AttributeCount(mode), corners, planes) ? 1 : -1;
      counts.triangles += state > 0 ? 1 : 0;
    }
    return state > 0 ? &planes : nullptr;
  };
  auto span = [&](int y, int lo, int hi)
  {
    if (const Planes* p = getPlanes())
    {
      counts.fragments += static_cast<std::size_t>(hi - lo + 1);
      ShadeSpan(f, tile, mode, *p, y, lo, hi, waiting, cut);
    }
  };
  const int x0 = static_cast<int>(bx0), x1 = static_cast<int>(bx1);
  const int y0 = static_cast<int>(by0), y1 = static_cast<int>(by1);
  double X[3] = { v[0]->X, v[1]->X, v[2]->X }, Y[3] = { v[0]->Y, v[1]->Y, v[2]->Y };
  Edges edges;
  if (std::max(std::max(-minX, maxX), std::max(-minY, maxY)) < FixedPointLimit)
  {
    if (!SetUpEdges(X, Y, edges))
    {
      return;
    }
    const bool small = edges.extent <= SmallTriangle && !f.clipToRange && !cut;
    if (!small || !DrawSmall(f, tile, mode, edges, getPlanes, x0, x1, y0, y1, counts))
    {
      CoverSpans(edges, x0, x1, y0, y1, span);
    }
    return;
  }
  CoverGuardBand(f, X, Y, x0, x1, y0, y1, span);
}

#include "FanRaster-inl.h" // FanPath: this namespace's fan path (a fragment of this file)
#include "FragmentFloor-inl.h" // the fragment loop's floor, for measurements

void RasterizeTileImpl(const RasterFrame& f, const TileTarget& target, const Fan* fans,
  std::size_t count, RasterCounts& counts, const LightFactors* lights)
{
  TileTarget tile = target; // with the lighting of the fan being drawn
  const bool reduce = ReducesInAnyOrder(f.blendMode);
  const bool integrates =
    f.blendMode == BlendMode::AverageIntensity || f.blendMode == BlendMode::Additive;
  if (reduce && (f.vertexColours || (integrates && !f.intensity)))
  {
    return; // no scalars to reduce (colours in the records), or no integral to reduce with
  }
  // A reduction interpolates the scalars as pre-integrated shading does.
  const Mode mode = !f.preIntegration && !reduce
    ? Mode::Compatible
    : (f.interpolation.perspective ? Mode::ExactIntegral : Mode::Integrated);
  WaitingFragments waiting; // pre-integrated fragments
  FanPath fanPath(f, tile, mode, waiting); // fans drawn whole
  for (std::size_t e = 0; e < count; ++e)
  {
    const Fan& fan = fans[e];
    tile.light = lights && !reduce ? lights + e : nullptr;
    const bool cut = fan.straddles != 0;
    if (!cut && fanPath.Draw(fan, counts))
    {
      continue; // the fan as a whole, as its triangles would be drawn
    }
    const int n = fan.count;
    Corner corners[5];
    bool finite = PlaceCorner(f, fan.centre, corners[n]);
    for (int k = 0; k < n; ++k)
    {
      finite = finite && PlaceCorner(f, fan.boundary[k], corners[k]);
    }
    if (!finite)
    {
      continue;
    }
    // Last triangle first: drawn under what the pixel holds, that is the slot's triangles
    // blended over one another in index order, as OpenGL draws them. (They overlap only
    // where a degenerate projection puts the centre outside the silhouette.)
    const int triangles = fan.closed ? n : n - 1;
    for (int k = triangles - 1; k >= 0; --k)
    {
      Corner* v[3] = { &corners[k], &corners[(k + 1) % n], &corners[n] };
      DrawTriangle(f, tile, mode, v, waiting, counts, cut);
    }
    ShadeWaiting(f, tile, waiting); // the fan's fragments, before the next fan is drawn
  }
}

const char* TargetName()
{
  return hwy::TargetName(HWY_TARGET);
}

void OpacitiesOfDensitiesImpl(const float* density, float* opacity, std::size_t count)
{
  const FragmentTag d;
  const std::size_t lanes = hn::Lanes(d);
  float in[MaxLanes], out[MaxLanes];
  for (std::size_t i = 0; i < count; i += lanes)
  {
    const std::size_t n = std::min(lanes, count - i);
    std::fill(in, in + lanes, 0.0f);
    std::copy(density + i, density + i + n, in);
    hn::StoreU(OpacityOfDensity(d, hn::LoadU(d, in)), d, out);
    std::copy(out, out + n, opacity + i);
  }
}

void PreIntegratedSegmentsImpl(const TransferFunctionTable& tf, const PreIntegrationTable& table,
  const float* front, const float* back, const float* length, float inverseUnit, float* rgba,
  std::size_t count)
{
  std::fill(rgba, rgba + 4 * count, 0.0f);
  if (!table.Covers(tf))
  {
    return;
  }
  RasterFrame f;
  f.transferFunction = tf;
  f.preIntegration = &table;
  f.inverseUnit = inverseUnit;
  const SegmentTable t(f);
  const FragmentTag d;
  const std::size_t lanes = hn::Lanes(d);
  for (std::size_t i = 0; i < count; i += lanes)
  {
    const std::size_t n = std::min(lanes, count - i);
    HWY_ALIGN float in[3][MaxLanes] = {}, out[4][MaxLanes] = {};
    std::copy(front + i, front + i + n, in[0]);
    std::copy(back + i, back + i + n, in[1]);
    std::copy(length + i, length + i + n, in[2]);
    hn::Vec<FragmentTag> colour[3];
    hn::Store(
      SegmentOfLanes(d, t, hn::Load(d, in[0]), hn::Load(d, in[1]), hn::Load(d, in[2]), colour),
      d, out[3]);
    for (int c = 0; c < 3; ++c)
    {
      hn::Store(colour[c], d, out[c]);
    }
    for (std::size_t k = 0; k < n; ++k)
    {
      for (int c = 0; c < 4; ++c)
      {
        rgba[4 * (i + k) + c] = out[c][k];
      }
    }
  }
}

void IntensityMeansImpl(const TransferFunctionTable& tf, const IntensityTable& table,
  const float* u0, const float* u1, float* mean, std::size_t count)
{
  const FragmentTag d;
  RasterFrame f;
  f.transferFunction = tf;
  f.intensity = &table;
  const std::size_t lanes = hn::Lanes(d);
  for (std::size_t i = 0; i < count; i += lanes)
  {
    const std::size_t n = std::min(lanes, count - i);
    HWY_ALIGN float a[MaxLanes] = {}, b[MaxLanes] = {}, out[MaxLanes] = {};
    std::copy(u0 + i, u0 + i + n, a);
    std::copy(u1 + i, u1 + i + n, b);
    hn::Store(IntensityMeanLanes(d, f, hn::Load(d, a), hn::Load(d, b)), d, out);
    std::copy(out, out + n, mean + i);
  }
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

HWY_EXPORT(RasterizeTileImpl);
HWY_EXPORT(TargetName);
HWY_EXPORT(OpacitiesOfDensitiesImpl);
HWY_EXPORT(PreIntegratedSegmentsImpl);
HWY_EXPORT(IntensityMeansImpl);
HWY_EXPORT(FragmentFloorImpl);
HWY_EXPORT(FragmentLanesImpl);

float FragmentFloor(int rung, std::size_t vectors, float* rgba, const float* depth)
{
  return HWY_DYNAMIC_DISPATCH(FragmentFloorImpl)(rung, vectors, rgba, depth);
}

std::size_t FragmentLanes()
{
  return HWY_DYNAMIC_DISPATCH(FragmentLanesImpl)();
}

void RasterizeTile(const RasterFrame& frame, const TileTarget& tile, const Fan* fans,
  std::size_t count, RasterCounts& counts, const LightFactors* lights)
{
  HWY_DYNAMIC_DISPATCH(RasterizeTileImpl)(frame, tile, fans, count, counts, lights);
}

const char* RasterTargetName()
{
  return HWY_DYNAMIC_DISPATCH(TargetName)();
}

void OpacitiesOfDensities(const float* density, float* opacity, std::size_t count)
{
  HWY_DYNAMIC_DISPATCH(OpacitiesOfDensitiesImpl)(density, opacity, count);
}

void PreIntegratedSegments(const TransferFunctionTable& tf, const PreIntegrationTable& table,
  const float* front, const float* back, const float* length, float inverseUnit, float* rgba,
  std::size_t count)
{
  HWY_DYNAMIC_DISPATCH(PreIntegratedSegmentsImpl)
  (tf, table, front, back, length, inverseUnit, rgba, count);
}

void IntensityMeans(const TransferFunctionTable& tf, const IntensityTable& table, const float* u0,
  const float* u1, float* mean, std::size_t count)
{
  HWY_DYNAMIC_DISPATCH(IntensityMeansImpl)(tf, table, u0, u1, mean, count);
}

} // namespace detail
} // namespace mtpt
#endif
