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

constexpr int T = Compositor::TileSize;
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
 * the polygon's vertices to px, py (at most 7) and returning their number.
 */
int ClipToBox(const double X[3], const double Y[3], double lo, double hiX, double hiY,
  double px[9], double py[9])
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
        const double t = di / (di - dj);
        ax[m] = px[i] + t * (px[j] - px[i]);
        ay[m++] = py[i] + t * (py[j] - py[i]);
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
  const float* depth; ///< null: no opaque depth
};

inline TileRow RowOf(const TileTarget& tile, int y)
{
  const int j = y - tile.y0;
  float* r = tile.rgba + j * T;
  return { r, r + T * T, r + 2 * T * T, r + 3 * T * T, tile.depth ? tile.depth + j * T : nullptr };
}

/// The vector type of the fragment loops: 8 lanes where the processor has them (AVX2 and
/// AVX-512 alike: wider vectors only add idle lanes to the short spans of small triangles).
using FragmentTag = hn::CappedTag<float, 8>;
constexpr std::size_t MaxLanes = 8;

/**
 * A fragment's opacity 1 - exp(-density), as -expm1(-density): no cancellation for thin
 * segments. Highway's Expm1 is a polynomial approximation of bounded error (tested against
 * std::expm1 by the core tests through OpacitiesOfDensities).
 */
template <class D, class V>
HWY_INLINE V OpacityOfDensity(D d, V density)
{
  return hn::Neg(hn::Expm1(d, hn::Neg(density)));
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
  const auto attenuation = hn::MulAdd(hn::Set(d, p.dx[3]), i, hn::Set(d, start[3]));
  const auto length = hn::MulAdd(hn::Set(d, p.dx[4]), i, hn::Set(d, start[4]));
  const auto opacity =
    OpacityOfDensity(d, hn::Mul(hn::Mul(attenuation, length), hn::Set(d, f.inverseUnit)));
  keep = hn::And(keep, hn::Gt(opacity, hn::Zero(d)));
  const auto rest = hn::Sub(one, opacity);
  float* planes[3] = { row.r, row.g, row.b };
  for (int k = 0; k < 3; ++k)
  {
    const auto colour = hn::MulAdd(hn::Set(d, p.dx[k]), i, hn::Set(d, start[k]));
    const auto below = hn::LoadU(d, planes[k] + x);
    const auto blended = hn::MulAdd(opacity, colour, hn::Mul(rest, below));
    hn::StoreU(hn::IfThenElse(keep, blended, below), d, planes[k] + x);
  }
  const auto alpha = hn::LoadU(d, row.a + x);
  hn::StoreU(hn::IfThenElse(keep, hn::MulAdd(rest, alpha, opacity), alpha), d, row.a + x);
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
void ShadeCompatible(const RasterFrame& f, const TileTarget& tile, const Planes& p, int y,
  int lo, int hi)
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
 * VTK-compatible shading of a small triangle (SmallTriangle) over rows [y0, y1] and columns
 * [x0, x1], a row's lanes at once. Coverage is tested per lane, exactly: within 15 pixels of
 * such a triangle every edge function value is an integer below 2^24 in magnitude, which
 * float holds exactly, so the float sums and comparisons decide as the 64-bit ones do.
 */
template <typename GetPlanes>
void ShadeSmall(const RasterFrame& f, const TileTarget& tile, const Edges& edges,
  GetPlanes&& planes, int x0, int x1, int y0, int y1, RasterCounts& counts)
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
    float start[6];
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
        RowStart(*p, y - tile.y0, start);
      }
      counts.fragments += hn::CountTrue(d, keep);
      ShadeVector(d, f, row, *p, start, x, keep);
    }
    for (int k = 0; k < 3; ++k)
    {
      edgeRow[k] += stepY[k];
    }
  }
}

/// Pre-integrated shading of the pixels [lo, hi] of row y, pixel by pixel (the table's
/// integrals are looked up per fragment).
void ShadeIntegrated(const RasterFrame& f, const TileTarget& tile, Mode mode, const Planes& p,
  int y, int lo, int hi)
{
  const TileRow row = RowOf(tile, y);
  const float j = static_cast<float>(y - tile.y0);
  for (int x = lo - tile.x0; x <= hi - tile.x0; ++x)
  {
    const float i = static_cast<float>(x);
    auto value = [&](int k) { return p.base[k] + p.dx[k] * i + p.dy[k] * j; };
    float front, back, length, z;
    if (mode == Mode::Integrated)
    {
      front = value(0);
      back = value(1);
      length = value(2);
      z = value(3);
    }
    else
    {
      const double frontW = value(1), backW = value(3), rayX = value(4), rayY = value(5);
      front = static_cast<float>(value(0) / frontW);
      back = static_cast<float>(value(2) / backW);
      length = static_cast<float>(
        std::max(0.0, 1.0 / backW - 1.0 / frontW) * std::sqrt(1.0 + rayX * rayX + rayY * rayY));
      z = value(6);
    }
    if (z < -1.0f || z > 1.0f || (row.depth && 0.5f * (z + 1.0f) > row.depth[x]))
    {
      continue; // clipped by the near or far plane, or behind opaque geometry
    }
    float rgba[4];
    f.preIntegration->Segment(f.transferFunction, front, back, length, f.inverseUnit, rgba);
    const float opacity = rgba[3];
    if (!(opacity > 0.0f))
    {
      continue;
    }
    const float rest = 1.0f - opacity;
    row.r[x] = opacity * rgba[0] + rest * row.r[x];
    row.g[x] = opacity * rgba[1] + rest * row.g[x];
    row.b[x] = opacity * rgba[2] + rest * row.b[x];
    row.a[x] = opacity + rest * row.a[x];
  }
}

/**
 * Rasterizes the triangle of corners v into the tile. Coverage comes first: the corners'
 * values and the attribute planes are set up only once a pixel is known to be covered.
 */
void DrawTriangle(const RasterFrame& f, const TileTarget& tile, Mode mode, Corner* const v[3],
  RasterCounts& counts)
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
  const double bx0 = std::max(tx0, std::ceil(minX - 0.5)), bx1 = std::min(tx1, std::floor(maxX - 0.5));
  const double by0 = std::max(ty0, std::ceil(minY - 0.5)), by1 = std::min(ty1, std::floor(maxY - 0.5));
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
    const Planes* p = getPlanes();
    if (!p)
    {
      return;
    }
    counts.fragments += static_cast<std::size_t>(hi - lo + 1);
    if (mode == Mode::Compatible)
    {
      ShadeCompatible(f, tile, *p, y, lo, hi);
    }
    else
    {
      ShadeIntegrated(f, tile, mode, *p, y, lo, hi);
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
    if (mode == Mode::Compatible && edges.extent <= SmallTriangle)
    {
      ShadeSmall(f, tile, edges, getPlanes, x0, x1, y0, y1, counts);
    }
    else
    {
      CoverSpans(edges, x0, x1, y0, y1, span);
    }
    return;
  }
  // Beyond the fixed-point range (a near-plane piece far off screen): clip to a guard band,
  // as OpenGL does, and cover the pieces; the planes stay those of the whole triangle.
  double px[9], py[9];
  const int n = ClipToBox(X, Y, -GuardBand, f.width + GuardBand, f.height + GuardBand, px, py);
  for (int k = 1; k + 1 < n; ++k)
  {
    const double fanX[3] = { px[0], px[k], px[k + 1] }, fanY[3] = { py[0], py[k], py[k + 1] };
    if (SetUpEdges(fanX, fanY, edges))
    {
      CoverSpans(edges, x0, x1, y0, y1, span);
    }
  }
}

void RasterizeTileImpl(const RasterFrame& f, const TileTarget& tile, const Fan* fans,
  std::size_t count, RasterCounts& counts)
{
  const Mode mode = !f.preIntegration
    ? Mode::Compatible
    : (f.interpolation.perspective ? Mode::ExactIntegral : Mode::Integrated);
  for (std::size_t e = 0; e < count; ++e)
  {
    const Fan& fan = fans[e];
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
    const int triangles = fan.closed ? n : n - 1;
    for (int k = 0; k < triangles; ++k)
    {
      Corner* v[3] = { &corners[k], &corners[(k + 1) % n], &corners[n] };
      DrawTriangle(f, tile, mode, v, counts);
    }
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

void RasterizeTile(const RasterFrame& frame, const TileTarget& tile, const Fan* fans,
  std::size_t count, RasterCounts& counts)
{
  HWY_DYNAMIC_DISPATCH(RasterizeTileImpl)(frame, tile, fans, count, counts);
}

const char* RasterTargetName()
{
  return HWY_DYNAMIC_DISPATCH(TargetName)();
}

void OpacitiesOfDensities(const float* density, float* opacity, std::size_t count)
{
  HWY_DYNAMIC_DISPATCH(OpacitiesOfDensitiesImpl)(density, opacity, count);
}

} // namespace detail
} // namespace mtpt
#endif
