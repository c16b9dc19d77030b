// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/FramePipeline.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace mtpt
{

namespace
{

/// The unit view direction in model space (the third row of the model-view matrix).
std::array<double, 3> ViewDirection(const Matrix4& m)
{
  const double length = std::sqrt(m[8] * m[8] + m[9] * m[9] + m[10] * m[10]);
  std::array<double, 3> d{};
  for (int i = 0; i < 3; ++i)
  {
    d[i] = length > 0 ? m[8 + i] / length : 0.0;
  }
  return d;
}

// The stages' keys for a frame, each built here and only here.

TransformKey TransformKeyOf(const FrameInput& input, const MeshKey& mesh)
{
  TransformKey key;
  key.mesh = mesh;
  key.modelView = input.modelView;
  key.projection = input.projection;
  key.placement = input.placementVersion;
  return key;
}

/// By attenuations with dependent components, by the opacity table when one is given, else
/// none.
CullingKey CullingKeyOf(const FrameInput& input, const MeshKey& mesh)
{
  CullingKey key;
  key.mesh = mesh;
  if (input.colours)
  {
    key.mode = CullingMode::Attenuations;
  }
  else if (input.opacity.table && input.opacity.size > 0)
  {
    key.mode = CullingMode::Table;
    key.table.table = input.opacity.table;
    key.table.size = input.opacity.size;
    key.table.low = input.opacity.low;
    key.table.high = input.opacity.high;
    key.table.version = input.opacityVersion;
  }
  return key;
}

CellSelectionKey CellSelectionKeyOf(
  const FrameInput& input, const MeshKey& mesh, std::uint64_t visible)
{
  CellSelectionKey key;
  key.mesh = mesh;
  key.visible = visible;
  key.level = DetailLevelOf(input.cellFraction);
  return key;
}

DepthKeyStageKey DepthKeyStageKeyOf(
  const FrameInput& input, std::uint64_t points, std::uint64_t visible)
{
  DepthKeyStageKey key;
  key.points = points;
  key.visible = visible;
  key.perspective = input.perspective;
  key.culling.frustum = input.cullFrustum;
  key.culling.imageSize = input.imageSize;
  return key;
}

NearPlaneKey NearPlaneKeyOf(std::uint64_t keys)
{
  NearPlaneKey key;
  key.keys = keys;
  return key;
}

OrderKey OrderKeyOf(std::uint64_t keys, std::uint64_t nearPlane, OrderMethod method,
  std::size_t maxSubArraySize, OrderMutation mutation, bool sorted)
{
  OrderKey key;
  key.sorted = sorted;
  key.keys = keys;
  key.nearPlane = nearPlane;
  key.method = method;
  key.maxSubArraySize = maxSubArraySize;
  key.mutation = mutation;
  return key;
}

DecompositionKey DecompositionKeyOf(std::uint64_t order, std::size_t first, std::size_t count,
  const ImageSize& imageSize, const OpaquePixels* hidden)
{
  DecompositionKey key;
  key.order = order;
  key.first = first;
  key.count = count;
  key.imageSize = imageSize;
  key.hidden = hidden ? hidden->Version() : 0;
  return key;
}

} // namespace

template <typename Body>
auto FramePipeline::ForgettingOnFailure(Body&& body)
{
  try
  {
    return body();
  }
  catch (...)
  {
    // A failure partway (an allocation: std::bad_alloc) may leave a stage's buffers half
    // written: no result of the pipeline may serve again.
    this->ForgetFrom(0);
    this->SortedSize = this->BatchCount = this->FanBatchCount = 0;
    throw;
  }
}

template <typename Body>
bool FramePipeline::Timed(double& seconds, Body&& stage)
{
  const auto start = Clock::now();
  const bool computed = stage();
  if (computed)
  {
    seconds += SecondsSince(start);
  }
  return computed;
}

std::size_t FramePipeline::MemoryBytes() const
{
  std::size_t bytes = 0;
  for (const StageBase* stage : StagesOf(*this))
  {
    bytes += stage->MemoryBytes();
  }
  return bytes;
}

std::size_t FramePipeline::BytesNeeded(const MemoryNeed& need)
{
  // Each stage's buffers at their largest (their MemoryBytes). Per point: the projected
  // points.
  const std::size_t perPoint = sizeof(ProjectedPoint);
  // Per cell: the culling's list; the depth keys (the order's scratch once it took them);
  // the near plane's verdict (a byte per key); the order; the ranks; with the level of
  // detail, each cell's kept level (a byte) and the subset's list, at most the cells its
  // largest fraction keeps.
  const std::size_t perCell = sizeof(std::uint32_t) + sizeof(SortKey) + 1 + sizeof(SortKey) +
    sizeof(std::uint32_t) + (need.levelOfDetail ? 1 : 0);
  const std::size_t subset =
    need.levelOfDetail ? CellSelectionStage::LargestSubset(need.cells) * sizeof(std::uint32_t) : 0;
  // Per piece: the pieces and their keys (grown one at a time, so up to twice their number),
  // their places in the order and its scratch, and their ranks.
  const std::size_t perPiece =
    2 * sizeof(NearPiece) + 2 * sizeof(SortKey) + 2 * sizeof(SortKey) + sizeof(std::uint32_t);
  // Per cell of a window: 5 vertices and 12 indices (slots), a fan; each with its
  // projection class (a byte).
  const std::size_t perWindowCell = (need.slots ? VerticesPerTetrahedron * sizeof(TetVertex) +
                                          IndicesPerTetrahedron * sizeof(std::uint32_t) + 1
                                                : 0) +
    (need.fans ? sizeof(Fan) + 1 : 0);
  // The radix order's per-thread bucket counts (256 per pass and thread).
  const std::size_t counts =
    static_cast<std::size_t>(detail::ResolveThreads(need.threads)) * 256 * sizeof(std::size_t);
  const std::size_t window = std::min(need.batch, need.cells + need.pieces);
  // Batches smaller than the order: the groups' starts and the counts that place them (the
  // grouped cells take the depth keys' buffer).
  const std::size_t groups = window < need.cells + need.pieces ? (OrderStage::MaxGroups + 2) *
      sizeof(std::size_t) * (1 + static_cast<std::size_t>(detail::ResolveThreads(need.threads)))
                                                               : 0;
  return need.points * perPoint + need.cells * perCell + subset + need.pieces * perPiece +
    window * perWindowCell + counts + groups;
}

void FramePipeline::ForgetFrom(std::size_t first)
{
  const auto stages = StagesOf(*this);
  for (std::size_t i = first; i < stages.size(); ++i)
  {
    stages[i]->Forget();
  }
  this->LightsRecord.Forget(); // lit from the decompositions forgotten here
}

void FramePipeline::Release()
{
  for (StageBase* stage : StagesOf(*this))
  {
    stage->Release();
  }
  this->LightsRecord.Forget();
  std::vector<LightFactors>().swap(this->Lights);
  this->SortedSize = this->BatchCount = this->FanBatchCount = 0;
}

void ApplyPlan(const FramePlan& plan, FrameInput& input)
{
  if (!plan.cullOpacity)
  {
    input.opacity = TransferFunctionTable{};
    input.opacityVersion = 0;
  }
  input.cullFrustum = plan.cullFrustum;
  input.imageSize = plan.cullPixels ? plan.imageSize : ImageSize{};
  input.cellFraction = plan.cellFraction;
  input.ordered = plan.ordered;
  input.lit = plan.lit;
}

MemoryVerdict CheckMemory(const MemoryNeed& need, std::size_t limit, std::size_t held,
  const std::function<std::size_t()>& available)
{
  MemoryVerdict verdict;
  verdict.bytes = FramePipeline::BytesNeeded(need);
  verdict.limit = limit > 0 ? limit : held + available();
  verdict.fits = verdict.bytes <= verdict.limit;
  return verdict;
}

BatchesDrawn FramePipeline::DrawBatches(
  const FramePlan& plan, const BatchDrawer& draw, const OpaquePixels* hidden)
{
  return this->ForgettingOnFailure([&] { return this->DrawBatchesInOrder(plan, draw, hidden); });
}

BatchesDrawn FramePipeline::DrawBatchesInOrder(
  const FramePlan& plan, const BatchDrawer& draw, const OpaquePixels* hidden)
{
  BatchesDrawn drawn;
  const std::size_t total = this->SortedSize;
  const std::size_t batch =
    std::max<std::size_t>(1, plan.batchSize > 0 ? std::min(total, plan.batchSize) : total);
  const std::size_t windows = (total + batch - 1) / batch;
  for (std::size_t w = 0; w < windows; ++w)
  {
    // Back to front the windows start at rank 0; front to back at the last window.
    const std::size_t first = (plan.frontToBack ? windows - 1 - w : w) * batch;
    Batch b;
    b.first = first;
    if (plan.target == BatchTarget::Fans)
    {
      // Only pixels made opaque by the batches in front can hide cells.
      const bool hides = plan.frontToBack && hidden && !hidden->Empty();
      this->DecomposeFans(first, batch, plan.threads, hides ? hidden : nullptr);
      b.count = this->FanBatchCount;
      b.fans = this->FanBuffers.Fans().data();
      b.classes = this->FanBuffers.Classes();
      b.version = this->FanBuffers.Version();
    }
    else
    {
      this->DecomposeBatch(first, batch, plan.threads);
      b.count = this->BatchCount;
      b.vertices = this->Slots.Vertices().data();
      b.indices = this->Slots.Indices().data();
      b.version = this->Slots.Version();
    }
    if (this->FrameShading.lit)
    {
      b.lights = this->LightBatch(plan.target, first, batch, plan.threads);
      b.lightsVersion = this->LightsRecord.Version();
    }
    ++drawn.batches;
    if (!draw(b))
    {
      drawn.failed = true;
      return drawn;
    }
    const std::size_t done = std::min(total, (w + 1) * batch);
    if (done < total && this->AfterBatch &&
      !this->AfterBatch(static_cast<double>(done) / static_cast<double>(total)))
    {
      drawn.stopped = true;
      break;
    }
  }
  return drawn;
}

const LightFactors* FramePipeline::LightBatch(
  BatchTarget target, std::size_t first, std::size_t count, int threads)
{
  const FrameLighting& l = this->FrameShading;
  LightKey key;
  key.target = target;
  key.buffers = target == BatchTarget::Fans ? this->FanBuffers.Version() : this->Slots.Version();
  key.lighting = l.lighting;
  key.normals = l.normalsVersion;
  key.modelView = l.modelView;
  if (!this->LightsRecord.Holds(key))
  {
    this->LightWindow(first, count, l.lighting, l.normals, l.modelView, this->Lights, threads);
    this->LightsRecord.Store(key);
  }
  return this->Lights.data();
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

void FramePipeline::PrepareLevelOfDetail(const FrameInput& input, int threads)
{
  this->ForgettingOnFailure([&] { this->PrepareImportance(input, threads); });
}

void FramePipeline::PrepareImportance(const FrameInput& input, int threads)
{
  const std::size_t n = input.cells.cellCount;
  if (n > MaxTetrahedra() ||
    CellSelectionStage::KeepsEveryCell(DetailLevelOf(input.cellFraction), n))
  {
    return;
  }
  this->Selection.PrepareImportance(
    MeshKey::Of(input.points, input.cells, input.scalars, input.colours, input.dataVersion),
    input.points, input.cells, ThreadsForWork(n, detail::CellsPerThread, threads));
}

bool FramePipeline::Prepare(const FrameInput& input, int threads)
{
  return this->ForgettingOnFailure([&] { return this->PrepareStages(input, threads); });
}

bool FramePipeline::PrepareStages(const FrameInput& input, int threads)
{
  const std::size_t n = input.cells.cellCount;
  threads = ThreadsForWork(std::max(n, input.points.count), detail::CellsPerThread, threads);
  this->LastTimes = StageTimes{};
  this->LastStats = FrameStats{};
  this->LastStats.cells = n;
  this->SortedSize = this->BatchCount = this->FanBatchCount = 0;
  this->WasStopped = false;
  if (n > MaxTetrahedra())
  {
    this->Order.Forget();
    return false;
  }
  if (!this->Reuse)
  {
    this->ForgetFrom(0);
  }
  const MeshKey mesh =
    MeshKey::Of(input.points, input.cells, input.scalars, input.colours, input.dataVersion);
  this->FrameShading = { input.lit, input.lighting, input.normals, input.normalsVersion,
    input.modelView };

  // 1. Transform.
  const bool projected = Timed(this->LastTimes.transform,
    [&]
    {
      return this->Transform.Update(
        TransformKeyOf(input, mesh), input.points, input.scalars, threads);
    });
  this->LastStats.transformReused = !projected;
  if (!this->Continue(Stage::Transform))
  {
    return false;
  }
  // 2. Opacity culling.
  Timed(this->LastTimes.cull,
    [&]
    {
      return this->Culling.Update(CullingKeyOf(input, mesh), input.cells, input.points.count,
        input.scalars, input.opacity, threads);
    });
  this->LastStats.opacityCulled = this->Culling.Culled();
  // 2b. The level of detail's subset.
  Timed(this->LastTimes.select,
    [&]
    {
      return this->Selection.Update(CellSelectionKeyOf(input, mesh, this->Culling.Version()),
        input.points, input.cells, this->Culling.Visible(), this->Culling.VisibleCount(), threads);
    });
  this->LastStats.leftOut = this->Selection.LeftOut();
  this->LastStats.attenuationScale = this->Selection.AttenuationScale();
  if (!this->Continue(Stage::Cull) || !this->UpdateOrder(input, mesh, threads))
  {
    return false;
  }

  DecomposeInput& d = this->DecomposeState;
  d.points = this->Transform.Points().data();
  d.pointCount = input.points.count;
  d.cells = input.cells;
  d.scalars = input.scalars;
  d.colours = input.colours;
  d.imageSize = input.imageSize;
  d.cellsCoverPixels = true; // the depth keys culled with this viewport (KeyCulling)
  d.cellList = this->Selection.Selected();
  d.cellListCount = this->Selection.SelectedCount();
  this->SortedSize = this->Order.Count();
  return this->Continue(Stage::Order);
}

bool FramePipeline::UpdateOrder(const FrameInput& input, const MeshKey& mesh, int threads)
{
  // 3. Depth keys, and the near plane's cut. The order consumed the keys it sorted: when the
  // near plane or the order must read them again (the order's method changed, say), they are
  // computed again, and the stages after them with them.
  const ProjectedPoint* points = this->Transform.Points().data();
  if (this->DepthKeys.Consumed() &&
    (!this->NearPlaneCut.Holds(NearPlaneKeyOf(this->DepthKeys.Version())) ||
      !this->Order.Holds(OrderKeyOf(this->DepthKeys.Version(), this->NearPlaneCut.Version(),
        this->Method, this->MaxSubArraySize, this->Mutation, input.ordered))))
  {
    this->DepthKeys.Forget();
  }
  const bool keyed = Timed(this->LastTimes.keys,
    [&]
    {
      const bool computed = this->DepthKeys.Update(
        DepthKeyStageKeyOf(input, this->Transform.Version(), this->Selection.Version()), points,
        input.points.count, input.cells, this->Selection.Selected(),
        this->Selection.SelectedCount(), threads);
      return this->NearPlaneCut.Update(NearPlaneKeyOf(this->DepthKeys.Version()),
               this->DepthKeys.Keys(), points, input.points.count, input.cells, input.scalars,
               input.colours, input.projection, input.perspective, threads) ||
        computed;
    });
  const KeyCounts& counts = this->DepthKeys.Counts();
  this->LastStats.frustumCulled = counts.frustumCulled;
  this->LastStats.pixelCulled = counts.pixelCulled;
  this->LastStats.nearClipped = this->NearPlaneCut.Clipped();
  this->LastStats.nearPieces = this->NearPlaneCut.Pieces().size();
  if (keyed && !this->Continue(Stage::DepthKeys))
  {
    return false;
  }

  // 4. Visibility order, and its inverse for the decomposition.
  OrderStage::Cells cells;
  cells.mesh = mesh;
  cells.points = this->Transform.Version();
  cells.visible = this->Selection.Version();
  cells.perspective = input.perspective;
  cells.whole =
    counts.frustumCulled == 0 && counts.pixelCulled == 0 && this->NearPlaneCut.Clipped() == 0;
  cells.direction = ViewDirection(input.modelView);
  const OrderKey key = OrderKeyOf(this->DepthKeys.Version(), this->NearPlaneCut.Version(),
    this->Method, this->MaxSubArraySize, this->Mutation, input.ordered);
  const bool sorted = Timed(this->LastTimes.order,
    [&]
    {
      return this->Order.Update(
        key, cells, this->Reuse, this->DepthKeys, this->NearPlaneCut, threads);
    });
  if (sorted)
  {
    Timed(this->LastTimes.decompose,
      [&]
      {
        // The decomposition visits the keys' candidates only (DecomposeInput::cellList).
        this->Order.Invert(input.cells.cellCount + this->NearPlaneCut.Pieces().size(), threads,
          this->Selection.Selected(), this->Selection.SelectedCount(), input.cells.cellCount);
        return true;
      });
  }
  this->LastStats.orderReused = !keyed && !sorted;
  this->LastStats.orderFromPrevious = sorted && this->Order.FromPrevious();
  this->LastStats.unordered = !input.ordered;
  this->LastStats.sorted = this->Order.Count();
  return true;
}

bool FramePipeline::Continue(Stage finished)
{
  if (this->Callback && !this->Callback(finished))
  {
    this->WasStopped = true;
    // Whatever was kept from the depth keys on may be incomplete: the next frame redoes it.
    this->ForgetFrom(DepthKeysStage);
    this->SortedSize = 0;
    return false;
  }
  return true;
}

DecompositionKey FramePipeline::WindowKey(
  std::size_t& first, std::size_t& count, const OpaquePixels* hidden)
{
  first = std::min(first, this->SortedSize);
  count = std::min(count, this->SortedSize - first);
  ++this->LastStats.batches;
  return DecompositionKeyOf(
    this->Order.Version(), first, count, this->DecomposeState.imageSize, hidden);
}

DecomposeInput FramePipeline::WindowInput(
  std::size_t first, std::size_t count, std::size_t size, int threads)
{
  DecomposeInput in = this->DecomposeState;
  if (count < this->SortedSize)
  {
    // A batch: the cells of the rank groups it overlaps, not every candidate.
    LargeVector<SortKey>& storage = this->DepthKeys.Consume();
    this->Order.Group(size, in.cells.cellCount, in.cellList, in.cellListCount, storage, threads);
    in.rankedCells = this->Order.CellsOfRanks(first, count, storage, in.rankedCellCount);
  }
  return in;
}

template <typename Buffers>
void FramePipeline::DecomposeWindow(Buffers& buffers, std::size_t first, std::size_t count,
  int threads, const OpaquePixels* hidden, std::size_t& decomposed)
{
  const std::size_t size = count;
  const DecompositionKey key = this->WindowKey(first, count, hidden);
  // The decomposition by rank visits the candidate cells (DecomposeInput::cellList), or a
  // batch's rank groups.
  threads = ThreadsForWork(this->LastStats.cells + count, detail::CellsPerThread, threads);
  const bool computed = Timed(this->LastTimes.decompose,
    [&]
    {
      if (buffers.Holds(key))
      {
        return false;
      }
      buffers.Reserve(std::min(size, this->SortedSize));
      DecomposeInput in = this->WindowInput(first, count, size, threads);
      in.hidden = hidden;
      return buffers.Update(key, in, this->Order.Rank(), this->NearPlaneCut.Pieces(), threads);
    });
  this->LastStats.decompositionReused |= !computed;
  this->LastStats.pixelCulled += buffers.PixelCulled();
  this->LastStats.notDrawable += buffers.NotDrawable();
  this->LastStats.hidden += buffers.Hidden();
  decomposed = count;
}

void FramePipeline::DecomposeBatch(std::size_t first, std::size_t count, int threads)
{
  this->DecomposeWindow(this->Slots, first, count, threads, nullptr, this->BatchCount);
}

void FramePipeline::DecomposeFans(
  std::size_t first, std::size_t count, int threads, const OpaquePixels* hidden)
{
  this->DecomposeWindow(this->FanBuffers, first, count, threads, hidden, this->FanBatchCount);
}

void FramePipeline::LightWindow(std::size_t first, std::size_t count, const Lighting& lighting,
  const float* normals, const Matrix4& modelView, std::vector<LightFactors>& factors, int threads)
{
  const auto start = Clock::now();
  const std::size_t size = count;
  first = std::min(first, this->SortedSize);
  count = std::min(count, this->SortedSize - first);
  factors.assign(count, Unlit());
  double normalMatrix[9];
  if (count == 0 || !normals || !NormalMatrix(modelView, normalMatrix))
  {
    this->LastTimes.light += SecondsSince(start);
    return;
  }
  const DecomposeInput in = this->WindowInput(first, count, size, threads);
  const std::uint32_t* rank = this->Order.Rank();
  const std::vector<NearPiece>& pieces = this->NearPlaneCut.Pieces();
  const std::size_t cellCount = in.cells.cellCount;
  // By rank, as the decomposition (DecomposeTetrahedraByRank): the cells in storage order
  // (of the window's rank groups, for a batch), each lit into its rank's entry, so that
  // their points and normals are read in order.
  const std::size_t listed = in.VisitedCount();
  threads = ThreadsForWork(listed, detail::CellsPerThread, threads);
  detail::DispatchCells(in.cells, in.pointCount,
    [&](const auto& access)
    {
      auto light = [&](std::size_t cell, std::uint32_t r)
      {
        std::int64_t ids[4];
        if (r == NotInOrder || r < first || r - first >= count ||
          !access.TetrahedronPoints(cell, ids))
        {
          return;
        }
        double corners[4][3];
        for (int i = 0; i < 4; ++i)
        {
          const ProjectedPoint& p = in.points[ids[i]];
          corners[i][0] = p.eyeX;
          corners[i][1] = p.eyeY;
          corners[i][2] = p.eyeZ;
        }
        factors[r - first] = LightTetrahedron(lighting, normalMatrix, normals + 3 * cell, corners);
      };
      const auto n = static_cast<std::int64_t>(listed);
      detail::ParallelFor(0, n, threads,
        [&](std::int64_t i)
        {
          std::size_t cell;
          std::uint32_t r;
          in.Visited(static_cast<std::size_t>(i), rank, cell, r);
          light(cell, r);
        });
      // A near-plane piece (id cellCount + j) is lit as its cell.
      for (std::size_t j = 0; j < pieces.size(); ++j)
      {
        light(pieces[j].cell, rank[cellCount + j]);
      }
    });
  this->LastTimes.light += SecondsSince(start);
}

} // namespace mtpt
