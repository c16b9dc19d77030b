// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/DepthKeys.h"
#include "mtpt/Faults.h"

#include "detail/KeyBatch.h"
#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

namespace mtpt
{

std::uint32_t EncodeDepth(float depth)
{
  if (!std::isfinite(depth))
  {
    depth = std::numeric_limits<float>::infinity();
  }
  depth += 0.0f; // -0 + +0 == +0: equal depths get equal bits
  std::uint32_t bits;
  std::memcpy(&bits, &depth, sizeof(bits));
  // IEEE-754 to an unsigned code that ascends with the float: flip all bits of negatives,
  // only the sign bit of positives. Complementing it makes ascending codes descending
  // depth, i.e. back to front.
  const std::uint32_t ascending = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  return ~ascending;
}

namespace
{

/// The key of `cell`: its centroid depth, +infinity when it is not a tetrahedron.
template <typename Access>
inline SortKey CellKey(
  const Access& cells, const ProjectedPoint* points, std::uint32_t cell, bool perspective)
{
  std::int64_t ids[4];
  float depth = std::numeric_limits<float>::infinity();
  if (cells.TetrahedronPoints(cell, ids))
  {
    const ProjectedPoint* corners[4] = { points + ids[0], points + ids[1], points + ids[2],
      points + ids[3] };
    depth = CentroidDepth(corners, perspective);
  }
  return MakeSortKey(depth, cell);
}

/**
 * The keys of the cells list[begin, end) (null list: the cell ids themselves) that `rules`
 * keep, several cells at a time (detail/KeyBatch.h: the frustum and pixel-centre culling of
 * KeyCulling, then CellKey's depth), written to out[0..) in list order. Returns their
 * number; `pixelCulled` counts the cells covering no pixel centre.
 */
template <typename Access>
std::size_t KeysInBatches(const Access& cells, const ProjectedPoint* points,
  const std::uint32_t* list, std::size_t begin, std::size_t end, const detail::KeyRules& rules,
  SortKey* out, std::size_t& pixelCulled)
{
  std::size_t written = 0;
  detail::KeyBatch batch;
  detail::KeyBatchResult result;
  std::uint32_t ids[detail::BatchSize];
  bool tetrahedron[detail::BatchSize];
  for (std::size_t first = begin; first < end; first += detail::BatchSize)
  {
    const int count = static_cast<int>(std::min<std::size_t>(detail::BatchSize, end - first));
    int valid = -1; // a lane with valid point ids, to pad the others with
    for (int l = 0; l < count; ++l)
    {
      ids[l] = list ? list[first + l] : static_cast<std::uint32_t>(first + l);
      std::int64_t corners[4];
      tetrahedron[l] = cells.TetrahedronPoints(ids[l], corners);
      if (tetrahedron[l])
      {
        valid = l;
        for (int i = 0; i < 4; ++i)
        {
          batch.point[i][l] = corners[i];
        }
      }
    }
    if (valid >= 0)
    {
      for (int l = 0; l < detail::BatchSize; ++l)
      {
        if (l >= count || !tetrahedron[l])
        {
          for (int i = 0; i < 4; ++i)
          {
            batch.point[i][l] = batch.point[i][valid];
          }
        }
      }
      detail::ComputeKeyBatch(points, batch, count, rules, result);
    }
    for (int l = 0; l < count; ++l)
    {
      if (!tetrahedron[l])
      {
        out[written++] = MakeSortKey(std::numeric_limits<float>::infinity(), ids[l]);
        continue;
      }
      pixelCulled += result.verdict[l] == detail::KeyCoversNoPixel;
      if (result.verdict[l] == detail::KeyKept)
      {
        out[written++] = MakeSortKey(static_cast<float>(result.depth[l]), ids[l]);
      }
    }
  }
  return written;
}

} // namespace

void ComputeDepthKeys(const ProjectedPoint* points, std::size_t pointCount, const CellsView& cells,
  bool perspective, SortKey* keys, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto count = static_cast<std::int64_t>(cells.cellCount);
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      detail::ParallelFor(0, count, nthreads,
        [&](std::int64_t c)
        { keys[c] = CellKey(access, points, static_cast<std::uint32_t>(c), perspective); });
    });
}

KeyCounts ComputeVisibleDepthKeys(const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, bool perspective,
  const KeyCulling& culling, SortKey* keys, int threads)
{
  const std::size_t n = list ? listCount : cells.cellCount;
  KeyCounts counts;
  std::atomic<std::size_t> pixelCulled{ 0 };
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      const detail::KeyRules rules{ perspective, culling.frustum, culling.imageSize };
      counts.kept = detail::CompactInOrder(n, detail::ResolveThreads(threads), keys,
        [&](std::size_t begin, std::size_t end, SortKey* out)
        {
          std::size_t noPixel = 0;
          const std::size_t written =
            KeysInBatches(access, points, list, begin, end, rules, out, noPixel);
          pixelCulled += noPixel;
          return written;
        });
    });
  counts.pixelCulled = pixelCulled.load();
  counts.frustumCulled = n - counts.kept - counts.pixelCulled;
  return counts;
}

bool DepthKeyStage::Update(const Key& key, const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  AllocationPoint(AllocationSite::DepthKeys);
  this->Kept.resize(list ? listCount : cells.cellCount);
  this->Count = ComputeVisibleDepthKeys(points, pointCount, cells, list, listCount, key.perspective,
    key.culling, this->Kept.data(), threads);
  this->Kept.resize(this->Count.kept);
  this->Used = false;
  this->Record.Store(key);
  return true;
}

void DepthKeyStage::Release()
{
  LargeVector<SortKey>().swap(this->Kept);
  this->Used = false;
  this->Record.Forget();
}

} // namespace mtpt
