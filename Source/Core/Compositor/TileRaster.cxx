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
#include <cstdint>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "TileRaster.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

#include <hwy/highway.h>

// The rasterizer's fragments (their headers say what each holds): the geometry and the
// pixels every path shares, pre-integrated segments, the blend modes' reductions, and the two
// drawing paths: fans drawn whole, and fans drawn triangle by triangle.
#include "detail/FanPath-inl.h"
#include "detail/RasterCorners-inl.h"
#include "detail/RasterPixels-inl.h"
#include "detail/Reductions-inl.h"
#include "detail/Segments-inl.h"
#include "detail/TrianglePath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

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
  WaitingFragments waiting;                // pre-integrated fragments
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
    if (!PlaceFanCorners(f, fan, corners))
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
      SegmentOfLanes(d, t, hn::Load(d, in[0]), hn::Load(d, in[1]), hn::Load(d, in[2]), colour), d,
      out[3]);
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
