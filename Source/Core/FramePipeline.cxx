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
  if (this->NdcPoints.size() < input.points.count)
  {
    this->NdcPoints.resize(input.points.count);
  }
  this->SortedKeys.resize(n);
  this->VertexBuffer.resize(VerticesPerTetrahedron * n);
  this->IndexBuffer.resize(IndicesPerTetrahedron * n);

  auto start = Clock::now();
  TransformToNDC(
    input.points, Multiply(input.projection, input.modelView), this->NdcPoints.data(), threads);
  this->LastTimes.transform = detail::SecondsSince(start);

  start = Clock::now();
  ComputeDepthKeys(input.points,
    input.cells,
    input.modelView,
    input.perspective,
    this->SortedKeys.data(),
    threads);
  this->LastTimes.keys = detail::SecondsSince(start);

  start = Clock::now();
  this->Order->Sort(this->SortedKeys.data(), n, threads);
  this->LastTimes.order = detail::SecondsSince(start);

  start = Clock::now();
  DecomposeInput decompose;
  decompose.ndc = this->NdcPoints.data();
  decompose.points = input.points;
  decompose.cells = input.cells;
  decompose.scalars = input.scalars;
  decompose.modelView = input.modelView;
  DecomposeTetrahedra(decompose,
    this->SortedKeys.data(),
    n,
    this->VertexBuffer.data(),
    this->IndexBuffer.data(),
    nullptr,
    threads);
  this->LastTimes.decompose = detail::SecondsSince(start);
  this->Count = n;
  return true;
}

} // namespace mtpt
