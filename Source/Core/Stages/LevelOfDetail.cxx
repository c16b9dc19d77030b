// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/LevelOfDetail.h"
#include "mtpt/Faults.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mtpt
{
namespace
{

/// Reads point i of a PointsView (of one array or of parts) as doubles.
class PointReader
{
public:
  explicit PointReader(const PointsView& points)
  {
    if (!points.parts)
    {
      this->Parts.push_back({ 0, points });
      return;
    }
    std::size_t first = 0;
    for (std::size_t k = 0; k < points.partCount; ++k)
    {
      this->Parts.push_back({ first, points.parts[k].points });
      first += points.parts[k].points.count;
    }
  }

  void Read(std::size_t i, double xyz[3]) const
  {
    const auto next = std::upper_bound(this->Parts.begin(), this->Parts.end(), i,
      [](std::size_t p, const Part& part) { return p < part.first; });
    const Part& part = *(next - 1);
    const std::size_t local = 3 * (i - part.first);
    for (int a = 0; a < 3; ++a)
    {
      xyz[a] = part.view.type == PointsView::Type::Float32
        ? static_cast<double>(static_cast<const float*>(part.view.data)[local + a])
        : static_cast<const double*>(part.view.data)[local + a];
    }
  }

private:
  struct Part
  {
    std::size_t first;
    PointsView view;
  };
  std::vector<Part> Parts;
};

/// Spreads the low 10 bits of v to every third bit (bit i to bit 3i).
std::uint32_t SpreadBits(std::uint32_t v)
{
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

/// The low `bits` bits of v in reverse order.
std::uint32_t ReverseBits(std::uint32_t v, int bits)
{
  std::uint32_t r = 0;
  for (int b = 0; b < bits; ++b)
  {
    r = (r << 1) | ((v >> b) & 1u);
  }
  return r;
}

/// The Morton codes of the cells' centroids on a 1024^3 lattice over the points' bounding
/// box, as keys (code << 32 | cell) so that sorting them orders the cells along the curve.
void MortonKeys(const PointsView& points, const CellsView& cells, std::uint64_t* keys, int threads)
{
  const PointReader reader(points);
  const auto pointCount = static_cast<std::int64_t>(points.count);
  double low[3] = { 0, 0, 0 }, high[3] = { 0, 0, 0 };
  bool any = false;
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    double p[3];
    reader.Read(static_cast<std::size_t>(i), p);
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])))
    {
      continue;
    }
    for (int a = 0; a < 3; ++a)
    {
      low[a] = any ? std::min(low[a], p[a]) : p[a];
      high[a] = any ? std::max(high[a], p[a]) : p[a];
    }
    any = true;
  }
  double scale[3];
  for (int a = 0; a < 3; ++a)
  {
    scale[a] = high[a] > low[a] ? 1024.0 / (high[a] - low[a]) : 0.0;
  }
  const auto n = static_cast<std::int64_t>(cells.cellCount);
  detail::DispatchCells(cells, points.count,
    [&](const auto& access)
    {
      detail::ParallelFor(0, n, threads,
        [&](std::int64_t c)
        {
          std::int64_t ids[4];
          double centre[3] = { low[0], low[1], low[2] };
          if (access.TetrahedronPoints(static_cast<std::size_t>(c), ids))
          {
            centre[0] = centre[1] = centre[2] = 0;
            for (int i = 0; i < 4; ++i)
            {
              double p[3];
              reader.Read(static_cast<std::size_t>(ids[i]), p);
              for (int a = 0; a < 3; ++a)
              {
                centre[a] += 0.25 * p[a];
              }
            }
          }
          std::uint32_t code = 0;
          for (int a = 0; a < 3; ++a)
          {
            const double q = (centre[a] - low[a]) * scale[a];
            // NaN and out-of-box centroids (from unusable points) land on the lattice's edge.
            const auto v = static_cast<std::uint32_t>(q > 0 ? std::min(q, 1023.0) : 0.0);
            code |= SpreadBits(v) << a;
          }
          keys[c] = (static_cast<std::uint64_t>(code) << 32) | static_cast<std::uint64_t>(c);
        });
    });
}

} // namespace

int ImportanceBits(std::size_t cellCount)
{
  int bits = 0;
  while (bits < 32 && (std::size_t{ 1 } << bits) < cellCount)
  {
    ++bits;
  }
  return bits;
}

namespace
{
/// body(cell, importance) for every cell, in parallel: the cells sorted along the Morton curve
/// of their centroids, the cell at position p of the curve of importance ReverseBits(p).
template <typename Body>
void ForEachAlongCurve(const PointsView& points, const CellsView& cells, int threads, Body&& body)
{
  const std::size_t n = cells.cellCount;
  if (n == 0)
  {
    return;
  }
  const int nthreads = detail::ResolveThreads(threads);
  std::vector<std::uint64_t> keys(n);
  MortonKeys(points, cells, keys.data(), nthreads);
  // Keys are distinct (the cell id is in the low half): one sorted order, any thread count.
  detail::ParallelSort(keys.data(), n, nthreads);
  const int bits = ImportanceBits(n);
  detail::ParallelFor(0, static_cast<std::int64_t>(n), nthreads,
    [&](std::int64_t p)
    { body(keys[p] & 0xffffffffu, ReverseBits(static_cast<std::uint32_t>(p), bits)); });
}
} // namespace

void ComputeImportance(
  const PointsView& points, const CellsView& cells, std::uint32_t* importance, int threads)
{
  ForEachAlongCurve(points, cells, threads,
    [importance](std::uint64_t cell, std::uint32_t value) { importance[cell] = value; });
}

int DetailLevelOf(double fraction)
{
  if (!(fraction < 1.0))
  {
    return 0; // 1 or more, or NaN: every cell, as ImportanceThreshold
  }
  if (!(fraction > 0.0))
  {
    return DeepestDetailLevel;
  }
  return static_cast<int>(
    std::min<double>(std::nearbyint(-4.0 * std::log2(fraction)), DeepestDetailLevel));
}

double DetailLevelFraction(int level)
{
  return std::exp2(-static_cast<double>(std::max(level, 0)) / 4.0); // as CellFractionLevel
}

void ComputeKeptLevels(
  const PointsView& points, const CellsView& cells, std::uint8_t* levels, int threads)
{
  // threshold[k]: the importance below which level k keeps a cell, non-increasing in k.
  std::uint64_t threshold[DeepestDetailLevel + 1];
  for (int k = 0; k <= DeepestDetailLevel; ++k)
  {
    threshold[k] = ImportanceThreshold(DetailLevelFraction(k), cells.cellCount);
  }
  ForEachAlongCurve(points, cells, threads,
    [&](std::uint64_t cell, std::uint32_t importance)
    {
      // The first level that leaves the cell out; the one before it is its deepest.
      const std::uint64_t* out = std::partition_point(threshold, threshold + DeepestDetailLevel + 1,
        [importance](std::uint64_t t) { return importance < t; });
      levels[cell] = static_cast<std::uint8_t>(out - threshold - 1);
    });
}

std::uint64_t ImportanceThreshold(double fraction, std::size_t cellCount)
{
  const double all = std::ldexp(1.0, ImportanceBits(cellCount));
  if (!(fraction < 1.0))
  {
    return static_cast<std::uint64_t>(all);
  }
  return static_cast<std::uint64_t>(std::ceil(std::max(fraction, 0.0) * all));
}

double CellFractionLevel(double fraction, double minimum)
{
  if (!(fraction < 1.0))
  {
    return 1.0;
  }
  // The largest 2^(-k/4) at or below the fraction (a level the fraction equals, up to
  // rounding, is that level), and at least the level at or below the minimum.
  const auto level = [](double f)
  {
    const double k = std::ceil(-4.0 * std::log2(f) - 1e-6);
    return std::exp2(-std::max(k, 0.0) / 4.0);
  };
  const double floor = minimum > 0 && minimum < 1 ? level(minimum) : (minimum >= 1 ? 1.0 : 0.0);
  return fraction > 0 ? std::max(level(fraction), floor) : std::max(floor, level(1e-6));
}

bool CellSelectionStage::Update(const Key& key, const PointsView& points, const CellsView& cells,
  const std::uint32_t* visible, std::size_t visibleCount, int threads)
{
  this->Visible = visible;
  this->VisibleCount = visibleCount;
  if (this->Record.Holds(key))
  {
    return false;
  }
  const std::size_t n = cells.cellCount;
  if (KeepsEveryCell(key.level, n))
  {
    // Every visible cell: the visible list itself, a new result only if it was a subset.
    this->Record.Store(key,
      !this->Passed || !this->Record.Valid() ||
        !(this->Record.Inputs().visible == key.visible && this->Record.Inputs().mesh == key.mesh));
    this->Passed = true;
    return false;
  }
  const int nthreads = detail::ResolveThreads(threads);
  this->PrepareImportance(key.mesh, points, cells, nthreads);
  // Count, then list: the list holds the kept cells only, in ascending order.
  const std::size_t candidates = visible ? visibleCount : n;
  const std::uint8_t* levels = this->Levels.data();
  const auto keeps = [&](std::size_t i, std::uint32_t& c)
  {
    c = visible ? visible[i] : static_cast<std::uint32_t>(i);
    return levels[c] >= key.level;
  };
  const int blocks = ThreadsForWork(candidates, detail::CellsPerThread, nthreads);
  std::vector<std::size_t> offsets(static_cast<std::size_t>(blocks), 0);
  std::size_t kept = 0;
  detail::CountPlaceScatter(
    candidates, blocks, blocks,
    [&](int b, detail::IndexRange r)
    {
      std::size_t count = 0;
      for (std::size_t i = r.begin; i < r.end; ++i)
      {
        std::uint32_t c;
        count += keeps(i, c) ? 1 : 0;
      }
      offsets[static_cast<std::size_t>(b)] = count;
    },
    [&]
    {
      kept = detail::ExclusivePrefixByBucket(offsets.data(), static_cast<std::size_t>(blocks), 1,
        [](std::size_t, std::size_t, std::size_t) {});
      AllocationPoint(AllocationSite::LevelOfDetail);
      if (this->List.size() < kept)
      {
        this->List.resize(kept); // grown only: a smaller subset reuses it
      }
      return true;
    },
    [&](int b, detail::IndexRange r)
    {
      std::uint32_t* out = this->List.data() + offsets[static_cast<std::size_t>(b)];
      for (std::size_t i = r.begin; i < r.end; ++i)
      {
        std::uint32_t c;
        if (keeps(i, c))
        {
          *out++ = c;
        }
      }
    });
  this->Count = kept;
  this->Passed = false;
  this->Record.Store(key);
  return true;
}

bool CellSelectionStage::PrepareImportance(
  const MeshKey& key, const PointsView& points, const CellsView& cells, int threads)
{
  if (this->LevelsRecord.Holds(key))
  {
    return false;
  }
  AllocationPoint(AllocationSite::LevelOfDetail);
  if (this->Levels.size() < cells.cellCount)
  {
    this->Levels.resize(cells.cellCount);
  }
  ComputeKeptLevels(points, cells, this->Levels.data(), threads);
  this->LevelsRecord.Store(key);
  return true;
}

void CellSelectionStage::Forget()
{
  this->Record.Forget();
  this->Passed = true;
}

void CellSelectionStage::Release()
{
  this->Forget();
  this->LevelsRecord.Forget();
  LargeVector<std::uint8_t>().swap(this->Levels);
  LargeVector<std::uint32_t>().swap(this->List);
  this->Count = 0;
}

std::size_t CellSelectionStage::MemoryBytes() const
{
  return this->Levels.capacity() + this->List.capacity() * sizeof(std::uint32_t);
}

double VolumeBudget(double allottedSeconds, double intervalSeconds, double lastSeconds)
{
  if (!(intervalSeconds > 0) || !(lastSeconds > 0) || !std::isfinite(intervalSeconds) ||
    !(intervalSeconds <= 2 * allottedSeconds + lastSeconds))
  {
    return allottedSeconds;
  }
  const double rest = std::min(std::max(intervalSeconds - lastSeconds, 0.0), 0.5 * allottedSeconds);
  return allottedSeconds - rest;
}

Detail ChooseDetail(const MeasuredFrame& last, double allottedSeconds, const DetailLimits& limits,
  const Detail& fixed)
{
  const double dMin = limits.minimumDistance;
  const double dMax = std::max(limits.maximumDistance, dMin);
  const double fMin = CellFractionLevel(limits.minimumFraction, 0.0);
  Detail full;
  full.cellFraction = limits.adjustFraction ? 1.0 : fixed.cellFraction;
  full.sampleDistance = limits.adjustDistance ? dMin : fixed.sampleDistance;
  const double f0 = last.detail.cellFraction, d0 = last.detail.sampleDistance;
  if (!(last.seconds > 0) || !(allottedSeconds > 0) || !std::isfinite(allottedSeconds) ||
    !(f0 > 0) || !(d0 > 0) || (!limits.adjustFraction && !limits.adjustDistance))
  {
    return full;
  }
  const double cell = std::min(std::max(last.cellSeconds, 0.0), last.seconds);
  const double samples = last.sampleSeconds >= 0
    ? std::min(last.sampleSeconds, last.seconds - cell)
    : last.seconds - cell - std::min(std::max(last.viewportSeconds, 0.0), last.seconds - cell);
  const double Z = last.seconds - cell - samples;
  const double C = cell / f0, R = samples * d0 * d0 / f0;
  // The part that follows the detail (f * (C + R / d^2)) gets what the viewport's work
  // leaves; at least 40% of the allotment, where the fixed work alone would nearly fill
  // it (the frame then runs over rather than dropping nearly every cell).
  if (Z + C + R / (full.sampleDistance * full.sampleDistance) <= allottedSeconds)
  {
    return full;
  }
  const double A = std::max(allottedSeconds - Z, 0.4 * allottedSeconds);
  const auto time = [&](double f, double d) { return f * (C + R / (d * d)); };
  // The distance at which fraction f takes the variable budget (infinite if none does).
  const auto distanceFor = [&](double f)
  {
    const double left = A / f - C;
    return left > 0 ? std::sqrt(R / left) : std::numeric_limits<double>::infinity();
  };
  const auto clampDistance = [&](double d) { return std::min(std::max(d, dMin), dMax); };
  if (time(full.cellFraction, full.sampleDistance) <= A)
  {
    return full;
  }
  Detail next = full;
  if (!limits.adjustFraction)
  {
    next.sampleDistance = clampDistance(distanceFor(next.cellFraction));
    return next;
  }
  const double preferred = limits.adjustDistance
    ? std::min(std::max(limits.preferredDistance, dMin), dMax)
    : fixed.sampleDistance;
  if (limits.adjustDistance && distanceFor(1.0) <= preferred)
  {
    next.sampleDistance = clampDistance(distanceFor(1.0));
    return next;
  }
  next.sampleDistance = preferred;
  next.cellFraction = CellFractionLevel(A / time(1.0, preferred), fMin);
  if (time(next.cellFraction, preferred) <= A || !limits.adjustDistance)
  {
    return next;
  }
  // At the smallest fraction: the distance that fits, up to the largest.
  next.cellFraction = fMin;
  next.sampleDistance = clampDistance(std::max(distanceFor(fMin), preferred));
  return next;
}

} // namespace mtpt
