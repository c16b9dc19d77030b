// SPDX-License-Identifier: BSD-3-Clause
// Internal: typed access to the cells of MeshView.h, with one dispatch to the two index
// types so hot loops read vtkCellArray's arrays in place.
#ifndef mtpt_detail_MeshAccess_h
#define mtpt_detail_MeshAccess_h

#include "mtpt/MeshView.h"

#include <cstdint>

namespace mtpt
{
namespace detail
{

template <typename IndexT>
struct CellAccess
{
  const IndexT* connectivity;
  const IndexT* offsets;
  std::int64_t pointCount;

  /// The 4 point ids of `cell`; false if it is not a tetrahedron or an id is out of range.
  bool TetrahedronPoints(std::size_t cell, std::int64_t ids[4]) const
  {
    const auto begin = static_cast<std::int64_t>(this->offsets[cell]);
    const auto end = static_cast<std::int64_t>(this->offsets[cell + 1]);
    if (end - begin != 4)
    {
      return false;
    }
    bool valid = true;
    for (int i = 0; i < 4; ++i)
    {
      ids[i] = static_cast<std::int64_t>(this->connectivity[begin + i]);
      // One unsigned comparison covers both negative and too-large ids.
      valid &= static_cast<std::uint64_t>(ids[i]) < static_cast<std::uint64_t>(this->pointCount);
    }
    return valid;
  }
};

/**
 * Software prefetch along a known visiting order. Cells visited in visibility order are
 * scattered in memory, so every cell costs three dependent cache misses (offsets, then
 * connectivity, then the point records) that the hardware prefetcher cannot predict. Each
 * stage is issued a fixed distance ahead of its use: offsets 3*Distance cells ahead,
 * connectivity 2*Distance ahead (its offsets are cached by then), point records Distance
 * ahead (their ids are cached by then).
 */
template <typename IndexT, typename Record>
struct GatherPrefetcher
{
  static constexpr std::int64_t Distance = 8;

  const CellAccess<IndexT>& cells;
  const Record* records;

  template <typename CellOf>
  void Ahead(std::int64_t k, std::int64_t end, CellOf&& cellOf) const
  {
    if (k + 3 * Distance < end)
    {
      __builtin_prefetch(this->cells.offsets + cellOf(k + 3 * Distance));
    }
    if (k + 2 * Distance < end)
    {
      __builtin_prefetch(this->cells.connectivity + this->cells.offsets[cellOf(k + 2 * Distance)]);
    }
    if (k + Distance < end)
    {
      const std::size_t cell = cellOf(k + Distance);
      const auto begin = static_cast<std::int64_t>(this->cells.offsets[cell]);
      if (static_cast<std::int64_t>(this->cells.offsets[cell + 1]) - begin == 4)
      {
        for (int i = 0; i < 4; ++i)
        {
          const auto id = static_cast<std::uint64_t>(this->cells.connectivity[begin + i]);
          if (id < static_cast<std::uint64_t>(this->cells.pointCount))
          {
            __builtin_prefetch(this->records + id);
          }
        }
      }
    }
  }
};

/// Calls functor(CellAccess<IndexT>) for the view's actual index type.
template <typename Functor>
void DispatchCells(const CellsView& cells, std::size_t pointCount, Functor&& functor)
{
  const auto n = static_cast<std::int64_t>(pointCount);
  if (cells.type == CellsView::Type::Int32)
  {
    functor(CellAccess<std::int32_t>{ static_cast<const std::int32_t*>(cells.connectivity),
      static_cast<const std::int32_t*>(cells.offsets), n });
  }
  else
  {
    functor(CellAccess<std::int64_t>{ static_cast<const std::int64_t*>(cells.connectivity),
      static_cast<const std::int64_t*>(cells.offsets), n });
  }
}

} // namespace detail
} // namespace mtpt

#endif
