// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Compositor.h"

#include "detail/Parallel.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace mtpt
{

namespace
{

/// Sub-pixel precision of the fixed-point rasterizer (as GPUs and Mesa's rasterizers snap
/// vertices): 8 bits.
constexpr int SubpixelBits = 8;
constexpr double SubpixelScale = 1 << SubpixelBits;
/// Window coordinates within +-2^22 pixels keep every edge-function product below 2^62.
constexpr double FixedPointLimit = 4194304.0;

struct ScreenTriangle
{
  double x[3], y[3];          ///< window coordinates
  int xmin, xmax, ymin, ymax; ///< pixels whose centres may be covered (inclusive)
};

/// Window-space triangle `t` (slot t/4, triangle t%4); false if it cannot cover a pixel
/// centre (zero area, off screen, non-finite).
inline bool SetUp(const TetVertex* vertices, const std::uint32_t* indices, std::size_t t, int width,
  int height, ScreenTriangle& s)
{
  const std::uint32_t* tri = indices + 12 * (t / 4) + 3 * (t % 4);
  if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
  {
    return false; // padding of a class-1 slot, or a degenerate slot
  }
  double minX = 1e300, maxX = -1e300, minY = 1e300, maxY = -1e300;
  for (int k = 0; k < 3; ++k)
  {
    const TetVertex& v = vertices[tri[k]];
    // Snapped to the rasterizer's sub-pixel grid first, so that the pixel range below is
    // the one of the triangle actually rasterized (a centre just outside the unsnapped
    // triangle may be inside the snapped one, and its neighbour then owns no such pixel).
    s.x[k] = std::nearbyint((static_cast<double>(v.x) + 1.0) * 0.5 * width * SubpixelScale) /
      SubpixelScale;
    s.y[k] = std::nearbyint((static_cast<double>(v.y) + 1.0) * 0.5 * height * SubpixelScale) /
      SubpixelScale;
    minX = std::min(minX, s.x[k]);
    maxX = std::max(maxX, s.x[k]);
    minY = std::min(minY, s.y[k]);
    maxY = std::max(maxY, s.y[k]);
  }
  if (!(maxX - minX < 1e300) || !(maxY - minY < 1e300))
  {
    return false; // NaN or infinite
  }
  // Pixel centres x + 0.5 within [minX, maxX].
  const double x0 = std::ceil(minX - 0.5), x1 = std::floor(maxX - 0.5);
  const double y0 = std::ceil(minY - 0.5), y1 = std::floor(maxY - 0.5);
  // Clamped on both sides before the conversions: a finite vertex far off screen would
  // otherwise overflow int (undefined behaviour; found by the fuzzer).
  s.xmin = static_cast<int>(std::min(std::max(0.0, x0), static_cast<double>(width)));
  s.xmax = static_cast<int>(std::max(std::min(width - 1.0, x1), -1.0));
  s.ymin = static_cast<int>(std::min(std::max(0.0, y0), static_cast<double>(height)));
  s.ymax = static_cast<int>(std::max(std::min(height - 1.0, y1), -1.0));
  return s.xmin <= s.xmax && s.ymin <= s.ymax;
}

/// Edge function of edge a->b at point p, and whether the edge owns points exactly on it
/// (top-left rule for counter-clockwise triangles, y up: a left edge goes down, a top edge
/// is horizontal and goes left).
struct Edge
{
  std::int64_t a, b, c; ///< E(p) = a * px + b * py + c, fixed point
  bool owns;
};

inline Edge MakeEdge(std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by)
{
  Edge e;
  e.a = ay - by;
  e.b = bx - ax;
  e.c = ax * by - ay * bx;
  const bool left = by < ay;
  const bool top = by == ay && bx < ax;
  e.owns = left || top;
  return e;
}

constexpr std::int64_t Step = std::int64_t(1) << SubpixelBits;
constexpr std::int64_t Half = Step / 2;

/**
 * Calls covered(x, y, e) for every pixel centre in rows [ymin, ymax] and columns [xmin,
 * xmax] that the triangle (x[k], y[k]) covers by the top-left rule on the 8-bit sub-pixel
 * grid (every coordinate within FixedPointLimit). e[k] is the edge function opposite
 * vertex k (CCW-oriented, so positive inside); e[k] / (e[0] + e[1] + e[2]) is vertex k's
 * barycentric weight. Returns false when the triangle has no area.
 */
template <typename Covered>
bool CoverTriangle(
  const double x[3], const double y[3], int xmin, int xmax, int ymin, int ymax, Covered&& covered)
{
  std::int64_t fx[3], fy[3];
  for (int k = 0; k < 3; ++k)
  {
    fx[k] = static_cast<std::int64_t>(std::nearbyint(x[k] * SubpixelScale));
    fy[k] = static_cast<std::int64_t>(std::nearbyint(y[k] * SubpixelScale));
  }
  const std::int64_t area2 = (fx[1] - fx[0]) * (fy[2] - fy[0]) - (fy[1] - fy[0]) * (fx[2] - fx[0]);
  if (area2 == 0)
  {
    return false;
  }
  // Edge k is opposite vertex k, oriented so that the inside is positive.
  Edge edges[3];
  for (int k = 0; k < 3; ++k)
  {
    int a = (k + 1) % 3, b = (k + 2) % 3;
    if (area2 < 0)
    {
      std::swap(a, b);
    }
    edges[k] = MakeEdge(fx[a], fy[a], fx[b], fy[b]);
  }
  for (int y = ymin; y <= ymax; ++y)
  {
    const std::int64_t py = y * Step + Half;
    const std::int64_t px0 = xmin * Step + Half;
    std::int64_t e[3];
    for (int k = 0; k < 3; ++k)
    {
      e[k] = edges[k].a * px0 + edges[k].b * py + edges[k].c;
    }
    for (int x = xmin; x <= xmax;
         ++x, e[0] += edges[0].a * Step, e[1] += edges[1].a * Step, e[2] += edges[2].a * Step)
    {
      bool inside = true;
      for (int k = 0; k < 3; ++k)
      {
        inside = inside && (e[k] > 0 || (e[k] == 0 && edges[k].owns));
      }
      if (inside)
      {
        covered(x, y, e);
      }
    }
  }
  return true;
}

/**
 * The shading of one triangle: its vertices classified once (lazily: at the first covered
 * pixel), then each fragment from barycentric weights, with the OpenGL shaders' math,
 * GL_LEQUAL against the opaque depth and "over" blending into `rgba`.
 */
class TriangleShader
{
public:
  TriangleShader(const TetVertex* const corners[3], const CompositeSettings& settings,
    float inverseUnit, int width, float* rgba)
    : Corners(corners)
    , Settings(settings)
    , PreIntegration(settings.shading == Shading::PreIntegrated ? settings.preIntegration : nullptr)
    , Exact(this->PreIntegration && settings.interpolation.perspective)
    , InverseUnit(inverseUnit)
    , Width(width)
    , Image(rgba)
  {
  }

  /// Shades and blends the fragment at pixel (x, y) with barycentric weights l[3].
  void Fragment(int x, int y, const double l[3])
  {
    if (!this->Classified)
    {
      this->Classify();
    }
    float f[6];
    for (int c = 0; c < 6; ++c)
    {
      f[c] = static_cast<float>(l[0] * this->Attributes[0][c] + l[1] * this->Attributes[1][c] +
        l[2] * this->Attributes[2][c]);
    }
    if (this->Exact)
    {
      this->PerspectiveExact(l, f);
    }
    if (f[5] < -1.0f || f[5] > 1.0f)
    {
      return; // clipped by the near or far plane
    }
    const std::size_t pixel = static_cast<std::size_t>(y) * this->Width + x;
    const float* opaqueDepth = this->Settings.opaqueDepth;
    if (opaqueDepth && 0.5f * (f[5] + 1.0f) > opaqueDepth[pixel])
    {
      return;
    }
    if (this->PreIntegration)
    {
      // f[0..3] become the segment's colour and opacity.
      this->PreIntegration->Segment(
        this->Settings.transferFunction, f[0], f[1], f[4], this->InverseUnit, f);
    }
    else
    {
      f[3] = 1.0f - std::exp(-f[3] * f[4] * this->InverseUnit);
    }
    const float opacity = f[3];
    if (!(opacity > 0.0f))
    {
      return;
    }
    float* d = this->Image + 4 * pixel;
    const float keep = 1.0f - opacity;
    d[0] = opacity * f[0] + keep * d[0];
    d[1] = opacity * f[1] + keep * d[1];
    d[2] = opacity * f[2] + keep * d[2];
    d[3] = opacity + keep * d[3];
  }

private:
  /// Per vertex: r, g, b, attenuation (pre-integrated: front scalar, back scalar, unused,
  /// unused), then segment length and NDC z; for perspective-exact pre-integration also
  /// 1 / w of front and back and the eye ray direction's x and y per unit depth.
  void Classify()
  {
    const TransferFunctionTable& tf = this->Settings.transferFunction;
    const PerspectiveInterpolation& view = this->Settings.interpolation;
    for (int k = 0; k < 3; ++k)
    {
      const TetVertex& v = *this->Corners[k];
      if (this->PreIntegration)
      {
        this->Attributes[k][0] = v.scalarFront;
        this->Attributes[k][1] = v.scalarBack;
        this->Attributes[k][2] = this->Attributes[k][3] = 0.0f;
      }
      else
      {
        float front[4], back[4];
        tf.Lookup(v.scalarFront, front);
        tf.Lookup(v.scalarBack, back);
        for (int c = 0; c < 4; ++c)
        {
          this->Attributes[k][c] = 0.5f * (front[c] + back[c]);
        }
      }
      this->Attributes[k][4] = v.thickness;
      this->Attributes[k][5] = v.z;
      if (this->Exact)
      {
        this->RayX[k] = (v.x + view.shiftX) * view.scaleX;
        this->RayY[k] = (v.y + view.shiftY) * view.scaleY;
        const double ray =
          std::sqrt(1.0 + this->RayX[k] * this->RayX[k] + this->RayY[k] * this->RayY[k]);
        const double w = 1.0 / (view.inverseWScale * v.z + view.inverseWOffset);
        this->FrontW[k] = 1.0 / w;
        this->BackW[k] = 1.0 / (w + v.thickness / ray);
      }
    }
    this->Classified = true;
  }

  /// Front and back scalars and the segment length, perspective-correctly.
  void PerspectiveExact(const double l[3], float f[6]) const
  {
    const double front = l[0] * FrontW[0] + l[1] * FrontW[1] + l[2] * FrontW[2];
    const double back = l[0] * BackW[0] + l[1] * BackW[1] + l[2] * BackW[2];
    const double dx = l[0] * RayX[0] + l[1] * RayX[1] + l[2] * RayX[2];
    const double dy = l[0] * RayY[0] + l[1] * RayY[1] + l[2] * RayY[2];
    f[0] = static_cast<float>(
      (l[0] * FrontW[0] * Attributes[0][0] + l[1] * FrontW[1] * Attributes[1][0] +
        l[2] * FrontW[2] * Attributes[2][0]) /
      front);
    f[1] =
      static_cast<float>((l[0] * BackW[0] * Attributes[0][1] + l[1] * BackW[1] * Attributes[1][1] +
                           l[2] * BackW[2] * Attributes[2][1]) /
        back);
    f[4] = static_cast<float>(
      std::max(0.0, 1.0 / back - 1.0 / front) * std::sqrt(1.0 + dx * dx + dy * dy));
  }

  const TetVertex* const* Corners;
  const CompositeSettings& Settings;
  const PreIntegrationTable* PreIntegration;
  const bool Exact;
  const float InverseUnit;
  const int Width;
  float* Image;
  bool Classified = false;
  float Attributes[3][6] = {};
  double FrontW[3] = { 1, 1, 1 }, BackW[3] = { 1, 1, 1 }, RayX[3] = {}, RayY[3] = {};
};

/// Whether every vertex of the set-up triangle is inside the fixed-point range.
inline bool InFixedPointRange(const ScreenTriangle& s)
{
  for (int k = 0; k < 3; ++k)
  {
    if (!(std::fabs(s.x[k]) < FixedPointLimit && std::fabs(s.y[k]) < FixedPointLimit))
    {
      return false;
    }
  }
  return true;
}

/**
 * Clips the triangle (x[k], y[k]) to the box [lo, hi] in both axes (Sutherland-Hodgman),
 * writing the polygon's vertices to px, py (at most 7) and returning their number.
 */
int ClipToBox(const double x[3], const double y[3], double lo, double hiX, double hiY, double px[9],
  double py[9])
{
  double ax[9], ay[9];
  int n = 3;
  for (int k = 0; k < 3; ++k)
  {
    px[k] = x[k];
    py[k] = y[k];
  }
  // Planes: x >= lo, x <= hiX, y >= lo, y <= hiY, as signed distances.
  for (int plane = 0; plane < 4 && n > 0; ++plane)
  {
    auto distance = [plane, lo, hiX, hiY](double u, double v)
    {
      switch (plane)
      {
        case 0:
          return u - lo;
        case 1:
          return hiX - u;
        case 2:
          return v - lo;
        default:
          return hiY - v;
      }
    };
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

/// Pixels within this distance of the viewport are rasterized from a triangle clipped to
/// it; the guard band keeps clipped edges far from every pixel centre that can be drawn.
constexpr double GuardBand = 1 << 20;

/**
 * Rasterizes a set-up triangle over the pixel range in `s` (the caller may have clipped
 * it): coverage by the top-left rule on 8-bit sub-pixel fixed point, shading by
 * TriangleShader. A triangle with a vertex beyond the fixed-point range (a near-plane piece
 * far off screen, say) is clipped to a guard band around the viewport first, as OpenGL's
 * rasterizers clip it; its attributes are still interpolated over the whole triangle, so
 * the pixels drawn are the same. True if it covered a pixel.
 */
bool RasterizeTriangle(const TetVertex* vertices, const std::uint32_t* tri, const ScreenTriangle& s,
  int width, int height, const CompositeSettings& settings, float inverseUnit, float* rgba)
{
  const TetVertex* corners[3] = { vertices + tri[0], vertices + tri[1], vertices + tri[2] };
  TriangleShader shader(corners, settings, inverseUnit, width, rgba);
  bool any = false;
  if (InFixedPointRange(s))
  {
    CoverTriangle(s.x, s.y, s.xmin, s.xmax, s.ymin, s.ymax,
      [&](int x, int y, const std::int64_t e[3])
      {
        const double inverseArea = 1.0 / static_cast<double>(e[0] + e[1] + e[2]);
        const double l[3] = { e[0] * inverseArea, e[1] * inverseArea, e[2] * inverseArea };
        shader.Fragment(x, y, l);
        any = true;
      });
    return any;
  }
  // Barycentric weights of the whole triangle as planes over the window: l[k] = a[k] X +
  // b[k] Y + c[k], from the edge opposite vertex k.
  const double area2 =
    (s.x[1] - s.x[0]) * (s.y[2] - s.y[0]) - (s.y[1] - s.y[0]) * (s.x[2] - s.x[0]);
  if (!(std::fabs(area2) > 0.0) || !std::isfinite(area2))
  {
    return false;
  }
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; ++k)
  {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    a[k] = (s.y[i] - s.y[j]) / area2;
    b[k] = (s.x[j] - s.x[i]) / area2;
    c[k] = (s.x[i] * s.y[j] - s.x[j] * s.y[i]) / area2;
  }
  double px[9], py[9];
  const int n = ClipToBox(s.x, s.y, -GuardBand, width + GuardBand, height + GuardBand, px, py);
  for (int k = 1; k + 1 < n; ++k)
  {
    const double fanX[3] = { px[0], px[k], px[k + 1] }, fanY[3] = { py[0], py[k], py[k + 1] };
    CoverTriangle(fanX, fanY, s.xmin, s.xmax, s.ymin, s.ymax,
      [&](int x, int y, const std::int64_t*)
      {
        const double X = x + 0.5, Y = y + 0.5;
        const double l[3] = { a[0] * X + b[0] * Y + c[0], a[1] * X + b[1] * Y + c[1],
          a[2] * X + b[2] * Y + c[2] };
        shader.Fragment(x, y, l);
        any = true;
      });
  }
  return any;
}

} // namespace

namespace
{

/// A slot that draws nothing (not drawable, or culled): its indices all repeat its first
/// vertex, while every drawn slot's first triangle has distinct corners. Reading two
/// indices instead of five vertices keeps the pass over culled slots cheap.
inline bool DegenerateSlot(const std::uint32_t* indices, std::int64_t slot)
{
  return indices[12 * slot] == indices[12 * slot + 1];
}

/// Rows [y0, y1] and columns [x0, x1] whose pixel centres the slot's 5 vertices span
/// (empty when y0 > y1 or x0 > x1). All of the slot's triangles lie inside.
inline void SlotPixels(
  const TetVertex* slot, int width, int height, int& x0, int& x1, int& y0, int& y1)
{
  float minX = slot[0].x, maxX = slot[0].x, minY = slot[0].y, maxY = slot[0].y;
  for (int k = 1; k < 5; ++k)
  {
    minX = std::min(minX, slot[k].x);
    maxX = std::max(maxX, slot[k].x);
    minY = std::min(minY, slot[k].y);
    maxY = std::max(maxY, slot[k].y);
  }
  // Conservative (1/128 pixel of slack, more than sub-pixel snapping moves a vertex): SetUp
  // decides exactly. The clamps keep
  // the conversions to int defined for huge or infinite values; NaN gives an empty range.
  const float lx = (minX + 1.0f) * 0.5f * width - 0.5f, hx = (maxX + 1.0f) * 0.5f * width - 0.5f;
  const float ly = (minY + 1.0f) * 0.5f * height - 0.5f, hy = (maxY + 1.0f) * 0.5f * height - 0.5f;
  auto low = [](float v, int size)
  { return v > 0.0f ? (v < size ? static_cast<int>(std::ceil(v - 1.0f / 128)) : size) : 0; };
  auto high = [](float v, int size)
  {
    return v < size - 1.0f ? (v > -1.0f ? static_cast<int>(std::floor(v + 1.0f / 128)) : -1)
                           : size - 1;
  };
  x0 = low(lx, width);
  x1 = high(hx, width);
  y0 = low(ly, height);
  y1 = high(hy, height);
  if (!(lx == lx && hx == hx && ly == ly && hy == hy))
  {
    y0 = 1;
    y1 = 0;
  }
}

} // namespace

PerspectiveInterpolation PerspectiveInterpolation::FromProjection(const Matrix4& p)
{
  PerspectiveInterpolation v;
  // A perspective frustum: clip w = p14 ez with p14 < 0 (the eye depth D = -ez times
  // -p14), clip z = p10 ez + p11, clip x and y free of translation terms.
  if (p[8] != 0.0 || p[9] != 0.0 || p[12] != 0.0 || p[13] != 0.0 || !(p[14] < 0.0) ||
    p[15] != 0.0 || !(p[0] != 0.0) || !(p[5] != 0.0) || p[1] != 0.0 || p[4] != 0.0 || p[3] != 0.0 ||
    p[7] != 0.0 || !(std::fabs(p[11]) > 0.0))
  {
    return v;
  }
  v.perspective = true;
  // z_ndc = p10 / p14 - p11 / (p14 D), so 1 / D = (p10 - p14 z_ndc) / p11.
  v.inverseWScale = -p[14] / p[11];
  v.inverseWOffset = p[10] / p[11];
  // x_ndc = p0 ex / (-p14 D) + p2 / p14, so ex / D = (x_ndc - p2 / p14) (-p14 / p0).
  v.scaleX = -p[14] / p[0];
  v.shiftX = -p[2] / p[14];
  v.scaleY = -p[14] / p[5];
  v.shiftY = -p[6] / p[14];
  return v;
}

void Compositor::Composite(const TetVertex* vertices, const std::uint32_t* indices,
  std::size_t count, const CompositeSettings& settings, std::vector<float>& rgba, int threads)
{
  const int width = std::max(0, settings.width), height = std::max(0, settings.height);
  const std::size_t values = 4 * static_cast<std::size_t>(width) * height;
  if (!settings.accumulate || rgba.size() != values)
  {
    rgba.assign(values, 0.0f);
  }
  this->Rasterized = 0;
  if (width == 0 || height == 0 || count == 0 || !settings.transferFunction.table ||
    settings.transferFunction.size < 1)
  {
    return;
  }
  const int nthreads = detail::ResolveThreads(threads);
  const auto slots = static_cast<std::int64_t>(count);

  // Balance: count the slots that reach a pixel by their first row, then cut the image
  // into one band of rows per thread holding about the same number of slots.
  this->RowCounts.assign(static_cast<std::size_t>(nthreads) * (height + 1), 0);
#pragma omp parallel num_threads(nthreads)
  {
    std::uint32_t* rows =
      this->RowCounts.data() + static_cast<std::size_t>(omp_get_thread_num()) * (height + 1);
#pragma omp for schedule(static)
    for (std::int64_t k = 0; k < slots; ++k)
    {
      if (DegenerateSlot(indices, k))
      {
        continue;
      }
      int x0, x1, y0, y1;
      SlotPixels(vertices + 5 * k, width, height, x0, x1, y0, y1);
      if (x0 <= x1 && y0 <= y1)
      {
        ++rows[y0];
      }
    }
  }
  std::vector<std::uint64_t> cumulative(static_cast<std::size_t>(height) + 1, 0);
  for (int y = 0; y < height; ++y)
  {
    std::uint64_t n = 0;
    for (int t = 0; t < nthreads; ++t)
    {
      n += this->RowCounts[static_cast<std::size_t>(t) * (height + 1) + y];
    }
    cumulative[y + 1] = cumulative[y] + n;
  }
  const int bands = std::min(nthreads, height);
  std::vector<int> bandStart(static_cast<std::size_t>(bands) + 1, height);
  bandStart[0] = 0;
  for (int b = 1; b < bands; ++b)
  {
    const std::uint64_t target = cumulative[height] * b / bands;
    int y = static_cast<int>(
      std::lower_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin());
    bandStart[b] = std::max(bandStart[b - 1] + 1, std::min(y, height - (bands - b)));
  }

  // Each band: every slot in order, whole tetrahedra rejected by their bounding box, the
  // rest rasterized triangle by triangle into this band's rows only.
  const float inverseUnit = static_cast<float>(1.0 / settings.unitDistance);
  if (settings.shading == Shading::PreIntegrated &&
    (!settings.preIntegration ||
      settings.preIntegration->integrals.size() <
        4 * static_cast<std::size_t>(settings.transferFunction.size)))
  {
    return; // no integral functions for this table: nothing can be shaded
  }
  std::size_t rasterized = 0;
#pragma omp parallel for num_threads(nthreads) schedule(static, 1) reduction(+ : rasterized)
  for (int band = 0; band < bands; ++band)
  {
    const int rowBegin = bandStart[band], rowEnd = bandStart[band + 1] - 1;
    ScreenTriangle s{};
    for (std::int64_t k = 0; k < slots; ++k)
    {
      if (DegenerateSlot(indices, k))
      {
        continue;
      }
      int sx0, sx1, sy0, sy1;
      SlotPixels(vertices + 5 * k, width, height, sx0, sx1, sy0, sy1);
      if (sx0 > sx1 || sy0 > sy1 || sy1 < rowBegin || sy0 > rowEnd)
      {
        continue;
      }
      for (std::size_t t = 4 * static_cast<std::size_t>(k); t < 4 * static_cast<std::size_t>(k) + 4;
           ++t)
      {
        if (!SetUp(vertices, indices, t, width, height, s) || s.ymax < rowBegin || s.ymin > rowEnd)
        {
          continue;
        }
        s.ymin = std::max(s.ymin, rowBegin);
        s.ymax = std::min(s.ymax, rowEnd);
        rasterized += RasterizeTriangle(vertices, indices + 12 * (t / 4) + 3 * (t % 4), s, width,
                        height, settings, inverseUnit, rgba.data())
          ? 1
          : 0;
      }
    }
  }
  this->Rasterized = rasterized;
}

} // namespace mtpt
