// SPDX-License-Identifier: BSD-3-Clause
// Internal: typed access to the cells of MeshView.h, with one dispatch to the two index
// types so hot loops read vtkCellArray's arrays in place.
#ifndef mtpt_detail_MeshAccess_h
#define mtpt_detail_MeshAccess_h

#include "mtpt/MeshView.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace mtpt
{
namespace detail
{

template <typename IndexT>
struct CellAccess
{
  const IndexT* connectivity;
  const IndexT* offsets; ///< null: every cell has cellSize points
  std::int64_t pointCount;
  std::int64_t cellSize;

  /// The 4 point ids of `cell`; false if it is not a tetrahedron or an id is out of range.
  bool TetrahedronPoints(std::size_t cell, std::int64_t ids[4]) const
  {
    std::int64_t begin, end;
    if (this->offsets)
    {
      begin = static_cast<std::int64_t>(this->offsets[cell]);
      end = static_cast<std::int64_t>(this->offsets[cell + 1]);
    }
    else
    {
      begin = static_cast<std::int64_t>(cell) * this->cellSize;
      end = begin + this->cellSize;
    }
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

/// The cells of several parts (MeshPart) as one mesh: cell ids and point ids run over the
/// parts in order.
struct PartsAccess
{
  struct Part
  {
    std::size_t firstCell;   ///< the part's first cell in the whole mesh
    std::int64_t firstPoint; ///< likewise its first point
    bool int32;
    CellAccess<std::int32_t> cells32;
    CellAccess<std::int64_t> cells64;
  };
  std::vector<Part> parts; ///< with cells, in order

  bool TetrahedronPoints(std::size_t cell, std::int64_t ids[4]) const
  {
    // The last part starting at or before `cell` (parts are few: a binary search).
    const auto next = std::upper_bound(this->parts.begin(), this->parts.end(), cell,
      [](std::size_t c, const Part& p) { return c < p.firstCell; });
    const Part& part = *(next - 1);
    const std::size_t local = cell - part.firstCell;
    const bool valid = part.int32 ? part.cells32.TetrahedronPoints(local, ids)
                                  : part.cells64.TetrahedronPoints(local, ids);
    if (valid)
    {
      for (int i = 0; i < 4; ++i)
      {
        ids[i] += part.firstPoint;
      }
    }
    return valid;
  }
};

template <typename IndexT>
CellAccess<IndexT> AccessOf(const CellsView& cells, std::size_t pointCount)
{
  return { static_cast<const IndexT*>(cells.connectivity),
    static_cast<const IndexT*>(cells.offsets), static_cast<std::int64_t>(pointCount),
    static_cast<std::int64_t>(cells.cellSize) };
}

/**
 * Calls functor(access) with the access of the view's actual layout: CellAccess<IndexT>
 * for a single mesh, PartsAccess for a mesh of parts. Every stage that reads cells goes
 * through here, so each is compiled once per layout.
 */
template <typename Functor>
void DispatchCells(const CellsView& cells, std::size_t pointCount, Functor&& functor)
{
  if (cells.parts)
  {
    PartsAccess access;
    std::size_t firstCell = 0;
    std::int64_t firstPoint = 0;
    for (std::size_t k = 0; k < cells.partCount; ++k)
    {
      const MeshPart& part = cells.parts[k];
      if (part.cells.cellCount > 0)
      {
        const bool int32 = part.cells.type == CellsView::Type::Int32;
        access.parts.push_back({ firstCell, firstPoint, int32,
          int32 ? AccessOf<std::int32_t>(part.cells, part.points.count)
                : CellAccess<std::int32_t>{},
          int32 ? CellAccess<std::int64_t>{}
                : AccessOf<std::int64_t>(part.cells, part.points.count) });
      }
      firstCell += part.cells.cellCount;
      firstPoint += static_cast<std::int64_t>(part.points.count);
    }
    if (!access.parts.empty())
    {
      functor(static_cast<const PartsAccess&>(access));
    }
    return;
  }
  const auto n = static_cast<std::int64_t>(pointCount);
  const auto size = static_cast<std::int64_t>(cells.cellSize);
  if (cells.type == CellsView::Type::Int32)
  {
    functor(CellAccess<std::int32_t>{ static_cast<const std::int32_t*>(cells.connectivity),
      static_cast<const std::int32_t*>(cells.offsets), n, size });
  }
  else
  {
    functor(CellAccess<std::int64_t>{ static_cast<const std::int64_t*>(cells.connectivity),
      static_cast<const std::int64_t*>(cells.offsets), n, size });
  }
}

} // namespace detail
} // namespace mtpt

#endif
