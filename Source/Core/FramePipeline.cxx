// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/FramePipeline.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mtpt
{

namespace
{

using Clock = std::chrono::steady_clock;

/// Grow-only resize: a vector keeps its size across frames, so frames that shrink and
/// grow again do not value-initialize memory they already had.
template <typename T>
void EnsureSize(std::vector<T>& v, std::size_t n)
{
  if (v.size() < n)
  {
    v.resize(n);
  }
}

template <typename T>
std::size_t Bytes(const std::vector<T>& v)
{
  return v.capacity() * sizeof(T);
}

/// The unit view direction in model space (the third row of the model-view matrix).
void ViewDirection(const Matrix4& m, double d[3])
{
  const double length = std::sqrt(m[8] * m[8] + m[9] * m[9] + m[10] * m[10]);
  for (int i = 0; i < 3; ++i)
  {
    d[i] = length > 0 ? m[8 + i] / length : 0.0;
  }
}

} // namespace

bool FramePipeline::Inputs::operator==(const Inputs& o) const
{
  return points == o.points && pointCount == o.pointCount && connectivity == o.connectivity &&
    offsets == o.offsets && cellSize == o.cellSize && cellCount == o.cellCount &&
    scalars == o.scalars && colours == o.colours && association == o.association &&
    dataVersion == o.dataVersion;
}

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

std::size_t FramePipeline::MemoryBytes() const
{
  return Bytes(this->ProjectedPoints) + Bytes(this->CellRanges) + Bytes(this->Visible) +
    Bytes(this->NewVisible) + Bytes(this->SortedKeys) + Bytes(this->Scratch) + Bytes(this->Rank) +
    Bytes(this->VertexBuffer) + Bytes(this->IndexBuffer) + Bytes(this->FanBuffer) +
    Bytes(this->Classes) + Bytes(this->Pieces) + Bytes(this->PieceKeys) + Bytes(this->Crossing) +
    this->Order->MemoryBytes();
}

void FramePipeline::Release()
{
  for (auto* v : { &this->Visible, &this->NewVisible, &this->Rank, &this->IndexBuffer })
  {
    std::vector<std::uint32_t>().swap(*v);
  }
  std::vector<ProjectedPoint>().swap(this->ProjectedPoints);
  std::vector<float>().swap(this->CellRanges);
  std::vector<SortKey>().swap(this->SortedKeys);
  std::vector<SortKey>().swap(this->Scratch);
  std::vector<TetVertex>().swap(this->VertexBuffer);
  std::vector<Fan>().swap(this->FanBuffer);
  std::vector<ProjectionClass>().swap(this->Classes);
  std::vector<NearPiece>().swap(this->Pieces);
  std::vector<SortKey>().swap(this->PieceKeys);
  std::vector<std::uint8_t>().swap(this->Crossing);
  this->Order = MakeVisibilityOrder(this->Order->Method(), this->MaxSubArraySize);
  this->HaveTransform = this->HaveRanges = this->HaveVisible = this->HaveOrder = false;
  this->SlotWindow.valid = this->FanWindow.valid = false;
  this->SortedSize = this->BatchCount = this->FanBatchCount = 0;
  this->SlotWindow = this->FanWindow = Window{};
  ++this->BuffersVersion;
  ++this->FansVersion;
}

void FramePipeline::SetOrderMutationForTesting(OrderMutation mutation)
{
  this->Mutation = mutation;
}

bool FramePipeline::Run(const FrameInput& input, int threads)
{
  if (!this->Prepare(input, threads))
  {
    return false;
  }
  this->DecomposeBatch(0, this->SortedSize, threads);
  return true;
}

bool FramePipeline::Prepare(const FrameInput& input, int threads)
{
  const std::size_t n = input.cells.cellCount;
  threads = ThreadsForWork(std::max(n, input.points.count), detail::CellsPerThread, threads);
  this->LastTimes = StageTimes{};
  this->LastStats = FrameStats{};
  this->LastStats.cells = n;
  this->BatchCount = this->FanBatchCount = 0;
  this->WasStopped = false;
  if (n > MaxTetrahedra())
  {
    this->SortedSize = 0;
    this->HaveOrder = false;
    this->SlotWindow.valid = this->FanWindow.valid = false;
    return false;
  }
  Inputs data;
  data.points = input.points.data;
  data.pointCount = input.points.count;
  data.connectivity = input.cells.connectivity;
  data.offsets = input.cells.offsets;
  data.cellSize = input.cells.cellSize;
  data.cellCount = n;
  data.scalars = input.scalars.values;
  data.colours = input.colours;
  data.association = input.scalars.association;
  data.dataVersion = input.dataVersion;
  const bool dataChanged = !this->Reuse || !(data == this->Data);
  if (dataChanged)
  {
    this->Data = data;
    this->HaveTransform = this->HaveRanges = this->HaveVisible = this->HaveOrder = false;
    this->SlotWindow.valid = this->FanWindow.valid = false;
  }

  const bool viewChanged = !this->HaveTransform || input.modelView != this->TransformModelView ||
    input.projection != this->TransformProjection;
  if (viewChanged)
  {
    const auto start = Clock::now();
    EnsureSize(this->ProjectedPoints, input.points.count);
    ProjectPoints(input.points, input.scalars, input.modelView, input.projection,
      this->ProjectedPoints.data(), threads);
    this->LastTimes.transform = detail::SecondsSince(start);
    this->TransformModelView = input.modelView;
    this->TransformProjection = input.projection;
    this->HaveTransform = true;
    ++this->PointsVersion;
  }
  this->LastStats.transformReused = !viewChanged;
  if (!this->Continue(Stage::Transform))
  {
    return false;
  }

  this->UpdateCulling(input, threads, dataChanged);
  if (!this->Continue(Stage::Cull) || !this->UpdateOrder(input, threads, dataChanged, viewChanged))
  {
    return false;
  }

  DecomposeInput& d = this->DecomposeState;
  d.points = this->ProjectedPoints.data();
  d.pointCount = input.points.count;
  d.cells = input.cells;
  d.scalars = input.scalars;
  d.colours = input.colours;
  d.viewportWidth = input.viewportWidth;
  d.viewportHeight = input.viewportHeight;
  d.cellsCoverPixels = true; // UpdateOrder's keys culled with this viewport (KeyCulling)
  return this->Continue(Stage::Order);
}

bool FramePipeline::Continue(Stage finished)
{
  if (this->Callback && !this->Callback(finished))
  {
    this->WasStopped = true;
    // Whatever was kept may be incomplete: the next frame starts from the transform.
    this->HaveOrder = false;
    this->SlotWindow.valid = this->FanWindow.valid = false;
    this->SortedSize = 0;
    return false;
  }
  return true;
}

void FramePipeline::UpdateCulling(const FrameInput& input, int threads, bool dataChanged)
{
  const std::size_t n = input.cells.cellCount;
  const bool byAttenuation = input.colours != nullptr;
  const bool cull = byAttenuation || (input.opacity.table && input.opacity.size > 0);
  if (!cull)
  {
    if (this->CullByOpacity)
    {
      this->CullByOpacity = false;
      ++this->VisibleVersion; // every cell is a candidate again
    }
    return;
  }
  const auto start = Clock::now();
  if (!this->HaveRanges || dataChanged)
  {
    EnsureSize(this->CellRanges, 2 * n);
    ComputeCellScalarRanges(
      input.cells, input.points.count, input.scalars, this->CellRanges.data(), threads);
    this->HaveRanges = true;
    this->HaveVisible = false;
  }
  const TransferFunctionTable& t = input.opacity;
  // With dependent components the scalars are the attenuations: no table is read.
  const bool tableChanged = !this->HaveVisible || !this->Reuse ||
    byAttenuation != this->CullByAttenuation ||
    (!byAttenuation &&
      (input.opacityVersion != this->OpacityVersion || t.table != this->OpacityTable.table ||
        t.size != this->OpacityTable.size || t.low != this->OpacityTable.low ||
        t.high != this->OpacityTable.high));
  if (tableChanged)
  {
    if (byAttenuation)
    {
      this->Opacity.SetAttenuations();
    }
    else
    {
      this->Opacity.SetTable(t);
    }
    this->CullByAttenuation = byAttenuation;
    this->NewVisible.resize(n);
    this->NewVisible.resize(this->Opacity.SelectVisibleCells(
      this->CellRanges.data(), n, this->NewVisible.data(), threads));
    // A new table that leaves the same cells visible (a colour change) keeps the order.
    if (!this->HaveVisible || !this->CullByOpacity || this->NewVisible != this->Visible)
    {
      this->Visible.swap(this->NewVisible);
      ++this->VisibleVersion;
    }
    this->HaveVisible = true;
    this->OpacityVersion = input.opacityVersion;
    this->OpacityTable = t;
    this->LastTimes.cull = detail::SecondsSince(start); // ranges included when computed
  }
  this->CullByOpacity = true;
  this->LastStats.opacityCulled = n - this->Visible.size();
}

bool FramePipeline::UpdateOrder(
  const FrameInput& input, int threads, bool dataChanged, bool viewChanged)
{
  const std::size_t n = input.cells.cellCount;
  const bool valid = this->HaveOrder && this->OrderPointsVersion == this->PointsVersion &&
    this->OrderVisibleVersion == this->VisibleVersion &&
    this->OrderPerspective == input.perspective && this->OrderCullFrustum == input.cullFrustum &&
    this->OrderViewport[0] == input.viewportWidth &&
    this->OrderViewport[1] == input.viewportHeight &&
    this->OrderMethodUsed == this->Order->Method() && this->OrderMutationUsed == this->Mutation;
  if (valid)
  {
    this->LastStats.orderReused = true;
    this->LastStats.frustumCulled = this->OrderFrustumCulled;
    this->LastStats.pixelCulled = this->OrderPixelCulled;
    this->LastStats.nearClipped = this->OrderNearClipped;
    this->LastStats.nearPieces = this->Pieces.size();
    this->LastStats.sorted = this->SortedSize;
    return true;
  }

  auto start = Clock::now();
  const std::uint32_t* list = this->CullByOpacity ? this->Visible.data() : nullptr;
  const std::size_t listCount = this->CullByOpacity ? this->Visible.size() : n;
  this->SortedKeys.resize(listCount);
  KeyCulling culling;
  culling.frustum = input.cullFrustum;
  culling.viewportWidth = input.viewportWidth;
  culling.viewportHeight = input.viewportHeight;
  const KeyCounts counts = ComputeVisibleDepthKeys(this->ProjectedPoints.data(), input.points.count,
    input.cells, list, listCount, input.perspective, culling, this->SortedKeys.data(), threads);
  const std::size_t frustumCulled = counts.frustumCulled;
  std::size_t count = counts.kept;
  this->SortedKeys.resize(count);
  const std::size_t nearClipped = this->ClipNearPlane(input, threads);
  count = this->SortedKeys.size();
  this->LastTimes.keys = detail::SecondsSince(start);
  if (!this->Continue(Stage::DepthKeys))
  {
    return false;
  }

  start = Clock::now();
  double direction[3];
  ViewDirection(input.modelView, direction);
  const double dot = direction[0] * this->OrderDirection[0] +
    direction[1] * this->OrderDirection[1] + direction[2] * this->OrderDirection[2];
  const double angle = std::acos(std::min(1.0, std::max(-1.0, dot)));
  // The same cells as the previous order (nothing entered or left the view or the visible
  // set): their keys in the previous order are nearly sorted after a small rotation.
  const bool samePermutation = this->Reuse && this->HaveOrder && !dataChanged && viewChanged &&
    this->OrderVisibleVersion == this->VisibleVersion &&
    this->OrderPerspective == input.perspective && this->OrderFrustumCulled == 0 &&
    frustumCulled == 0 && this->OrderPixelCulled == 0 && counts.pixelCulled == 0 &&
    nearClipped == 0 && this->OrderNearClipped == 0 && count == this->SortedSize &&
    angle < NearlySortedMaxAngle && this->Mutation == OrderMutation::None;
  bool fromPrevious = false;
  if (samePermutation)
  {
    EnsureSize(this->Scratch, count);
    const auto m = static_cast<std::int64_t>(count);
#pragma omp parallel for num_threads(detail::ResolveThreads(threads)) schedule(static)
    for (std::int64_t i = 0; i < m; ++i)
    {
      const SortKey key = this->SortedKeys[i];
      this->Scratch[this->Rank[CellOfKey(key)]] = key;
    }
    // Budget: about the cost of a full sort; beyond it the keys moved too far.
    if (SortNearlySorted(this->Scratch.data(), count, 4 * count, threads))
    {
      std::copy(this->Scratch.begin(), this->Scratch.begin() + m, this->SortedKeys.begin());
      fromPrevious = true;
    }
  }
  if (!fromPrevious)
  {
    this->Order->Sort(this->SortedKeys.data(), count, threads);
  }
  if (!this->PieceKeys.empty())
  {
    // The pieces of cells cut by the near plane, sorted and merged into the order.
    std::sort(this->PieceKeys.begin(), this->PieceKeys.end());
    this->Scratch.resize(count + this->PieceKeys.size());
    std::merge(this->SortedKeys.begin(), this->SortedKeys.begin() + count, this->PieceKeys.begin(),
      this->PieceKeys.end(), this->Scratch.begin());
    this->SortedKeys.swap(this->Scratch);
    count = this->SortedKeys.size();
  }
  this->MutateOrder(count);
  this->LastTimes.order = detail::SecondsSince(start);

  start = Clock::now();
  const std::size_t ranked = n + this->Pieces.size();
  EnsureSize(this->Rank, ranked);
  InvertOrder(this->SortedKeys.data(), count, ranked, this->Rank.data(), threads);
  this->LastTimes.decompose += detail::SecondsSince(start);

  this->SortedSize = count;
  this->HaveOrder = true;
  this->OrderPointsVersion = this->PointsVersion;
  this->OrderVisibleVersion = this->VisibleVersion;
  this->OrderPerspective = input.perspective;
  this->OrderCullFrustum = input.cullFrustum;
  this->OrderViewport[0] = input.viewportWidth;
  this->OrderViewport[1] = input.viewportHeight;
  this->OrderPixelCulled = counts.pixelCulled;
  this->OrderMethodUsed = this->Order->Method();
  this->OrderMutationUsed = this->Mutation;
  this->OrderFrustumCulled = frustumCulled;
  this->OrderNearClipped = nearClipped;
  std::copy(direction, direction + 3, this->OrderDirection);
  ++this->OrderVersion;
  this->LastStats.frustumCulled = frustumCulled;
  this->LastStats.pixelCulled = counts.pixelCulled;
  this->LastStats.nearClipped = nearClipped;
  this->LastStats.nearPieces = this->Pieces.size();
  this->LastStats.sorted = count;
  this->LastStats.orderFromPrevious = fromPrevious;
  return true;
}

void FramePipeline::MutateOrder(std::size_t count)
{
  if (this->Mutation == OrderMutation::Reversed)
  {
    std::reverse(this->SortedKeys.begin(), this->SortedKeys.begin() + count);
  }
  else if (this->Mutation == OrderMutation::Storage)
  {
    std::sort(this->SortedKeys.begin(), this->SortedKeys.begin() + count,
      [](SortKey a, SortKey b) { return CellOfKey(a) < CellOfKey(b); });
  }
}

std::size_t FramePipeline::ClipNearPlane(const FrameInput& input, int threads)
{
  this->Pieces.clear();
  this->PieceKeys.clear();
  const NearPlane plane(input.projection);
  const ProjectedPoint* points = this->ProjectedPoints.data();
  const auto pointCount = static_cast<std::int64_t>(input.points.count);
  const int nthreads = detail::ResolveThreads(threads);
  // Most frames have no point in front of the plane: one pass over the points decides.
  int any = 0;
#pragma omp parallel for num_threads(nthreads) schedule(static) reduction(| : any)
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    any |= HasFiniteEyeCoordinates(points[i]) && plane.Distance(points[i]) < 0.0 ? 1 : 0;
  }
  if (!any)
  {
    return 0;
  }
  const std::size_t n = input.cells.cellCount;
  const float* cellScalars =
    input.scalars.association == ScalarsView::Association::Cells ? input.scalars.values : nullptr;
  const auto count = static_cast<std::int64_t>(this->SortedKeys.size());
  EnsureSize(this->Crossing, this->SortedKeys.size());
  // 0: keep, 1: crosses the plane (cut), 2: wholly in front of it (dropped).
  detail::DispatchCells(input.cells, input.points.count,
    [&](const auto& cells)
    {
#pragma omp parallel for num_threads(nthreads) schedule(static)
      for (std::int64_t k = 0; k < count; ++k)
      {
        const std::uint32_t cell = CellOfKey(this->SortedKeys[k]);
        std::int64_t ids[4];
        std::uint8_t verdict = 0;
        if (cells.TetrahedronPoints(cell, ids) &&
          (!cellScalars || std::isfinite(cellScalars[cell])))
        {
          int front = 0, finite = 0;
          for (int i = 0; i < 4; ++i)
          {
            const ProjectedPoint& p = points[ids[i]];
            const bool ok = HasFiniteEyeCoordinates(p);
            finite += ok ? 1 : 0;
            front += ok && plane.Distance(p) < 0.0 ? 1 : 0;
          }
          verdict = finite < 4 || front == 0 ? 0 : (front == 4 ? 2 : 1);
        }
        this->Crossing[k] = verdict;
      }
    });
  // In order (deterministic piece ids): keep the others' keys, cut the crossing cells.
  std::size_t kept = 0, clipped = 0;
  detail::DispatchCells(input.cells, input.points.count,
    [&](const auto& cells)
    {
      for (std::int64_t k = 0; k < count; ++k)
      {
        const SortKey key = this->SortedKeys[k];
        if (this->Crossing[k] == 0 || n + this->Pieces.size() + 3 > MaxTetrahedra())
        {
          this->SortedKeys[kept++] = key;
          continue;
        }
        if (this->Crossing[k] == 2)
        {
          continue;
        }
        const std::uint32_t cell = CellOfKey(key);
        std::int64_t ids[4] = { 0, 0, 0, 0 };
        cells.TetrahedronPoints(cell, ids); // succeeded when the verdict was made
        const ProjectedPoint* corners[4] = { points + ids[0], points + ids[1], points + ids[2],
          points + ids[3] };
        float scalars[4];
        const float* colours[4] = { nullptr, nullptr, nullptr, nullptr };
        for (int i = 0; i < 4; ++i)
        {
          scalars[i] = cellScalars ? cellScalars[cell] : corners[i]->scalar;
          if (input.colours)
          {
            colours[i] =
              input.colours + 4 * (cellScalars ? static_cast<std::int64_t>(cell) : ids[i]);
          }
        }
        const std::size_t before = this->Pieces.size();
        CutTetrahedron(corners, scalars, plane, input.projection, this->Pieces,
          input.colours ? colours : nullptr);
        ++clipped;
        for (std::size_t j = before; j < this->Pieces.size(); ++j)
        {
          // The same key as a cell's (DepthKeys.h): its centroid's depth.
          double x = 0, y = 0, z = 0;
          for (const ProjectedPoint& p : this->Pieces[j].corners)
          {
            x += 0.25 * p.eyeX;
            y += 0.25 * p.eyeY;
            z += 0.25 * p.eyeZ;
          }
          const auto depth = static_cast<float>(input.perspective ? x * x + y * y + z * z : -z);
          this->PieceKeys.push_back(MakeSortKey(depth, static_cast<std::uint32_t>(n + j)));
        }
      }
    });
  this->SortedKeys.resize(kept);
  return clipped;
}

bool FramePipeline::Window::Holds(
  std::uint64_t order, std::size_t first, std::size_t count, const DecomposeInput& in) const
{
  return this->valid && this->orderVersion == order && this->first == first &&
    this->count == count && this->viewport[0] == in.viewportWidth &&
    this->viewport[1] == in.viewportHeight;
}

template <typename Cells, typename Piece>
bool FramePipeline::DecomposeWindow(Window& window, std::size_t& first, std::size_t& count,
  int threads, Cells&& decomposeCells, Piece&& decomposePiece)
{
  first = std::min(first, this->SortedSize);
  count = std::min(count, this->SortedSize - first);
  // The decomposition by rank visits every cell of the mesh (DecomposeTetrahedraByRank).
  threads = ThreadsForWork(this->LastStats.cells + count, detail::CellsPerThread, threads);
  ++this->LastStats.batches;
  const DecomposeInput& in = this->DecomposeState;
  if (this->Reuse && window.Holds(this->OrderVersion, first, count, in))
  {
    this->LastStats.decompositionReused = true;
    this->LastStats.pixelCulled += window.pixelCulled;
    this->LastStats.notDrawable += window.notDrawable;
    return false;
  }
  const auto start = Clock::now();
  EnsureSize(this->Classes, count);
  decomposeCells(in, first, count, threads);
  // Pieces of cells cut by the near plane: ranks after the cells'.
  const auto pieces = static_cast<std::int64_t>(this->Pieces.size());
#pragma omp parallel for num_threads(detail::ResolveThreads(threads))                              \
  schedule(static) if (pieces > 1024)
  for (std::int64_t j = 0; j < pieces; ++j)
  {
    const std::uint32_t r = this->Rank[in.cells.cellCount + j];
    const std::uint64_t k = static_cast<std::uint64_t>(r) - first;
    if (r != NotInOrder && k < count)
    {
      const NearPiece& piece = this->Pieces[j];
      const ProjectedPoint* corners[4] = { &piece.corners[0], &piece.corners[1], &piece.corners[2],
        &piece.corners[3] };
      const float* colours[4] = { piece.colours[0], piece.colours[1], piece.colours[2],
        piece.colours[3] };
      this->Classes[k] =
        decomposePiece(in, corners, piece.scalars, in.colours ? colours : nullptr, k);
    }
  }
  std::size_t pixelCulled = 0, notDrawable = 0;
  const auto m = static_cast<std::int64_t>(count);
#pragma omp parallel for num_threads(detail::ResolveThreads(threads)) schedule(static) \
  reduction(+ : pixelCulled, notDrawable)
  for (std::int64_t k = 0; k < m; ++k)
  {
    pixelCulled += this->Classes[k] == ProjectionClass::CoversNoPixel;
    notDrawable += this->Classes[k] == ProjectionClass::NotDrawable;
  }
  this->LastTimes.decompose += detail::SecondsSince(start);
  this->LastStats.pixelCulled += pixelCulled;
  this->LastStats.notDrawable += notDrawable;
  window = Window{ true, this->OrderVersion, first, count, { in.viewportWidth, in.viewportHeight },
    pixelCulled, notDrawable };
  return true;
}

void FramePipeline::DecomposeBatch(std::size_t first, std::size_t count, int threads)
{
  const bool decomposed = this->DecomposeWindow(
    this->SlotWindow, first, count, threads,
    [&](const DecomposeInput& in, std::size_t from, std::size_t n, int team)
    {
      EnsureSize(this->VertexBuffer, VerticesPerTetrahedron * n);
      EnsureSize(this->IndexBuffer, IndicesPerTetrahedron * n);
      DecomposeTetrahedraByRank(in, this->Rank.data(), from, n, this->VertexBuffer.data(),
        this->IndexBuffer.data(), this->Classes.data(), team);
    },
    [&](const DecomposeInput& in, const ProjectedPoint* const corners[4], const float* scalars,
      const float* const* colours, std::uint64_t k)
    {
      return DecomposeIntoSlot(
        in, corners, scalars, k, this->VertexBuffer.data(), this->IndexBuffer.data(), colours);
    });
  this->BatchCount = count;
  this->BuffersVersion += decomposed ? 1 : 0;
}

void FramePipeline::DecomposeFans(std::size_t first, std::size_t count, int threads)
{
  const bool decomposed = this->DecomposeWindow(
    this->FanWindow, first, count, threads,
    [&](const DecomposeInput& in, std::size_t from, std::size_t n, int team)
    {
      EnsureSize(this->FanBuffer, n);
      DecomposeFansByRank(
        in, this->Rank.data(), from, n, this->FanBuffer.data(), this->Classes.data(), team);
    },
    [&](const DecomposeInput& in, const ProjectedPoint* const corners[4], const float* scalars,
      const float* const* colours, std::uint64_t k)
    { return DecomposeIntoFan(in, corners, scalars, this->FanBuffer[k], colours); });
  this->FanBatchCount = count;
  this->FansVersion += decomposed ? 1 : 0;
}

} // namespace mtpt
