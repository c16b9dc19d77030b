// SPDX-License-Identifier: BSD-3-Clause
// The fragment loop's floor, for measurements (mtpt_bench_compositor --floor): the core's
// fan path fragment (detail/FanPath-inl.h) and the fragments it includes, compiled once per
// instruction set as the rasterizer compiles them, with the loops below beside them.
//
// A ladder of loops over one tile, each adding one cost of the fan path's fragment loop to
// the one below, every vector's lanes all fragments (FloorRung):
//   Registers  the floor: a fragment's exponential and its blend under eight pixel vectors
//              held in registers, its values already in registers;
//   Memory     the blend under the tile's pixels in memory (load, blend, store: BlendUnder);
//   Planes     the six values from their planes (one multiply-add each), the fragment's depth
//              against the near and far planes and the opaque depth (ShadeVector's);
//   Lookups    each lane's values from its own triangle's planes, chosen by the spokes
//              (FanLaneValues), as the fan path does;
//   Coverage   the silhouette's edges and the pixels already opaque tested first (FanPath::Rows).
// What the real loop costs beyond the top rung is the set-up per fan and the lanes a fan's
// box leaves idle (Documentation/compositor.md, "The floor").
#include "FragmentFloor.h"

#include <cstddef>
#include <cstdint>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "FragmentFloor.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

#include <hwy/highway.h>

#include "detail/FanPath-inl.h"
#include "detail/RasterCorners-inl.h"
#include "detail/RasterPixels-inl.h"

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace bench
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;
using namespace mtpt::detail::HWY_NAMESPACE;
using mtpt::detail::RasterFrame;
using mtpt::detail::TileTarget;

/// The rungs of the floor's ladder (see above), in order.
enum class FloorRung
{
  Registers,
  Memory,
  Planes,
  Lookups,
  Coverage
};

#if HWY_TARGET != HWY_SCALAR

/// A fragment's density in the rungs: the pixels' alpha grows by about this much a fragment,
/// so that none turns opaque (which would skip fragments) in billions of them per tile.
constexpr float FloorDensity = 1e-10f;

/// A fan of four triangles around the tile's centre, for the rungs with lane lookups: its
/// spokes and edges, and planes of its triangles whose values stay within a fragment's range.
struct FloorFan
{
  FanPlanes planes;
  FanGeometry geometry;

  FloorFan()
  {
    // A square of 60 pixels around the centre of the tile, corners on the diagonals.
    this->geometry.triangles = 4;
    this->geometry.cx = this->geometry.cy = 32 * 256;
    const std::int32_t corner[4][2] = { { 30, 30 }, { -30, 30 }, { -30, -30 }, { 30, -30 } };
    for (int k = 0; k < 4; ++k)
    {
      this->geometry.x[k] = corner[k][0] * 256;
      this->geometry.y[k] = corner[k][1] * 256;
    }
    FanEdges(4, this->geometry);
    this->planes.Clear();
    for (int a = 0; a < 6; ++a)
    {
      for (int k = 0; k < 4; ++k)
      {
        // r, g, b in [0, 1], z inside the view, and an attenuation so small (FloorDensity)
        // that the tile's pixels never turn opaque however often the loop goes over them.
        this->planes.base[a][k] = a < 3 ? 0.2f + 0.1f * k
          : a == 3                      ? FloorDensity * (1 + k)
          : a == 4                      ? 0.5f
                                        : -0.5f;
        this->planes.dx[a][k] = a == 3 ? 0.0f : 1e-4f * (a + 1);
        this->planes.dy[a][k] = a == 3 ? 0.0f : -1e-4f * (k + 1);
      }
    }
    this->planes.triangles = 4;
  }
};

/// The floor: `vectors` vectors of fragments blended under eight independent pixel vectors
/// (as a fan's consecutive vectors are), each fragment's density and colour already in
/// registers, changed a little every time. Returns a sum of the pixels.
HWY_NOINLINE float FloorInRegisters(std::size_t vectors)
{
  const FragmentTag d;
  using V = hn::Vec<FragmentTag>;
  constexpr int pixels = 8;
  const V one = hn::Set(d, 1.0f), inverseUnit = hn::Set(d, 2.0f);
  V colour[pixels][3], alpha[pixels], density = hn::Set(d, FloorDensity);
  const V step = hn::Set(d, FloorDensity * 1e-6f);
  const V c[3] = { hn::Set(d, 0.3f), hn::Set(d, 0.5f), hn::Set(d, 0.7f) };
  for (int p = 0; p < pixels; ++p)
  {
    alpha[p] = hn::Zero(d);
    for (int k = 0; k < 3; ++k)
    {
      colour[p][k] = hn::Zero(d);
    }
  }
  for (std::size_t v = 0; v < vectors; v += pixels)
  {
    for (int p = 0; p < pixels; ++p)
    {
      density = hn::Add(density, step);
      const V opacity = OpacityOfDensity(d, hn::Mul(density, inverseUnit));
      const V weight = hn::Mul(hn::Sub(one, alpha[p]), opacity);
      for (int k = 0; k < 3; ++k)
      {
        colour[p][k] = hn::MulAdd(weight, c[k], colour[p][k]);
      }
      alpha[p] = hn::Add(alpha[p], weight);
    }
  }
  V sum = hn::Zero(d);
  for (int p = 0; p < pixels; ++p)
  {
    sum = hn::Add(sum, hn::Add(alpha[p], colour[p][0]));
  }
  return hn::GetLane(hn::SumOfLanes(d, sum));
}

/// The FloorFan's silhouette edges and spokes over the tile, row by row from its first.
struct FloorEdges
{
  EdgeLanes<FragmentTag> bounding[MaxFanTriangles], spokes[MaxFanTriangles];

  /// At the tile's first row (pixel centres relative to the fan's centre).
  void Start(const FanGeometry& g)
  {
    const auto iota = hn::Iota(hn::RebindToSigned<FragmentTag>(), 0);
    const std::int64_t corner = -32 * 256 + 128; // the tile's first pixel centre
    for (int k = 0; k < 4; ++k)
    {
      this->bounding[k].Start(g.boundA[k], g.boundB[k], g.boundC[k], corner, corner, iota);
      this->spokes[k].Start(g.spokeA[k], g.spokeB[k], 0, corner, corner, iota);
    }
  }

  void NextRow()
  {
    for (int k = 0; k < 4; ++k)
    {
      this->bounding[k].NextRow();
      this->spokes[k].NextRow();
    }
  }
};

/**
 * `vectors` vectors of fragments through rung `R` (above Registers) over the tile `rgba`
 * (T x T pixels: R, G, B, A planes) with opaque depth `depth`, vector after vector along its
 * rows; returns a sum of the results, so that nothing is left out as unused.
 */
template <FloorRung R>
HWY_NOINLINE float FloorOverTile(std::size_t vectors, float* rgba, const float* depth)
{
  const FragmentTag d;
  using V = hn::Vec<FragmentTag>;
  const int lanes = static_cast<int>(hn::Lanes(d));
  RasterFrame frame;
  frame.inverseUnit = 2.0f;
  TileTarget tile;
  tile.rgba = rgba;
  tile.depth = depth;
  tile.width = tile.height = T;
  const FloorFan fan;
  FloorEdges edges;
  edges.Start(fan.geometry);
  FanPlanes planes = fan.planes;
  Planes flat; // the planes of its first triangle, for the Planes rung
  for (int a = 0; a < 6; ++a)
  {
    flat.base[a] = fan.planes.base[a][0];
    flat.dx[a] = fan.planes.dx[a][0];
    flat.dy[a] = fan.planes.dy[a][0];
  }
  V density = hn::Set(d, FloorDensity); // changed a little every time, as in Registers
  const V step = hn::Set(d, FloorDensity * 1e-6f);
  const V colour[3] = { hn::Set(d, 0.3f), hn::Set(d, 0.5f), hn::Set(d, 0.7f) };
  V sum = hn::Zero(d);
  for (std::size_t v = 0; v < vectors; ++v)
  {
    const int y = static_cast<int>((v / (T / lanes)) % T);
    const int x = static_cast<int>(v % (T / lanes)) * lanes;
    const TileRow row = RowOf(tile, y);
    auto keep = hn::FirstN(d, lanes);
    if constexpr (R == FloorRung::Memory)
    {
      density = hn::Add(density, step);
      const V opacity = OpacityOfDensity(d, hn::Mul(density, hn::Set(d, frame.inverseUnit)));
      sum = hn::Add(sum, BlendUnder(d, row, x, opacity, colour, keep));
    }
    else if constexpr (R == FloorRung::Planes)
    {
      float start[6];
      RowStart(flat, y, start);
      ShadeVector(d, frame, row, flat, start, x, keep);
    }
    else
    {
      if (x == 0)
      {
        planes.Row(d, y);
      }
      if constexpr (R == FloorRung::Coverage)
      {
        for (int k = 0; k < 4; ++k)
        {
          keep = hn::And(keep, edges.bounding[k].Inside(d, x));
        }
        keep = hn::And(keep, Transparent(d, row, x));
      }
      if (!hn::AllFalse(d, keep))
      {
        sum = hn::Add(sum, ShadeFanLanes(d, frame, row, planes, edges.spokes, x, x, keep));
      }
    }
    if (x + lanes == T) // the row's last vector: the next row, or the tile again
    {
      edges.NextRow();
      if (y + 1 == T)
      {
        edges.Start(fan.geometry);
      }
    }
  }
  return hn::GetLane(hn::SumOfLanes(d, sum)) + rgba[0];
}

#endif

/// The loop of rung `rung` (FloorRung's order); 0 on one lane (no fan path there).
float FragmentFloorImpl(int rung, std::size_t vectors, float* rgba, const float* depth)
{
#if HWY_TARGET != HWY_SCALAR
  switch (static_cast<FloorRung>(rung))
  {
    case FloorRung::Registers:
      return FloorInRegisters(vectors);
    case FloorRung::Memory:
      return FloorOverTile<FloorRung::Memory>(vectors, rgba, depth);
    case FloorRung::Planes:
      return FloorOverTile<FloorRung::Planes>(vectors, rgba, depth);
    case FloorRung::Lookups:
      return FloorOverTile<FloorRung::Lookups>(vectors, rgba, depth);
    case FloorRung::Coverage:
      return FloorOverTile<FloorRung::Coverage>(vectors, rgba, depth);
  }
#else
  (void)rung;
  (void)vectors;
  (void)rgba;
  (void)depth;
#endif
  return 0.0f;
}

/// The lanes of the fragment loops' vectors here.
std::size_t FragmentLanesImpl()
{
  return hn::Lanes(FragmentTag());
}

} // namespace HWY_NAMESPACE
} // namespace bench
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtpt
{
namespace bench
{

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

} // namespace bench
} // namespace mtpt
#endif
