// SPDX-License-Identifier: BSD-3-Clause
// Internal: typed access to the views of MeshView.h, with one dispatch to the four
// (point type x index type) instantiations so hot loops read VTK's arrays in place.
#ifndef mtpt_detail_MeshAccess_h
#define mtpt_detail_MeshAccess_h

#include "mtpt/MeshView.h"

#include <cstdint>
#include <type_traits>

namespace mtpt
{
namespace detail
{

template<typename PointT, typename IndexT>
struct MeshAccess
{
  const PointT* xyz;
  const IndexT* connectivity;
  const IndexT* offsets;
  std::int64_t pointCount;

  /// The 4 point ids of `cell`; false if it is not a tetrahedron or an id is out of range.
  bool TetrahedronPoints(std::size_t cell, std::int64_t ids[4]) const
  {
    const std::int64_t begin = static_cast<std::int64_t>(this->offsets[cell]);
    const std::int64_t end = static_cast<std::int64_t>(this->offsets[cell + 1]);
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

  void Point(std::int64_t id, double p[3]) const
  {
    const PointT* q = this->xyz + 3 * id;
    p[0] = static_cast<double>(q[0]);
    p[1] = static_cast<double>(q[1]);
    p[2] = static_cast<double>(q[2]);
  }
};

/// Calls functor(MeshAccess<PointT, IndexT>) for the view's actual types.
template<typename Functor>
void DispatchMesh(const PointsView& points, const CellsView& cells, Functor&& functor)
{
  const auto n = static_cast<std::int64_t>(points.count);
  auto withPoints = [&](auto* xyz)
  {
    using PointT = std::remove_const_t<std::remove_pointer_t<decltype(xyz)>>;
    if (cells.type == CellsView::Type::Int32)
    {
      const auto* conn = static_cast<const std::int32_t*>(cells.connectivity);
      const auto* offs = static_cast<const std::int32_t*>(cells.offsets);
      functor(MeshAccess<PointT, std::int32_t>{ xyz, conn, offs, n });
    }
    else
    {
      const auto* conn = static_cast<const std::int64_t*>(cells.connectivity);
      const auto* offs = static_cast<const std::int64_t*>(cells.offsets);
      functor(MeshAccess<PointT, std::int64_t>{ xyz, conn, offs, n });
    }
  };
  if (points.type == PointsView::Type::Float32)
  {
    withPoints(static_cast<const float*>(points.data));
  }
  else
  {
    withPoints(static_cast<const double*>(points.data));
  }
}

} // namespace detail
} // namespace mtpt

#endif
