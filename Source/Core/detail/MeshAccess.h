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

/// Calls functor(CellAccess<IndexT>) for the view's actual index type.
template <typename Functor>
void DispatchCells(const CellsView& cells, std::size_t pointCount, Functor&& functor)
{
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
