// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Compositor.h"
#include "mtpt/Faults.h"

#include "detail/Parallel.h"
#include "detail/Streaming.h"
#include "detail/TileRaster.h"

#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace mtpt
{

namespace
{

constexpr std::size_t TilePixels = static_cast<std::size_t>(TileSize) * TileSize;
/// Fans a rasterizing thread gathers from a tile's list at a time (64 KiB: in cache while
/// they are drawn).
constexpr std::size_t FansPerChunk = 512;
/// How far ahead in a tile's list the gathering thread asks for fans (their indices grow,
/// with gaps the hardware's prefetchers do not follow).
constexpr std::size_t PrefetchDistance = 16;

/**
 * The rows [y0, y1] and columns [x0, x1] whose pixel centres the fan's vertices span; false
 * when there are none in the image. Conservative by 1/128 pixel (more than snapping moves a
 * vertex): the rasterizer decides exactly. The clamps keep the conversions to int defined
 * for huge or infinite values; NaN gives false.
 */
bool FanPixels(const Fan& fan, int width, int height, int& x0, int& x1, int& y0, int& y1)
{
  float minX = fan.centre.x, maxX = minX, minY = fan.centre.y, maxY = minY;
  for (int k = 0; k < fan.count; ++k)
  {
    minX = std::min(minX, fan.boundary[k].x);
    maxX = std::max(maxX, fan.boundary[k].x);
    minY = std::min(minY, fan.boundary[k].y);
    maxY = std::max(maxY, fan.boundary[k].y);
  }
  const float lx = (minX + 1.0f) * 0.5f * width - 0.5f, hx = (maxX + 1.0f) * 0.5f * width - 0.5f;
  const float ly = (minY + 1.0f) * 0.5f * height - 0.5f, hy = (maxY + 1.0f) * 0.5f * height - 0.5f;
  if (!(lx == lx && hx == hx && ly == ly && hy == hy))
  {
    return false;
  }
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
  return x0 <= x1 && y0 <= y1;
}

/// Whether the settings can shade anything.
bool Usable(const CompositeSettings& s)
{
  if (s.width <= 0 || s.height <= 0)
  {
    return false;
  }
  if (s.vertexColours)
  {
    // The records hold the colours: no table is read, and only VTK-compatible shading
    // applies (the frame's plan decides so: CompositeSettingsFor).
    return s.shading == Shading::VTKCompatible;
  }
  if (!s.transferFunction.table || s.transferFunction.size < 1)
  {
    return false;
  }
  return s.shading != Shading::PreIntegrated ||
    (s.preIntegration &&
      s.preIntegration->integrals.size() >= 4 * static_cast<std::size_t>(s.transferFunction.size));
}

/// Tile `tile` of an image of tilesX tiles across as the rasterizer draws it: its pixels
/// `rgba`, and the opaque depth of its pixels copied into `depth` (TileSize^2 floats).
detail::TileTarget TargetOf(
  int tile, int tilesX, const CompositeSettings& s, float* rgba, std::vector<float>& depth)
{
  detail::TileTarget target;
  target.x0 = (tile % tilesX) * TileSize;
  target.y0 = (tile / tilesX) * TileSize;
  target.width = std::min(TileSize, s.width - target.x0);
  target.height = std::min(TileSize, s.height - target.y0);
  target.rgba = rgba;
  if (s.opaqueDepth)
  {
    for (int j = 0; j < target.height; ++j)
    {
      const float* row = s.opaqueDepth + static_cast<std::size_t>(target.y0 + j) * s.width;
      std::copy(row + target.x0, row + target.x0 + target.width, depth.data() + j * TileSize);
    }
    target.depth = depth.data();
  }
  return target;
}

/// Where a fan lies against the clipping planes.
enum class FanSide : std::uint8_t
{
  Kept,      ///< no plane cuts it
  Straddles, ///< a plane cuts it: its fragments are cut
  Clipped    ///< one plane clips all of it
};

/**
 * The fan's side of the planes, from the eye points of its records' segment ends: the fan's
 * fragments' segments lie in their convex hull.
 */
FanSide SideOfPlanes(const Fan& fan, const ClipPlanes& planes, const DepthClipping& view)
{
  double ends[10][3];
  int n = 0;
  auto add = [&](const TetVertex& v)
  {
    const double front = view.EyeDepth(0.5 * (v.z + 1.0));
    view.EyePoint(v.x, v.y, front, ends[n++]);
    view.EyePoint(v.x, v.y, front + v.thickness / view.RayLength(v.x, v.y), ends[n++]);
  };
  add(fan.centre);
  for (int k = 0; k < fan.count && k < 4; ++k)
  {
    add(fan.boundary[k]);
  }
  bool cut = false;
  for (int i = 0; i < planes.count; ++i)
  {
    int kept = 0;
    for (int k = 0; k < n; ++k)
    {
      kept += planes.Distance(i, ends[k]) < 0.0 ? 0 : 1; // not a number: not clipped
    }
    if (kept == 0)
    {
      return FanSide::Clipped;
    }
    cut = cut || kept < n;
  }
  return cut ? FanSide::Straddles : FanSide::Kept;
}

/**
 * Depth peeling: copies the near and far window depths of tile `tile`'s pixels into `range`
 * (2 TileSize^2 floats). Returns whether any pixel asks for a range (near <= far).
 */
bool CopyRanges(int tile, int tilesX, const CompositeSettings& s, std::vector<float>& range)
{
  const int x0 = (tile % tilesX) * TileSize, y0 = (tile / tilesX) * TileSize;
  const int width = std::min(TileSize, s.width - x0), height = std::min(TileSize, s.height - y0);
  bool asked = false;
  for (int j = 0; j < height; ++j)
  {
    const float* row = s.depthRange + 2 * (static_cast<std::size_t>(y0 + j) * s.width + x0);
    std::copy(row, row + 2 * width, range.data() + 2 * j * TileSize);
    for (int i = 0; i < width && !asked; ++i)
    {
      asked = row[2 * i] <= row[2 * i + 1];
    }
  }
  return asked;
}

/**
 * Draws the fans listed in `list` (count of them, in visibility order: back to front) into
 * `target` front to back: gathered from the list's end, a chunk at a time.
 */
void DrawFrontToBack(const Fan* fans, const std::uint8_t* straddles, const LightFactors* lights,
  const std::uint32_t* list, std::size_t count, const detail::RasterFrame& frame,
  const detail::TileTarget& target, std::vector<Fan>& chunk, std::vector<LightFactors>& lit,
  detail::RasterCounts& counts)
{
  for (std::size_t left = count; left > 0;)
  {
    const std::size_t n = std::min(FansPerChunk, left);
    left -= n;
    for (std::size_t k = 0; k < n; ++k)
    {
      const std::size_t at = left + n - 1 - k;
      if (at >= PrefetchDistance)
      {
        const char* ahead = reinterpret_cast<const char*>(fans + list[at - PrefetchDistance]);
        __builtin_prefetch(ahead);
        __builtin_prefetch(ahead + 64);
      }
      chunk[k] = fans[list[at]];
      chunk[k].straddles = straddles ? straddles[list[at]] : 0;
      if (lights)
      {
        lit[k] = lights[list[at]];
      }
    }
    detail::RasterizeTile(frame, target, chunk.data(), n, counts, lights ? lit.data() : nullptr);
  }
}

/// Composites the tile image `front` (premultiplied colour and coverage alpha planes) over
/// `back`: back = front + (1 - front alpha) back.
void Over(const float* front, float* back)
{
  const float* alpha = front + 3 * TilePixels;
  for (std::size_t c = 0; c < 4; ++c)
  {
    for (std::size_t i = 0; i < TilePixels; ++i)
    {
      back[c * TilePixels + i] =
        front[c * TilePixels + i] + (1.0f - alpha[i]) * back[c * TilePixels + i];
    }
  }
}

} // namespace

/// One thread's scratch for Rasterize: a tile's opaque depth, its peel ranges, a transparent
/// image for fans drawn over an earlier Composite's, a chunk of fans and their lighting, and
/// what the thread counted.
struct RasterScratch
{
  std::vector<float> depth = std::vector<float>(TilePixels);
  std::vector<float> range = std::vector<float>(2 * TilePixels);
  std::vector<float> batch = std::vector<float>(4 * TilePixels);
  std::vector<Fan> chunk = std::vector<Fan>(FansPerChunk);
  std::vector<LightFactors> lit = std::vector<LightFactors>(FansPerChunk);
  detail::RasterCounts counts;
  bool anyOpaque = false; ///< a tile it drew has an opaque pixel
};

struct Compositor::ThreadScratch
{
  detail::PerThread<RasterScratch> threads;
};

Compositor::Compositor()
  : Scratch(std::make_unique<ThreadScratch>())
{
}

Compositor::~Compositor() = default;

void Compositor::Begin(const CompositeSettings& settings)
{
  this->Settings = settings;
  this->Statistics = CompositorStats{};
  const int width = std::max(0, settings.width), height = std::max(0, settings.height);
  this->TilesX = (width + TileSize - 1) / TileSize;
  this->TilesY = (height + TileSize - 1) / TileSize;
  const std::size_t tiles = static_cast<std::size_t>(this->TilesX) * this->TilesY;
  if (this->Image.size() < 4 * TilePixels * tiles)
  {
    ReserveDiscarding(this->Image, 4 * TilePixels * tiles); // every tile cleared when drawn
    this->Image.resize(4 * TilePixels * tiles);
  }
  // Tiles are cleared when first drawn in: a frame that touches few pays for few.
  this->Cleared.assign(tiles, 0);
  this->Touched = PixelRegion{ width, height, 0, 0 };
  // Reductions mark nothing: their alpha says only that a fragment came.
  if (ReducesInAnyOrder(settings.blendMode))
  {
    this->OpaqueImage.Reset(0, 0);
  }
  else
  {
    this->OpaqueImage.Reset(width, height);
  }
}

float* Compositor::Tile(int tile)
{
  float* pixels = this->Image.data() + 4 * TilePixels * static_cast<std::size_t>(tile);
  if (!this->Cleared[tile])
  {
    std::fill(pixels, pixels + 4 * TilePixels, 0.0f);
    this->Cleared[tile] = 1;
  }
  return pixels;
}

void Compositor::Composite(const Fan* fans, std::size_t count, int threads,
  const LightFactors* lights, const ProjectionClass* classes)
{
  this->Draw(fans, count, threads, lights, classes, false);
}

void Compositor::CompositeBehind(const Fan* fans, std::size_t count, int threads,
  const LightFactors* lights, const ProjectionClass* classes)
{
  this->Draw(fans, count, threads, lights, classes, true);
}

void Compositor::Draw(const Fan* fans, std::size_t count, int threads, const LightFactors* lights,
  const ProjectionClass* classes, bool behind)
{
  if (count == 0 || !Usable(this->Settings))
  {
    return;
  }
  auto start = Clock::now();
  this->Bin(fans, count, threads, classes);
  this->Statistics.binSeconds += detail::SecondsSince(start);
  start = Clock::now();
  this->Rasterize(fans, lights, threads, behind);
  this->Statistics.rasterSeconds += detail::SecondsSince(start);
}

void Compositor::Bin(
  const Fan* fans, std::size_t count, int threads, const ProjectionClass* classes)
{
  // A counting sort of (fan, tile) pairs by tile: block b of the fans (contiguous in
  // visibility order) counts its pairs per tile, the counts become each (tile, block)'s
  // place in one array, tile by tile and block by block within a tile, and each block writes
  // its fans' indices there. A tile's fans are then listed contiguously and in visibility
  // order, whatever the thread count; rasterization gathers them a chunk at a time. (Copying
  // the 128-byte fans themselves into the lists moved the whole frame's fans through memory
  // twice more.)
  const int blocks = ThreadsForWork(count, detail::FansPerThread, threads);
  this->PrepareBins(count, blocks);
  std::size_t total = 0;
  detail::CountPlaceScatter(
    count, blocks, blocks,
    [&](int b, detail::IndexRange r) { this->CountPairs(fans, classes, b, r.begin, r.end); },
    [&]
    {
      total = this->PlaceEntries(blocks);
      return true;
    },
    [&](int b, detail::IndexRange r) { this->ListEntries(b, r.begin, r.end); });
  for (int b = 0; b < blocks; ++b)
  {
    this->Statistics.fans += this->BlockBinned[b];
    const PixelRegion& r = this->BlockTouched[b];
    this->Touched = { std::min(this->Touched.x0, r.x0), std::min(this->Touched.y0, r.y0),
      std::max(this->Touched.x1, r.x1), std::max(this->Touched.y1, r.y1) };
  }
  this->Statistics.binEntries += total;
  this->Statistics.tiles += this->Tiles.size();
}

void Compositor::PrepareBins(std::size_t count, int blocks)
{
  AllocationPoint(AllocationSite::Tiles); // the image begun already: halfway through
  const std::size_t tiles = static_cast<std::size_t>(this->TilesX) * this->TilesY;
  this->Counts.assign(static_cast<std::size_t>(blocks) * tiles, 0);
  // Every Composite writes them anew: grown to the size asked, never doubled.
  if (this->Ranges.size() < count)
  {
    ReserveDiscarding(this->Ranges, count);
    this->Ranges.resize(count);
  }
  if (this->Settings.clipPlanes.count > 0 && this->Straddles.size() < count)
  {
    ReserveDiscarding(this->Straddles, count);
    this->Straddles.resize(count);
  }
  this->BlockTouched.assign(static_cast<std::size_t>(blocks), this->Touched);
  this->BlockBinned.assign(static_cast<std::size_t>(blocks), 0);
}

void Compositor::CountPairs(
  const Fan* fans, const ProjectionClass* classes, int b, std::size_t begin, std::size_t end)
{
  const std::size_t tiles = static_cast<std::size_t>(this->TilesX) * this->TilesY;
  const ClipPlanes& planes = this->Settings.clipPlanes;
  const int width = this->Settings.width, height = this->Settings.height;
  std::uint32_t* counts = this->Counts.data() + b * tiles;
  // Counted in locals, stored once: the blocks' entries share cache lines.
  std::size_t blockBinned = 0;
  PixelRegion region = this->BlockTouched[b];
  for (std::size_t i = begin; i < end; ++i)
  {
    int x0, x1, y0, y1;
    TileRange& range = this->Ranges[i];
    if (classes && !Drawn(classes[i]))
    {
      range = TileRange{ 1, 0, 0, 0 }; // nothing to draw; a hidden fan was not even written
      continue;
    }
    const FanSide side = planes.count > 0 && fans[i].count >= 2
      ? SideOfPlanes(fans[i], planes, this->Settings.clipping)
      : FanSide::Kept;
    if (fans[i].count < 2 || side == FanSide::Clipped ||
      !FanPixels(fans[i], width, height, x0, x1, y0, y1))
    {
      range = TileRange{ 1, 0, 0, 0 };
      continue;
    }
    if (planes.count > 0)
    {
      this->Straddles[i] = side == FanSide::Straddles ? 1 : 0;
    }
    ++blockBinned;
    region = { std::min(region.x0, x0), std::min(region.y0, y0), std::max(region.x1, x1 + 1),
      std::max(region.y1, y1 + 1) };
    range = TileRange{ static_cast<std::uint16_t>(x0 / TileSize),
      static_cast<std::uint16_t>(x1 / TileSize), static_cast<std::uint16_t>(y0 / TileSize),
      static_cast<std::uint16_t>(y1 / TileSize) };
    for (int ty = range.y0; ty <= range.y1; ++ty)
    {
      for (int tx = range.x0; tx <= range.x1; ++tx)
      {
        ++counts[ty * this->TilesX + tx];
      }
    }
  }
  this->BlockBinned[b] = blockBinned;
  this->BlockTouched[b] = region;
}

std::size_t Compositor::PlaceEntries(int blocks)
{
  // Places: tile by tile, block by block; each count becomes its block's cursor.
  const std::size_t tiles = static_cast<std::size_t>(this->TilesX) * this->TilesY;
  this->TileStart.assign(tiles + 1, 0);
  this->Tiles.clear();
  const std::size_t total =
    detail::ExclusivePrefixByBucket(this->Counts.data(), static_cast<std::size_t>(blocks), tiles,
      [&](std::size_t t, std::size_t first, std::size_t pairs)
      {
        this->TileStart[t] = first;
        if (pairs > 0)
        {
          this->Tiles.push_back(static_cast<int>(t));
        }
      });
  this->TileStart[tiles] = total;
  if (this->Entries.size() < total)
  {
    ReserveDiscarding(this->Entries, total);
    this->Entries.resize(total);
  }
  return total;
}

void Compositor::ListEntries(int b, std::size_t begin, std::size_t end)
{
  const std::size_t tiles = static_cast<std::size_t>(this->TilesX) * this->TilesY;
  std::uint32_t* cursor = this->Counts.data() + b * tiles;
  for (std::size_t i = begin; i < end; ++i)
  {
    const TileRange& range = this->Ranges[i];
    for (int ty = range.y0; ty <= range.y1; ++ty)
    {
      for (int tx = range.x0; tx <= range.x1; ++tx)
      {
        this->Entries[cursor[ty * this->TilesX + tx]++] = static_cast<std::uint32_t>(i);
      }
    }
  }
}

namespace
{
/// What every tile of a frame of settings `s` shares.
detail::RasterFrame RasterFrameOf(const CompositeSettings& s)
{
  detail::RasterFrame frame;
  frame.width = s.width;
  frame.height = s.height;
  frame.transferFunction = s.transferFunction;
  frame.preIntegration = s.shading == Shading::PreIntegrated ? s.preIntegration : nullptr;
  frame.vertexColours = s.vertexColours;
  frame.interpolation = s.interpolation;
  frame.inverseUnit = static_cast<float>(1.0 / s.unitDistance);
  frame.clipToRange = s.depthRange != nullptr;
  frame.clipping = s.clipping;
  frame.planes = s.clipPlanes;
  frame.blendMode = s.blendMode;
  frame.intensity = s.intensity;
  AverageRangeEntries(s.transferFunction, s.averageRange, AverageRangeBeyond, frame.averageRange);
  return frame;
}
} // namespace

void Compositor::Rasterize(const Fan* fans, const LightFactors* lights, int threads, bool behind)
{
  const CompositeSettings& s = this->Settings;
  const detail::RasterFrame frame = RasterFrameOf(s);
  const bool reduce = ReducesInAnyOrder(s.blendMode);
  const std::uint8_t* straddles = s.clipPlanes.count > 0 ? this->Straddles.data() : nullptr;
  const auto jobs = static_cast<std::int64_t>(this->Tiles.size());
  // Threads take tiles: no more threads than tiles, nor than the binned fans are worth.
  const std::size_t entries = this->TileStart.empty() ? 0 : this->TileStart.back();
  const int team = std::min(ThreadsForWork(this->Tiles.size(), 1, threads),
    ThreadsForWork(entries, detail::FansPerThread, threads));
  detail::PerThread<RasterScratch>& scratch = this->Scratch->threads;
  scratch.Prepare(team, [] { return RasterScratch(); });
  for (RasterScratch& mine : scratch)
  {
    mine.counts = detail::RasterCounts{};
    mine.anyOpaque = false;
  }
  detail::ParallelForDynamic(jobs, team,
    [&](std::int64_t job, int thread)
    {
      RasterScratch& mine = scratch[thread];
      const int tile = this->Tiles[job];
      if (s.depthRange && !CopyRanges(tile, this->TilesX, s, mine.range))
      {
        return; // depth peeling: no pixel of the tile has a range to composite
      }
      // A tile drawn by an earlier Composite holds what lies behind these fans: they are
      // drawn into a transparent image of their own, composited over it afterwards. Behind
      // an earlier batch (CompositeBehind), or in a reduction (which folds fragments in any
      // order), they are drawn into the tile itself.
      const bool apart = this->Cleared[tile] != 0 && !reduce && !behind;
      float* pixels = this->Tile(tile);
      if (apart)
      {
        std::fill(mine.batch.begin(), mine.batch.end(), 0.0f);
      }
      detail::TileTarget target =
        TargetOf(tile, this->TilesX, s, apart ? mine.batch.data() : pixels, mine.depth);
      target.range = s.depthRange ? mine.range.data() : nullptr;
      detail::RasterCounts counts;
      const std::size_t first = this->TileStart[tile];
      DrawFrontToBack(fans, straddles, lights, this->Entries.data() + first,
        this->TileStart[tile + 1] - first, frame, target, mine.chunk, mine.lit, counts);
      if (apart)
      {
        Over(mine.batch.data(), pixels);
      }
      if (!reduce && this->MarkOpaque(tile, pixels))
      {
        mine.anyOpaque = true;
      }
      mine.counts.triangles += counts.triangles;
      mine.counts.fragments += counts.fragments;
      mine.counts.hidden += counts.hidden;
      mine.counts.fanVectors += counts.fanVectors;
    });
  bool anyOpaque = !this->OpaqueImage.Empty(); // alpha only grows: opaque stays opaque
  for (const RasterScratch& mine : scratch)
  {
    this->Statistics.triangles += mine.counts.triangles;
    this->Statistics.fragments += mine.counts.fragments;
    this->Statistics.hiddenFans += mine.counts.hidden;
    this->Statistics.fanVectors += mine.counts.fanVectors;
    anyOpaque = anyOpaque || mine.anyOpaque;
  }
  if (!reduce)
  {
    this->OpaqueImage.Marked(anyOpaque);
  }
}

bool Compositor::MarkOpaque(int tile, const float* pixels)
{
  const int tx = tile % this->TilesX, x0 = tx * TileSize, y0 = (tile / this->TilesX) * TileSize;
  const int width = std::min(TileSize, this->Settings.width - x0);
  const int height = std::min(TileSize, this->Settings.height - y0);
  const float* alpha = pixels + 3 * TilePixels;
  static_assert(TileSize == OpaquePixels::BitsPerWord, "a tile's row is one word");
  std::uint64_t any = 0;
  for (int j = 0; j < height; ++j)
  {
    std::uint64_t word = 0;
    for (int i = 0; i < width; ++i)
    {
      word |= static_cast<std::uint64_t>(alpha[j * TileSize + i] >= OpaqueAlpha) << i;
    }
    this->OpaqueImage.Row(y0 + j)[tx] = word;
    any |= word;
  }
  return any != 0;
}

const char* Compositor::InstructionSet()
{
  return detail::RasterTargetName();
}

namespace
{
/// Every target of this build that this processor runs, whatever UseInstructionSet chose.
std::vector<std::int64_t> RunnableTargets()
{
  // As hwy::SupportedAndGeneratedTargets, which the choice would restrict.
  std::vector<std::int64_t> targets;
  for (std::int64_t left = hwy::SupportedTargets() & HWY_TARGETS; left != 0; left &= left - 1)
  {
    targets.push_back(left & ~(left - 1)); // the lowest bit: Highway's best first
  }
  return targets;
}

/// The target UseInstructionSet chose (0: none, the best).
std::int64_t chosenTarget = 0;
} // namespace

bool Compositor::UseInstructionSet(const std::string& name)
{
  const std::int64_t previous = chosenTarget;
  hwy::SetSupportedTargetsForTest(0); // every target, to look the name up among
  chosenTarget = 0;
  for (const std::int64_t target : RunnableTargets())
  {
    if (name == hwy::TargetName(target))
    {
      chosenTarget = target;
    }
  }
  if (!name.empty() && chosenTarget == 0)
  {
    chosenTarget = previous; // unknown: nothing changes
    hwy::SetSupportedTargetsForTest(previous);
    return false;
  }
  hwy::SetSupportedTargetsForTest(chosenTarget);
  return true;
}

std::vector<std::string> Compositor::InstructionSets()
{
  hwy::SetSupportedTargetsForTest(0);
  std::vector<std::string> names;
  for (const std::int64_t target : RunnableTargets())
  {
    names.emplace_back(hwy::TargetName(target));
  }
  hwy::SetSupportedTargetsForTest(chosenTarget);
  return names;
}

PixelRegion Compositor::TouchedRegion() const
{
  return this->Touched.Empty() ? PixelRegion{} : this->Touched;
}

namespace
{

/// Calls pixel(i, image) for each pixel of `region`: i counts region pixels, and image points
/// at its premultiplied R (G, B, A one plane apart), or is null where nothing was drawn.
template <typename Pixel>
void ForEachPixel(const PixelRegion& region, int tilesX, const std::vector<std::uint8_t>& cleared,
  const float* image, int threads, Pixel&& pixel)
{
  const int width = region.x1 - region.x0;
  const std::size_t pixels = static_cast<std::size_t>(std::max(width, 0)) *
    static_cast<std::size_t>(std::max(region.y1 - region.y0, 0));
  const int team = ThreadsForWork(pixels, detail::PixelsPerThread, threads);
  detail::ParallelFor(region.y0, region.y1, team,
    [&](std::int64_t row)
    {
      const int y = static_cast<int>(row);
      for (int x = region.x0; x < region.x1; ++x)
      {
        const int tile = (y / TileSize) * tilesX + x / TileSize;
        const std::size_t i = static_cast<std::size_t>(y - region.y0) * width + (x - region.x0);
        pixel(i,
          cleared[tile] ? image + 4 * TilePixels * tile + (y % TileSize) * TileSize + x % TileSize
                        : nullptr);
      }
    });
}

} // namespace

namespace
{
/// A colour value in [0, 1] from a float or an 8-bit channel, and back (8 bits: clamped and
/// rounded to nearest).
inline float Unit(float value)
{
  return value;
}
inline float Unit(std::uint8_t value)
{
  return value * (1.0f / 255.0f);
}
inline void Store(float value, float& out)
{
  // Colours and opacity lie in [0, 1]; the accumulated sums can round just past 1 (a
  // premultiplied colour over an opaque pixel: found by the fuzzer), as 8 bits are clamped.
  // A NaN stays one, for the tests to see.
  out = value > 1.0f ? 1.0f : (value < 0.0f ? 0.0f : value);
}
inline void Store(float value, std::uint8_t& out)
{
  out = static_cast<std::uint8_t>(std::min(1.0f, std::max(0.0f, value)) * 255.0f + 0.5f);
}

/**
 * The premultiplied colour of a pixel's reduced planes (detail::TileTarget) in a blend mode
 * other than Composite, as VTK's GPU ray caster ends its rays: the transfer function at the
 * extreme scalar (maximum and minimum), or a grey clamped to [0, 1], opaque (average: the
 * weighted sum over the length in the range, none when the pixel saw no such stretch;
 * additive: the sum per unit distance).
 */
void ReducedPixel(const CompositeSettings& s, const float* p, float rgba[4])
{
  rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0.0f;
  if (!(p[3 * TilePixels] > 0.0f))
  {
    return; // no fragment reached the pixel
  }
  float grey = 0.0f;
  bool shown = false;
  switch (s.blendMode)
  {
    case BlendMode::MaximumIntensity:
    case BlendMode::MinimumIntensity:
    {
      // The transfer function at the extreme scalar's entry coordinate.
      float entry[4];
      s.transferFunction.LookupEntry(p[0], entry);
      const float alpha = std::min(1.0f, std::max(0.0f, entry[3]));
      for (int k = 0; k < 3; ++k)
      {
        rgba[k] = entry[k] * alpha;
      }
      rgba[3] = alpha;
      return;
    }
    case BlendMode::AverageIntensity:
      if (p[TilePixels] > 0.0f)
      {
        grey = p[0] / p[TilePixels];
        shown = true;
      }
      break;
    case BlendMode::Additive:
      grey = static_cast<float>(p[0] / s.unitDistance);
      shown = true;
      break;
    case BlendMode::Composite:
      break;
  }
  if (shown)
  {
    grey = grey > 1.0f ? 1.0f : (grey > 0.0f ? grey : 0.0f); // NaN gives 0
    rgba[0] = rgba[1] = rgba[2] = grey;
    rgba[3] = 1.0f;
  }
}

} // namespace

template <typename T>
void Compositor::ResolveInto(const PixelRegion& region, const T* below, T* rgba, int threads)
{
  const auto start = Clock::now();
  const bool reduced = ReducesInAnyOrder(this->Settings.blendMode);
  ForEachPixel(region, this->TilesX, this->Cleared, this->Image.data(), threads,
    [&](std::size_t i, const float* p)
    {
      float drawn[4] = { 0.0f, 0.0f, 0.0f, 0.0f };
      if (p && reduced)
      {
        ReducedPixel(this->Settings, p, drawn);
      }
      else if (p)
      {
        for (int c = 0; c < 4; ++c)
        {
          drawn[c] = p[c * TilePixels];
        }
      }
      const float rest = 1.0f - drawn[3];
      for (int c = 0; c < 4; ++c)
      {
        Store(below ? drawn[c] + rest * Unit(below[4 * i + c]) : drawn[c], rgba[4 * i + c]);
      }
    });
  this->Statistics.resolveSeconds += detail::SecondsSince(start);
}

void Compositor::Resolve(const PixelRegion& region, const float* below, float* rgba, int threads)
{
  this->ResolveInto(region, below, rgba, threads);
}

void Compositor::Resolve(
  const PixelRegion& region, const std::uint8_t* below, std::uint8_t* rgba, int threads)
{
  this->ResolveInto(region, below, rgba, threads);
}

void Compositor::Composite(const TetVertex* vertices, const std::uint32_t* indices,
  std::size_t count, const CompositeSettings& settings, std::vector<float>& rgba, int threads,
  const LightFactors* lights)
{
  const int width = std::max(0, settings.width), height = std::max(0, settings.height);
  const std::size_t values = 4 * static_cast<std::size_t>(width) * height;
  rgba.assign(values, 0.0f);
  // Each triangle with three distinct corners as a fan of one.
  this->SlotFans.clear();
  this->SlotLights.clear();
  for (std::size_t k = 0; k < count; ++k)
  {
    for (std::size_t t = 0; t < 4; ++t)
    {
      const std::uint32_t* tri = indices + 12 * k + 3 * t;
      if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2])
      {
        Fan fan{};
        fan.boundary[0] = vertices[tri[0]];
        fan.boundary[1] = vertices[tri[1]];
        fan.centre = vertices[tri[2]];
        fan.count = 2;
        this->SlotFans.push_back(fan);
        if (lights)
        {
          this->SlotLights.push_back(lights[k]);
        }
      }
    }
  }
  this->Begin(settings);
  this->Composite(this->SlotFans.data(), this->SlotFans.size(), threads,
    lights ? this->SlotLights.data() : nullptr);
  if (values > 0)
  {
    this->Resolve(PixelRegion{ 0, 0, width, height }, nullptr, rgba.data(), threads);
  }
}

} // namespace mtpt
