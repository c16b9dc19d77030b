// SPDX-License-Identifier: BSD-3-Clause
// Internal: the rasterizer's geometry. Corners snapped to 1/256 pixel with their values per
// shading mode (Mode), the planes of a triangle's values over a tile (set up in double
// precision from the snapped corners, evaluated in float relative to the tile's corner), and
// exact coverage: 64-bit fixed-point edge functions with the top-left rule, the row spans
// they bound, and the clipping of a triangle beyond the fixed-point range to a guard band.
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_RASTER_CORNERS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_RASTER_CORNERS_INL_H_
#undef MTPT_COMPOSITOR_RASTER_CORNERS_INL_H_
#else
#define MTPT_COMPOSITOR_RASTER_CORNERS_INL_H_
#endif

#include "detail/TileRaster.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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
constexpr int MaxAttributes = 8;

/// What is interpolated, per shading mode (the layout of Corner::values and Planes).
enum class Mode
{
  Compatible,   ///< r, g, b, attenuation, length, z
  Integrated,   ///< front scalar, back scalar, length, z (linear in screen space)
  /// front scalar / w, 1 / w, back scalar / w, 1 / w, ray x, ray y, z, 1 / w back - front
  ExactIntegral
};

inline int AttributeCount(Mode mode)
{
  return mode == Mode::Compatible ? 6 : (mode == Mode::Integrated ? 4 : 8);
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
inline bool PlaceCorner(const RasterFrame& f, const TetVertex& v, Corner& c)
{
  c.X = Snap(v.x, f.width);
  c.Y = Snap(v.y, f.height);
  c.vertex = &v;
  c.valued = false;
  return std::isfinite(c.X) && std::isfinite(c.Y);
}

/// The corners of `fan` placed (PlaceCorner): corners[k] its boundary's, corners[count] its
/// centre's; false if any is not finite.
inline bool PlaceFanCorners(const RasterFrame& f, const Fan& fan, Corner corners[5])
{
  const int n = fan.count;
  bool finite = PlaceCorner(f, fan.centre, corners[n]);
  for (int k = 0; k < n; ++k)
  {
    finite = finite && PlaceCorner(f, fan.boundary[k], corners[k]);
  }
  return finite;
}

/// The attribute values of a placed corner, per shading mode (see Mode).
inline void ValueCorner(const RasterFrame& f, Mode mode, Corner& c)
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
  // screen space over each triangle (PerspectiveInterpolation), and so is their difference,
  // formed here without cancellation: a segment thin against its depth (a small cell far
  // off) changes 1 / w by less than a float resolves, and the two faces' 1 / w, each
  // rounded, would give its length from their last bits (ExactSegmentLength).
  const PerspectiveInterpolation& view = f.interpolation;
  const double rayX = (v.x + view.shiftX) * view.scaleX;
  const double rayY = (v.y + view.shiftY) * view.scaleY;
  const double ray = std::sqrt(1.0 + rayX * rayX + rayY * rayY);
  const double w = 1.0 / (view.inverseWScale * v.z + view.inverseWOffset);
  const double depth = v.thickness / ray, frontW = 1.0 / w, backW = 1.0 / (w + depth);
  c.values[0] = frontW * v.scalarFront;
  c.values[1] = frontW;
  c.values[2] = backW * v.scalarBack;
  c.values[3] = backW;
  c.values[4] = rayX;
  c.values[5] = rayY;
  c.values[6] = v.z;
  c.values[7] = -depth * frontW * backW; // backW - frontW
}

/// The planes of the triangle (a, b, c) over the tile; false for a triangle without area.
inline bool SetUpPlanes(const TileTarget& tile, int attributes, const Corner* const v[3], Planes& p)
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

/// The pixels [x0, x1] x [y0, y1] within [firstX, lastX] x [firstY, lastY] whose centres
/// lie in the bounding box of the triangle (X, Y), snapped; false if there are none.
inline bool TrianglePixels(const double X[3], const double Y[3], int firstX, int lastX,
  int firstY, int lastY, int& x0, int& x1, int& y0, int& y1)
{
  const auto [minX, maxX] = std::minmax({ X[0], X[1], X[2] });
  const auto [minY, maxY] = std::minmax({ Y[0], Y[1], Y[2] });
  // Pixel centres x + 0.5 within the bounding box and the bounds.
  const double bx0 = std::max<double>(firstX, std::ceil(minX - 0.5)),
               bx1 = std::min<double>(lastX, std::floor(maxX - 0.5));
  const double by0 = std::max<double>(firstY, std::ceil(minY - 0.5)),
               by1 = std::min<double>(lastY, std::floor(maxY - 0.5));
  if (!(bx0 <= bx1 && by0 <= by1))
  {
    return false;
  }
  x0 = static_cast<int>(bx0);
  x1 = static_cast<int>(bx1);
  y0 = static_cast<int>(by0);
  y1 = static_cast<int>(by1);
  return true;
}

/// Whether every corner of the triangle (X, Y), finite, lies within FixedPointLimit, so that
/// its edges can be set up exactly (SetUpEdges); else it is clipped first (CoverGuardBand).
inline bool WithinFixedPoint(const double X[3], const double Y[3])
{
  for (int k = 0; k < 3; ++k)
  {
    if (!(std::fabs(X[k]) < FixedPointLimit && std::fabs(Y[k]) < FixedPointLimit))
    {
      return false;
    }
  }
  return true;
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
inline bool SetUpEdges(const double X[3], const double Y[3], Edges& e)
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
inline int ClipToBox(const double X[3], const double Y[3], double lo, double hiX, double hiY,
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

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_RASTER_CORNERS_INL_H_
