// SPDX-License-Identifier: BSD-3-Clause
// Internal: the compositor's per-tile rasterizer, written once (TileRaster.cxx) and compiled
// for every instruction set Google Highway targets, the best chosen at run time. Binning
// and threading stay in Compositor.cxx; this is the per-pixel math only (the split of
// Intel's MaskedOcclusionCulling).
#ifndef mtpt_detail_TileRaster_h
#define mtpt_detail_TileRaster_h

#include "mtpt/Lighting.h"
#include "mtpt/Records.h"
#include "mtpt/Shading.h"
#include "mtpt/TransferFunctionTable.h"

#include <cstddef>
#include <cstdint>

namespace mtpt
{
namespace detail
{

/// What every tile of a frame shares.
struct RasterFrame
{
  int width = 0, height = 0; ///< the image
  TransferFunctionTable transferFunction;
  const PreIntegrationTable* preIntegration = nullptr; ///< null: VTK-compatible shading
  bool vertexColours = false; ///< the records hold colours (CompositeSettings::vertexColours)
  bool clipToRange = false;   ///< CompositeSettings::depthRange is set (TileTarget::range)
  DepthClipping clipping;
  ClipPlanes planes; ///< cut the fragments of fans marked Fan::straddles
  PerspectiveInterpolation interpolation;
  float inverseUnit = 1.0f; ///< 1 / ScalarOpacityUnitDistance
  /// A mode other than Composite reduces fragments into the tile's planes (ReduceFragment).
  BlendMode blendMode = BlendMode::Composite;
  const IntensityTable* intensity = nullptr;  ///< average and additive modes
  double averageRange[2] = { 0.0, 0.0 };       ///< average mode: AverageRangeEntries
  /// VTK-compatible fans drawn whole where they can be (FanPath-inl.h), which gives the
  /// image of drawing them triangle by triangle bit for bit; false (tests) draws them so.
  bool fanPath = true;
};

/**
 * One tile: its pixels, its image and opaque depth (TileSize x TileSize each, row-major,
 * row 0 at the bottom, whatever part of it lies outside the image). In a blend mode other
 * than Composite the image's planes hold, per pixel, the reduced value (R: the extreme
 * scalar's entry coordinate, or the sum of o x times length), the length summed (G,
 * average), and whether a fragment reached the pixel (A: 1).
 */
struct TileTarget
{
  int x0 = 0, y0 = 0;           ///< the tile's first pixel in the image
  int width = 0, height = 0;    ///< its pixels inside the image
  float* rgba = nullptr;        ///< R, G, B, A planes of TileSize * TileSize floats
  const float* depth = nullptr; ///< opaque depth; null: none
  const float* range = nullptr; ///< depth peeling: near and far window depth per pixel
  /// Shading: the lighting of the fan being drawn (each fragment's colour c becomes
  /// clamp(scale c + offset, 0, 1)); null: unlit.
  const LightFactors* light = nullptr;
};

/// Work counted while rasterizing.
struct RasterCounts
{
  std::size_t triangles = 0; ///< triangles that covered a pixel of the tile (set up)
  /// Pixels covered by the fans drawn (shaded, or skipped behind opaque pixels).
  std::size_t fragments = 0;
  std::size_t hidden = 0; ///< fans skipped whole: every pixel of their box opaque already
  std::size_t fanVectors = 0; ///< vectors the fan path tested for coverage
};

/**
 * Draws fans[0, count), in that order, front to back (the first nearest), under what the
 * tile holds; pixels already opaque skip the fragments behind them (OpaqueAlpha). With
 * `lights` (count entries, composite blending only), fan e is lit by lights[e].
 * Thread safety: writes only the tile's image and `counts`.
 */
void RasterizeTile(const RasterFrame& frame, const TileTarget& tile, const Fan* fans,
  std::size_t count, RasterCounts& counts, const LightFactors* lights = nullptr);

/// The instruction set RasterizeTile runs with here (e.g. "AVX2"), for reports.
const char* RasterTargetName();

/**
 * opacity[i] = 1 - exp(-density[i]) computed exactly as RasterizeTile's VTK-compatible
 * fragments compute it (the SIMD approximation), for tests of its error.
 */
void OpacitiesOfDensities(const float* density, float* opacity, std::size_t count);

/**
 * rgba[4i, 4i + 4) = PreIntegrationTable::Segment of fragment i, computed as RasterizeTile's
 * pre-integrated fragments compute it (several fragments per SIMD vector), for tests.
 */
void PreIntegratedSegments(const TransferFunctionTable& tf, const PreIntegrationTable& table,
  const float* front, const float* back, const float* length, float inverseUnit, float* rgba,
  std::size_t count);

/**
 * mean[i] = IntensityTable::Mean over [u0[i], u1[i]] computed as RasterizeTile's average and
 * additive fragments compute it (in float, several per vector), for tests.
 */
void IntensityMeans(const TransferFunctionTable& tf, const IntensityTable& table, const float* u0,
  const float* u1, float* mean, std::size_t count);

} // namespace detail
} // namespace mtpt

#endif
