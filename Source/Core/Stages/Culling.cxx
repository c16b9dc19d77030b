// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Culling.h"
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

/// The scalar range of `cell` by ComputeCellScalarRanges' rule.
template <typename Access>
void RangeOfCell(
  const Access& access, const ScalarsView& scalars, std::size_t cell, float& low, float& high)
{
  const float nan = std::numeric_limits<float>::quiet_NaN();
  low = high = nan;
  std::int64_t ids[4];
  if (!access.TetrahedronPoints(cell, ids))
  {
    return;
  }
  if (!scalars.values)
  {
    low = high = 0.0f;
    return;
  }
  if (scalars.association == ScalarsView::Association::Cells)
  {
    low = high = scalars.values[cell];
  }
  else
  {
    low = high = scalars.values[ids[0]];
    for (int i = 1; i < 4; ++i)
    {
      low = std::min(low, scalars.values[ids[i]]);
      high = std::max(high, scalars.values[ids[i]]);
    }
    for (int i = 0; i < 4; ++i) // min/max drop a NaN in some positions
    {
      if (!std::isfinite(scalars.values[ids[i]]))
      {
        low = high = nan;
      }
    }
  }
  if (!std::isfinite(low) || !std::isfinite(high))
  {
    low = high = nan;
  }
}

/// The ids of the cells with a visible range (rangeOf(c, low, high) gives cell c's),
/// ascending, into `cells`; returns their number.
template <typename RangeOf>
std::size_t SelectVisible(const OpacityCulling& culling, std::size_t cellCount,
  std::uint32_t* cells, int threads, const RangeOf& rangeOf)
{
  return detail::CompactInOrder(cellCount, detail::ResolveThreads(threads), cells,
    [&](std::size_t begin, std::size_t end, std::uint32_t* out)
    {
      std::size_t kept = 0;
      for (std::size_t c = begin; c < end; ++c)
      {
        float low, high;
        rangeOf(c, low, high);
        if (culling.Visible(low, high))
        {
          out[kept++] = static_cast<std::uint32_t>(c);
        }
      }
      return kept;
    });
}

/// Whether SelectVisible would write exactly the `count` ascending ids of `cells`.
template <typename RangeOf>
bool SelectsExactlyThese(const OpacityCulling& culling, std::size_t cellCount,
  const std::uint32_t* cells, std::size_t count, int threads, const RangeOf& rangeOf)
{
  if (count > 0 && cells[count - 1] >= cellCount)
  {
    return false;
  }
  const int nthreads = detail::ResolveThreads(threads);
  return detail::ParallelReduce(
    0, nthreads, nthreads, true, [](bool a, bool b) { return a && b; },
    [&](std::int64_t b)
    {
      // This block's cells and the part of the list that can name them.
      const std::size_t begin = cellCount * static_cast<std::size_t>(b) / nthreads;
      const std::size_t end = cellCount * static_cast<std::size_t>(b + 1) / nthreads;
      const std::uint32_t* next = std::lower_bound(cells, cells + count, begin);
      const std::uint32_t* const stop = std::lower_bound(next, cells + count, end);
      bool match = true;
      for (std::size_t c = begin; c < end && match; ++c)
      {
        float low, high;
        rangeOf(c, low, high);
        const bool listed = next != stop && *next == c;
        match = culling.Visible(low, high) == listed;
        next += listed ? 1 : 0;
      }
      return match && next == stop;
    });
}

} // namespace

void ComputeCellScalarRanges(const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, float* ranges, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto n = static_cast<std::int64_t>(cells.cellCount);
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      detail::ParallelFor(0, n, nthreads,
        [&](std::int64_t c) {
          RangeOfCell(
            access, scalars, static_cast<std::size_t>(c), ranges[2 * c], ranges[2 * c + 1]);
        });
    });
}

void OpacityCulling::SetAttenuations()
{
  this->Attenuations = true;
  this->NonZeroBefore.clear();
  this->Size = 0;
}

void OpacityCulling::SetTable(const TransferFunctionTable& table)
{
  this->Attenuations = false;
  this->Size = table.table ? std::max(0, table.size) : 0;
  this->NonZeroBefore.assign(static_cast<std::size_t>(this->Size) + 1, 0);
  for (int i = 0; i < this->Size; ++i)
  {
    this->NonZeroBefore[i + 1] = this->NonZeroBefore[i] + (table.table[4 * i + 3] != 0.0f);
  }
  // The same float mapping as TransferFunctionTable::Lookup.
  const double span = table.high > table.low ? table.high - table.low : 1.0;
  this->Low = static_cast<float>(table.low);
  this->Scale = static_cast<float>((this->Size - 1) / span);
}

bool OpacityCulling::Visible(float low, float high) const
{
  if (this->Attenuations)
  {
    return low <= high && high > 0.0f; // false for NaN
  }
  if (this->Size == 0 || !(low <= high))
  {
    return false; // no table or NaN: nothing drawn
  }
  const float last = static_cast<float>(this->Size - 1);
  auto entry = [&](float s)
  {
    const float t = (s - this->Low) * this->Scale;
    return t > 0.0f ? (t < last ? t : last) : 0.0f;
  };
  // Entries floor(t(low)) .. floor(t(high)) + 1 are read; widen by one on each side so that
  // rounding in the interpolated scalars can never reach an entry not tested.
  const int first = std::max(0, static_cast<int>(entry(low)) - 1);
  const int end = std::min(this->Size, static_cast<int>(entry(high)) + 3);
  return this->NonZeroBefore[end] != this->NonZeroBefore[first];
}

std::size_t OpacityCulling::SelectVisibleCells(
  const float* ranges, std::size_t cellCount, std::uint32_t* cells, int threads) const
{
  return SelectVisible(*this, cellCount, cells, threads,
    [&](std::size_t c, float& low, float& high)
    {
      low = ranges[2 * c];
      high = ranges[2 * c + 1];
    });
}

std::size_t OpacityCulling::SelectVisibleCells(const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, std::uint32_t* list, int threads) const
{
  std::size_t count = 0;
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      count = SelectVisible(*this, cells.cellCount, list, threads,
        [&](std::size_t c, float& low, float& high)
        { RangeOfCell(access, scalars, c, low, high); });
    });
  return count;
}

bool OpacityCulling::SelectsExactly(const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, const std::uint32_t* list, std::size_t count, int threads) const
{
  bool same = cells.cellCount == 0 && count == 0;
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      same = SelectsExactlyThese(*this, cells.cellCount, list, count, threads,
        [&](std::size_t c, float& low, float& high)
        { RangeOfCell(access, scalars, c, low, high); });
    });
  return same;
}

bool CullingStage::Update(const Key& key, const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, const TransferFunctionTable& table, int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  const bool wasCulling = this->Record.Valid() && this->Record.Inputs().mode != CullingMode::None;
  if (key.mode == CullingMode::None)
  {
    // Every cell is a candidate: a new result only if cells were culled before.
    this->Record.Store(key, wasCulling || !this->Record.Valid());
    return false;
  }
  const std::size_t n = cells.cellCount;
  if (key.mode == CullingMode::Attenuations)
  {
    this->Opacity.SetAttenuations();
  }
  else
  {
    this->Opacity.SetTable(table);
  }
  // The same cells as before (a colour change): the same result. The list is compared
  // before it is rewritten, so that the stage never holds a second one. The cells' scalar
  // ranges are found on the way each time (a gather of their scalars), not kept: 8 bytes a
  // cell spared for a pass that runs only when the data or the transfer function change.
  const bool same = this->Record.Valid() && wasCulling && this->Record.Inputs().mesh == key.mesh &&
    this->Opacity.SelectsExactly(
      cells, pointCount, scalars, this->List.data(), this->List.size(), threads);
  if (!same)
  {
    AllocationPoint(AllocationSite::Culling);
    this->List.resize(n);
    this->List.resize(
      this->Opacity.SelectVisibleCells(cells, pointCount, scalars, this->List.data(), threads));
  }
  this->Record.Store(key, !same);
  return true;
}

std::size_t CullingStage::VisibleCount() const
{
  return this->Record.Inputs().mode == CullingMode::None ? this->Record.Inputs().mesh.cellCount
                                                         : this->List.size();
}

void CullingStage::Release()
{
  LargeVector<std::uint32_t>().swap(this->List);
  this->Forget();
}

std::size_t CullingStage::MemoryBytes() const
{
  return this->List.capacity() * sizeof(std::uint32_t);
}

} // namespace mtpt
