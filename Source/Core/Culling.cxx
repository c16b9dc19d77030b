// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Culling.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mtpt
{

void ComputeCellScalarRanges(const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, float* ranges, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto n = static_cast<std::int64_t>(cells.cellCount);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const bool perCell = scalars.association == ScalarsView::Association::Cells;
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
#pragma omp parallel for num_threads(nthreads) schedule(static)
      for (std::int64_t c = 0; c < n; ++c)
      {
        std::int64_t ids[4];
        float low = nan, high = nan;
        if (access.TetrahedronPoints(static_cast<std::size_t>(c), ids))
        {
          if (!scalars.values)
          {
            low = high = 0.0f;
          }
          else if (perCell)
          {
            low = high = scalars.values[c];
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
        ranges[2 * c] = low;
        ranges[2 * c + 1] = high;
      }
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
  return detail::CompactInOrder(cellCount, detail::ResolveThreads(threads), cells,
    [&](std::size_t begin, std::size_t end, std::uint32_t* out)
    {
      std::size_t kept = 0;
      for (std::size_t c = begin; c < end; ++c)
      {
        if (this->Visible(ranges[2 * c], ranges[2 * c + 1]))
        {
          out[kept++] = static_cast<std::uint32_t>(c);
        }
      }
      return kept;
    });
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
  if (!this->RangesRecord.Holds(key.mesh))
  {
    if (this->Ranges.size() < 2 * n)
    {
      this->Ranges.resize(2 * n);
    }
    ComputeCellScalarRanges(cells, pointCount, scalars, this->Ranges.data(), threads);
    this->RangesRecord.Store(key.mesh);
  }
  if (key.mode == CullingMode::Attenuations)
  {
    this->Opacity.SetAttenuations();
  }
  else
  {
    this->Opacity.SetTable(table);
  }
  this->NewList.resize(n);
  this->NewList.resize(
    this->Opacity.SelectVisibleCells(this->Ranges.data(), n, this->NewList.data(), threads));
  // The same cells as before (a colour change): the same result.
  const bool same = this->Record.Valid() && wasCulling && this->Record.Inputs().mesh == key.mesh &&
    this->NewList == this->List;
  if (!same)
  {
    this->List.swap(this->NewList);
  }
  this->Record.Store(key, !same);
  return true;
}

std::size_t CullingStage::VisibleCount() const
{
  return this->Record.Inputs().mode == CullingMode::None ? this->Record.Inputs().mesh.cellCount
                                                  : this->List.size();
}

void CullingStage::Forget()
{
  this->Record.Forget();
  this->RangesRecord.Forget();
}

void CullingStage::Release()
{
  std::vector<float>().swap(this->Ranges);
  std::vector<std::uint32_t>().swap(this->List);
  std::vector<std::uint32_t>().swap(this->NewList);
  this->Forget();
}

std::size_t CullingStage::MemoryBytes() const
{
  return this->Ranges.capacity() * sizeof(float) +
    (this->List.capacity() + this->NewList.capacity()) * sizeof(std::uint32_t);
}

} // namespace mtpt
