// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Compositor.h
 * @brief Stage 6 of a frame on the CPU: the compositor blends the sorted tetrahedra (as fans,
 * Decompose.h) into a float RGBA image with the per-fragment math of the OpenGL path, for machines
 * where OpenGL is itself a software rasterizer. Its cost follows the fragments: a tetrahedron is
 * set up once per screen tile it touches, and in VTK-compatible shading every pixel covered
 * costs one SIMD lane (pre-integrated shading integrates each fragment on its own).
 *
 * Conventions:
 * - Window coordinates: pixel (x, y) covers [x, x+1) x [y, y+1), y up (OpenGL), its sample
 *   point is the centre (x + 0.5, y + 0.5). NDC map to window coordinates as
 *   X = (x_ndc + 1) / 2 * width, Y = (y_ndc + 1) / 2 * height; depth = (z_ndc + 1) / 2.
 *   Vertices are snapped to a 1/256-pixel grid, as GPUs and Mesa's rasterizers snap them.
 * - Coverage: a pixel belongs to a triangle if its centre is inside, or on an edge that is
 *   a top or a left edge (the top-left rule of Direct3D and of Mesa's rasterizers), so a
 *   pixel on an edge shared by two triangles is covered exactly once. Coverage is decided
 *   exactly, on 64-bit fixed point; a triangle with a vertex beyond +-2^22 pixels is first
 *   clipped to a guard band around the viewport, as OpenGL clips it.
 * - Shading, exactly as the OpenGL path's shaders, in one of two modes (Shading):
 *   VTK-compatible: each vertex is classified as the mean of the transfer function at its
 *   front and back scalars (colour rgb, attenuation a), or, with dependent components,
 *   carries its colour and attenuation (CompositeSettings::vertexColours); colour,
 *   attenuation and segment
 *   length are interpolated linearly in screen space; fragment opacity =
 *   1 - exp(-a * length / unitDistance).
 *   Pre-integrated: the front scalar, back scalar and segment length are interpolated
 *   (in perspective views exactly, see PerspectiveInterpolation) and each fragment is
 *   shaded with PreIntegrationTable::Segment's formulas (several per SIMD vector), so
 *   transfer-function features between the vertex scalars are not missed.
 * - Blending, as glBlendFuncSeparate(SRC_ALPHA, ONE_MINUS_SRC_ALPHA, ONE,
 *   ONE_MINUS_SRC_ALPHA) starting from a transparent image: the image holds premultiplied
 *   colour and coverage alpha; Resolve composites it over what lies below. It is computed
 *   front to back (C += (1 - A) a c, A += (1 - A) a: the same image up to rounding), and a
 *   pixel whose alpha reached 1 - 2^-11 skips the fragments behind it, which could change it
 *   by at most 2^-11 (an eighth of an 8-bit step).
 * - Depth: with an opaque depth image, a fragment is kept if its depth is <= the opaque
 *   depth at that pixel (GL_LEQUAL, no depth writes); fragments outside the near and far
 *   planes are dropped.
 *
 * How the work is shared (threads never write the same pixel):
 * 1. Binning: each thread takes a contiguous range of the fans (in visibility order) and
 *    appends each fan that covers a pixel centre of a tile to its own list for that tile
 *    (TileSize x TileSize pixels). Concatenated in thread order, a tile's lists are in
 *    visibility order, whatever the thread count.
 * 2. Rasterization: threads take tiles; a tile's fans are drawn front to back, a fan of
 *    VTK-compatible shading as a whole (its silhouette's edges tested a vector of a row at
 *    a time, each pixel shaded with its triangle's planes), others triangle by triangle,
 *    last first (triangles that overlap blend as OpenGL blends a slot's, in index order),
 *    span by span (exact row spans), SIMD lanes wide (Google Highway, the widest instruction
 *    set the processor has, chosen at run time). A fan whose box is all opaque already is
 *    skipped. A tile's pixels stay in its own cache-sized buffer; a tile drawn by an earlier
 *    Composite gets the new fans drawn apart and composited over it, and one drawn by an
 *    earlier CompositeBehind goes on blending under what it holds.
 * 3. Composite blending: each tile drawn marks its opaque pixels (Opaque()).
 * The image is therefore bit-identical for any thread count.
 */
#ifndef mtpt_Compositor_h
#define mtpt_Compositor_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/Lighting.h"
#include "mtpt/MeshView.h"
#include "mtpt/OpaquePixels.h"
#include "mtpt/Records.h"
#include "mtpt/Shading.h"
#include "mtpt/TransferFunctionTable.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mtpt
{

struct CompositeSettings
{
  int width = 0, height = 0;
  TransferFunctionTable transferFunction;
  Shading shading = Shading::VTKCompatible;
  /// Integral functions of `transferFunction`, required for Shading::PreIntegrated.
  const PreIntegrationTable* preIntegration = nullptr;
  double unitDistance = 1.0;
  /// Optional window depth of opaque geometry in [0, 1], width * height floats, row 0 at
  /// the bottom. Null: no occlusion.
  const float* opaqueDepth = nullptr;
  /// Pre-integrated shading in perspective views: see PerspectiveInterpolation.
  PerspectiveInterpolation interpolation;
  /**
   * Dependent components: the records hold their vertex's colour (StoreVertexColour, from
   * a decomposition with DecomposeInput::colours) instead of scalars, shaded VTK-compatibly
   * with those colours; the table is not read. `shading` must then be VTKCompatible (the
   * frame's plan decides so, CompositeSettingsFor): otherwise nothing is drawn.
   */
  bool vertexColours = false;
  /**
   * Depth peeling: per pixel a range of window depths, near then far (width * height pairs,
   * row 0 at the bottom; near > far: none). Each fragment then contributes only the part of
   * its segment inside its pixel's range (`clipping`), with the length and, in
   * pre-integrated shading, the scalars of that part (VTK-compatible shading keeps the
   * segment's colour and attenuation); the opaque depth is not read. Null: whole segments,
   * kept when their front is not behind the opaque depth.
   */
  const float* depthRange = nullptr;
  DepthClipping clipping;
  /**
   * Clipping planes in eye coordinates (`clipping` gives the eye ray of each pixel): each
   * fragment contributes only the part of its segment every plane keeps, with that part's
   * length and, in pre-integrated shading, its scalars; VTK-compatible shading keeps the
   * segment's colour and attenuation, as for depth peeling. Fans wholly clipped by one plane
   * are left out at binning, and fans no plane cuts are drawn as without planes.
   */
  ClipPlanes clipPlanes;
  /**
   * How fragments become a pixel (BlendMode). A mode other than Composite reduces each
   * pixel's fragments, in any order, to one value that Resolve maps to colour: the fans may
   * come in any order, and `intensity` (the integral of `transferFunction`, kept alive by the
   * caller) is required for the average and additive modes. `interpolation` must then be
   * the view's, as for pre-integrated shading (the scalars are interpolated as there), and
   * `vertexColours` is not supported (nothing is drawn).
   */
  BlendMode blendMode = BlendMode::Composite;
  const IntensityTable* intensity = nullptr;
  /// Average intensity: only the stretches whose scalar lies in [low, high] count (VTK's
  /// AverageIPScalarRange, in scalar units).
  double averageRange[2] = { -1e300, 1e300 };

  /// Switches to pre-integrated shading with `table` (the integral functions of
  /// transferFunction, kept alive by the caller) and the view's `interpolation`.
  void UsePreIntegration(const PreIntegrationTable& table, const PerspectiveInterpolation& view)
  {
    this->shading = Shading::PreIntegrated;
    this->preIntegration = &table;
    this->interpolation = view;
  }
};

/// What the compositor did since Begin, and how long it took.
struct CompositorStats
{
  std::size_t fans = 0;       ///< fans given that touch the image
  std::size_t binEntries = 0; ///< (fan, tile) pairs
  std::size_t triangles = 0;  ///< (triangle, tile) pairs that covered a pixel (set up)
  /// Pixels covered by a triangle of the fans drawn: shaded, or skipped behind pixels already
  /// opaque (fans are drawn front to back; Compositor.h, "Rasterization").
  std::size_t fragments = 0;
  std::size_t hiddenFans = 0; ///< (fan, tile) pairs skipped whole behind opaque pixels
  /// Vectors of fragments the fan path tested for coverage (its fans' boxes, row by row):
  /// with `fragments`, how full its vectors are (Documentation/compositor.md, "The floor").
  std::size_t fanVectors = 0;
  std::size_t tiles = 0;     ///< tiles that had fans
  double binSeconds = 0;     ///< binning
  double rasterSeconds = 0;  ///< set-up and fragments
  double resolveSeconds = 0; ///< Resolve
};

/**
 * Composites fans into an image, frame after frame; its buffers are kept and reused.
 * Thread safety: one object per thread of control; the work inside uses OpenMP threads.
 * Determinism: bit-identical for any thread count (see the file comment).
 */
class Compositor
{
public:
  /// Pixels per side of a tile (Records.h).
  static constexpr int TileSize = mtpt::TileSize;

  Compositor();
  ~Compositor();
  Compositor(const Compositor&) = delete;
  Compositor& operator=(const Compositor&) = delete;

  /**
   * Starts a new image of settings.width x height, transparent. `settings` (and what it
   * points to) must stay valid until the last Composite of the image.
   */
  void Begin(const CompositeSettings& settings);

  /**
   * Composites fans[0, count) in front of everything composited since Begin, the first
   * farthest (visibility order). Shading (Lighting.h): with `lights` (count entries), each
   * fragment of fan k has its colour c lit as clamp(scale c + offset, 0, 1) by lights[k]
   * (composite blending only: the other blend modes ignore it, as VTK's ray caster does).
   * With `classes` (count entries, the decomposition's), a fan whose class is not Drawn
   * (Records.h) is not read: a hidden fan may be left unwritten.
   */
  void Composite(const Fan* fans, std::size_t count, int threads,
    const LightFactors* lights = nullptr, const ProjectionClass* classes = nullptr);

  /**
   * As Composite, but the fans lie behind everything composited since Begin: the batches of
   * a frame given front to back (FramePlan::frontToBack), each in visibility order. Every
   * tile goes on blending under what it holds, so the image is the one of all the batches
   * given to one Composite, bit for bit, and the pixels earlier batches made opaque hide
   * what lies behind them (Opaque()). A blend mode other than Composite reduces in any
   * order: the same as Composite.
   */
  void CompositeBehind(const Fan* fans, std::size_t count, int threads,
    const LightFactors* lights = nullptr, const ProjectionClass* classes = nullptr);

  /**
   * The pixels of the image opaque so far (OpaquePixels.h), as of the last Composite or
   * CompositeBehind: what a decomposition of cells behind them may leave out
   * (DecomposeInput::hidden). Empty in a blend mode other than Composite.
   */
  const OpaquePixels& Opaque() const { return this->OpaqueImage; }

  /// The pixels a fan was drawn in since Begin may lie in this region; outside it the image
  /// is transparent.
  PixelRegion TouchedRegion() const;

  /**
   * The image composited over `below` in `region` (a sub-rectangle of the image): `below`
   * holds the region's RGBA values beneath the volume (null: transparent black, which gives
   * the premultiplied image itself), `rgba` receives the region's, both row-major, row 0 at
   * the bottom.
   */
  void Resolve(const PixelRegion& region, const float* below, float* rgba, int threads);
  /// The same in 8 bits per channel (rounded to nearest), as a window holds it.
  void Resolve(
    const PixelRegion& region, const std::uint8_t* below, std::uint8_t* rgba, int threads);

  /**
   * The slot entry point: composites slots [0, count) of OpenGL decomposition buffers (each
   * triangle with three distinct corners as a fan of one) into `rgba` (4 * width * height
   * floats, premultiplied, row 0 at the bottom), which it resizes. Tests and the fuzzer use
   * it to check the compositor against hand-made triangles and against the OpenGL path's
   * buffers.
   */
  void Composite(const TetVertex* vertices, const std::uint32_t* indices, std::size_t count,
    const CompositeSettings& settings, std::vector<float>& rgba, int threads,
    const LightFactors* lights = nullptr);

  const CompositorStats& Stats() const { return this->Statistics; }

  /// The instruction set the fragment loops run with on this processor (e.g. "AVX2"),
  /// chosen at run time.
  static const char* InstructionSet();

  /**
   * For measurements: every SIMD kernel of the process (Google Highway's dispatch) runs with
   * the instruction set named `name` (one of InstructionSets()) from now on, or, with an
   * empty name, with the best this processor has again. False, changing nothing, for a name
   * this build or this processor does not have. Not thread-safe: call it before any frame.
   */
  static bool UseInstructionSet(const std::string& name);

  /// The instruction sets of this build that this processor runs, best first.
  static std::vector<std::string> InstructionSets();

private:
  void Draw(const Fan* fans, std::size_t count, int threads, const LightFactors* lights,
    const ProjectionClass* classes, bool behind);
  void Bin(const Fan* fans, std::size_t count, int threads, const ProjectionClass* classes);
  /// Binning's buffers for `count` fans in `blocks` blocks, before its three steps: count a
  /// block's (fan, tile) pairs and touched region; turn the counts into places (returns the
  /// pairs); list a block's fans' indices in their places.
  void PrepareBins(std::size_t count, int blocks);
  void CountPairs(
    const Fan* fans, const ProjectionClass* classes, int block, std::size_t begin, std::size_t end);
  std::size_t PlaceEntries(int blocks);
  void ListEntries(int block, std::size_t begin, std::size_t end);
  template <typename T>
  void ResolveInto(const PixelRegion& region, const T* below, T* rgba, int threads);
  void Rasterize(const Fan* fans, const LightFactors* lights, int threads, bool behind);
  float* Tile(int tile);
  /// Marks the opaque pixels of tile `tile`, whose pixels are `pixels`, in OpaqueImage;
  /// returns whether any is opaque.
  bool MarkOpaque(int tile, const float* pixels);

  /// Tiles a fan touches (inclusive; empty when x0 > x1).
  struct TileRange
  {
    std::uint16_t x0, x1, y0, y1;
  };

  CompositeSettings Settings;
  CompositorStats Statistics;
  int TilesX = 0, TilesY = 0;
  LargeVector<float> Image;              ///< per tile: R, G, B, A planes
  std::vector<std::uint8_t> Cleared;     ///< per tile: cleared since Begin
  LargeVector<TileRange> Ranges;         ///< per fan of the last Composite
  LargeVector<std::uint8_t> Straddles;   ///< per fan of the last Composite: cut by a plane
  std::vector<std::uint32_t> Counts;     ///< per (block, tile): pairs, then the block's cursor
  std::vector<std::size_t> TileStart;    ///< per tile: its first entry (tiles + 1 values)
  LargeVector<std::uint32_t> Entries;    ///< fans of the last Composite, tile by tile, in order
  std::vector<int> Tiles;                ///< tiles with fans in the last Composite
  std::vector<PixelRegion> BlockTouched; ///< per binning block: the region its fans touch
  std::vector<std::size_t> BlockBinned;  ///< per binning block: its fans that touch the image
  /// Each thread's scratch for Rasterize (Compositor.cxx), made before its parallel loop and
  /// kept from call to call: the loop allocates nothing.
  struct ThreadScratch;
  std::unique_ptr<ThreadScratch> Scratch;
  PixelRegion Touched;
  OpaquePixels OpaqueImage;             ///< composite blending: the pixels opaque so far (Opaque())
  std::vector<Fan> SlotFans;            ///< the slot entry point's fans
  std::vector<LightFactors> SlotLights; ///< and their lighting
};

} // namespace mtpt

#endif
