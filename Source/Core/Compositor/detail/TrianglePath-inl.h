// SPDX-License-Identifier: BSD-3-Clause
// Internal: the triangle path. A fan drawn triangle by triangle, each set up on its own
// (corners, planes, edges) and covered span by span: VTK-compatible shading of whole spans,
// pre-integrated fragments waiting to be shaded, the blend modes' reductions, small triangles
// pixel by pixel, clipped fragments one at a time, and triangles beyond the fixed-point range
// through the guard band.
// A fragment of the per-tile rasterizer, compiled once per instruction set: whoever includes
// it does so under Highway's per-target re-inclusion (hwy/foreach_target.h), and it includes
// what it uses and opens its own per-target namespace, so it reads alone.

// Highway's per-target include guard: once for each target.
#if defined(MTPT_COMPOSITOR_TRIANGLE_PATH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef MTPT_COMPOSITOR_TRIANGLE_PATH_INL_H_
#undef MTPT_COMPOSITOR_TRIANGLE_PATH_INL_H_
#else
#define MTPT_COMPOSITOR_TRIANGLE_PATH_INL_H_
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
  const double X[3] = { v[0]->X, v[1]->X, v[2]->X }, Y[3] = { v[0]->Y, v[1]->Y, v[2]->Y };
  int x0, x1, y0, y1;
  if (!TrianglePixels(X, Y, tile.x0, tile.x0 + tile.width - 1, tile.y0, tile.y0 + tile.height - 1,
        x0, x1, y0, y1))
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
  Edges edges;
  if (WithinFixedPoint(X, Y))
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

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#endif // MTPT_COMPOSITOR_TRIANGLE_PATH_INL_H_
