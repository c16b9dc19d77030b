// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/DepthKeys.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"
#include "detail/PixelCoverage.h"

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

/// Bits of the clip planes a usable projected point lies beyond (0: inside the frustum).
inline unsigned OutCode(const ProjectedPoint& p)
{
  return (p.x < -1.0 ? 1u : 0u) | (p.x > 1.0 ? 2u : 0u) | (p.y < -1.0 ? 4u : 0u) |
    (p.y > 1.0 ? 8u : 0u) | (p.z < -1.0 ? 16u : 0u) | (p.z > 1.0 ? 32u : 0u);
}

/// Why a cell was left out of the keys.
enum class Verdict
{
  Kept,
  OutsideFrustum,
  CoversNoPixel
};

/// The key of `cell`, or why it is culled (see KeyCulling; null `culling`: none).
template <typename Access>
inline Verdict CellKey(const Access& cells, const ProjectedPoint* points, std::uint32_t cell,
  bool perspective, const KeyCulling* culling, SortKey& key)
{
  std::int64_t ids[4];
  float depth = std::numeric_limits<float>::infinity();
  if (cells.TetrahedronPoints(cell, ids))
  {
    const ProjectedPoint* corners[4] = { points + ids[0], points + ids[1], points + ids[2],
      points + ids[3] };
    unsigned outside = ~0u;
    int usable = 0;
    for (const ProjectedPoint* p : corners)
    {
      outside &= OutCode(*p);
      usable += p->usable;
    }
    if (culling && usable == 4)
    {
      if (culling->frustum && outside != 0)
      {
        return Verdict::OutsideFrustum;
      }
      if (culling->viewportWidth > 0 && culling->viewportHeight > 0 &&
        !detail::CoversPixelCentre(corners, culling->viewportWidth, culling->viewportHeight))
      {
        return Verdict::CoversNoPixel;
      }
    }
    depth = CentroidDepth(corners, perspective);
  }
  key = MakeSortKey(depth, cell);
  return Verdict::Kept;
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
#pragma omp parallel for num_threads(nthreads) schedule(static)
      for (std::int64_t c = 0; c < count; ++c)
      {
        CellKey(access, points, static_cast<std::uint32_t>(c), perspective, nullptr, keys[c]);
      }
    });
}

KeyCounts ComputeVisibleDepthKeys(const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, bool perspective,
  const KeyCulling& culling, SortKey* keys, int threads)
{
  const std::size_t n = list ? listCount : cells.cellCount;
  KeyCounts counts;
  std::size_t pixelCulled = 0;
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      counts.kept = detail::CompactInOrder(n, detail::ResolveThreads(threads), keys,
        [&](std::size_t begin, std::size_t end, SortKey* out)
        {
          std::size_t written = 0, noPixel = 0;
          for (std::size_t i = begin; i < end; ++i)
          {
            const auto cell = list ? list[i] : static_cast<std::uint32_t>(i);
            const Verdict verdict =
              CellKey(access, points, cell, perspective, &culling, out[written]);
            written += verdict == Verdict::Kept ? 1 : 0;
            noPixel += verdict == Verdict::CoversNoPixel ? 1 : 0;
          }
#pragma omp atomic
          pixelCulled += noPixel;
          return written;
        });
    });
  counts.pixelCulled = pixelCulled;
  counts.frustumCulled = n - counts.kept - pixelCulled;
  return counts;
}

bool DepthKeyStage::Update(const Key& key, const ProjectedPoint* points, std::size_t pointCount,
  const CellsView& cells, const std::uint32_t* list, std::size_t listCount, int threads)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  this->Kept.resize(list ? listCount : cells.cellCount);
  this->Count = ComputeVisibleDepthKeys(points, pointCount, cells, list, listCount, key.perspective,
    key.culling, this->Kept.data(), threads);
  this->Kept.resize(this->Count.kept);
  this->Record.Store(key);
  return true;
}

void DepthKeyStage::Release()
{
  std::vector<SortKey>().swap(this->Kept);
  this->Record.Forget();
}

} // namespace mtpt
