// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/FramePipeline.h"

#include "detail/Parallel.h"

#include <chrono>
#include <cstdint>
#include <limits>

namespace mtpt
{

FramePipeline::FramePipeline()
  : Order(MakeVisibilityOrder(OrderMethod::RadixSort))
{
}

void FramePipeline::SetOrderMethod(OrderMethod method, std::size_t maxSubArraySize)
{
  if (method != this->Order->Method() || maxSubArraySize != this->MaxSubArraySize)
  {
    this->Order = MakeVisibilityOrder(method, maxSubArraySize);
    this->MaxSubArraySize = maxSubArraySize;
  }
}

std::size_t FramePipeline::MaxTetrahedra()
{
  // Slot k's vertices are numbered from 5k with 32-bit indices; keys hold 32-bit cell ids.
  return std::numeric_limits<std::uint32_t>::max() / VerticesPerTetrahedron;
}

bool FramePipeline::Run(const FrameInput& input, int threads)
{
  using Clock = std::chrono::steady_clock;
  const std::size_t n = input.cells.cellCount;
  this->LastTimes = StageTimes{};
  this->Count = 0;
  if (n > MaxTetrahedra())
  {
    return false;
  }
  // Grow only: resize() value-initializes new elements once, later frames reuse them.
  if (this->ProjectedPoints.size() < input.points.count)
  {
    this->ProjectedPoints.resize(input.points.count);
  }
  this->SortedKeys.resize(n);
  this->Rank.resize(n);
  this->VertexBuffer.resize(VerticesPerTetrahedron * n);
  this->IndexBuffer.resize(IndicesPerTetrahedron * n);

  auto start = Clock::now();
  ProjectPoints(input.points, input.scalars, input.modelView, input.projection,
    this->ProjectedPoints.data(), threads);
  this->LastTimes.transform = detail::SecondsSince(start);

  start = Clock::now();
  ComputeDepthKeys(this->ProjectedPoints.data(), input.points.count, input.cells, input.perspective,
    this->SortedKeys.data(), threads);
  this->LastTimes.keys = detail::SecondsSince(start);

  start = Clock::now();
  this->Order->Sort(this->SortedKeys.data(), n, threads);
  this->LastTimes.order = detail::SecondsSince(start);

  start = Clock::now();
  DecomposeInput decompose;
  decompose.points = this->ProjectedPoints.data();
  decompose.pointCount = input.points.count;
  decompose.cells = input.cells;
  decompose.scalars = input.scalars;
  decompose.viewportWidth = input.viewportWidth;
  decompose.viewportHeight = input.viewportHeight;
  // Visiting cells in storage order and scattering the slots is several times faster than
  // gathering cells in visibility order on meshes larger than the cache (Decompose.h).
  InvertOrder(this->SortedKeys.data(), n, n, this->Rank.data(), threads);
  DecomposeTetrahedraByRank(decompose, this->Rank.data(), this->VertexBuffer.data(),
    this->IndexBuffer.data(), nullptr, threads);
  this->LastTimes.decompose = detail::SecondsSince(start);
  this->Count = n;
  return true;
}

} // namespace mtpt
