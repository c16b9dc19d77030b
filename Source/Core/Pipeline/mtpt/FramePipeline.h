// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FramePipeline.h
 * @brief The CPU stages of one frame in sequence: 1 transform (Transform.h), 2 opacity
 * culling (Culling.h), 3 depth keys (DepthKeys.h) and 3b the near plane's cut
 * (NearPlane.h), 4 visibility order (VisibilityOrder.h), 5 decomposition (Decompose.h); 2b,
 * in moving frames, the level of detail's subset of the cells (LevelOfDetail.h).
 * Each stage is an object that owns its result, the key it was computed from and a version
 * (Stage.h; Documentation/architecture.md, "The stages of a frame"); this class only runs
 * them in order, passing each the versions of the results it reads, times them and gathers
 * what they culled and reused. Stage 6, drawing, belongs to the backends.
 *
 * Work follows what the scene needs (Documentation/algorithm.md, "Culling and reuse"):
 * - cells crossing the near plane are cut by it and their visible part drawn as extra
 *   tetrahedra with their own keys (NearPlane.h); cells wholly in front of it are dropped;
 * - culling before the sort: cells the opacity transfer function makes fully transparent
 *   (Culling.h; recomputed only when the data or the opacity table change), and, while the
 *   keys are computed, cells entirely outside the view volume and cells whose projection
 *   covers no pixel centre of the viewport (DepthKeys.h, detail/PixelCoverage.h); the
 *   pieces of cells cut by the near plane are tested for pixel coverage by the same rule
 *   when they are decomposed (Decompose.h);
 * - reuse (SetReuse): an unchanged view, model matrix and data skip every stage; a change
 *   of colour only (the same opacity-visible cells) skips every stage too; a change of
 *   the opacity table redoes culling, keys, order and decomposition but not the
 *   transform; a small rotation sorts this frame's keys from the previous order
 *   (SortNearlySorted) when the same cells are drawn, and falls back to the full sort when
 *   that would cost more;
 * - bounded memory: the decomposition runs in windows of the order (DecomposeBatch), so the
 *   vertex and index buffers hold one batch instead of the whole mesh.
 * Culling and reuse never change the image: every culled cell would produce no fragment,
 * and every reused result equals what the stage would compute again.
 */
#ifndef mtpt_FramePipeline_h
#define mtpt_FramePipeline_h

#include "mtpt/Culling.h"
#include "mtpt/Decompose.h"
#include "mtpt/DepthKeys.h"
#include "mtpt/FramePlan.h"
#include "mtpt/LargeBuffer.h"
#include "mtpt/LevelOfDetail.h"
#include "mtpt/Lighting.h"
#include "mtpt/NearPlane.h"
#include "mtpt/Transform.h"
#include "mtpt/VisibilityOrder.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <type_traits>
#include <vector>

namespace mtpt
{

/// Wall-clock seconds of each CPU stage of the last frame. `cull` is the opacity culling
/// (cell scalar ranges and the visible-cell list); `select` the level of detail's subset
/// (LevelOfDetail.h); `decompose` includes inverting the order and sums over the frame's
/// batches, as `light` (shading: LightWindow) does.
struct StageTimes
{
  double transform = 0, cull = 0, select = 0, keys = 0, order = 0, decompose = 0, light = 0;
  double Total() const { return transform + cull + select + keys + order + decompose + light; }
};

/// What the last frame did: cell counts at each culling step and what it reused.
struct FrameStats
{
  std::size_t cells = 0;         ///< cells in the mesh
  std::size_t opacityCulled = 0; ///< transparent over their whole scalar range
  std::size_t leftOut = 0;       ///< visible, left out by the level of detail
  /// What the backends multiply every attenuation by: visible / drawn cells (1 without a
  /// level of detail), so that a ray keeps its expected optical depth (LevelOfDetail.h).
  double attenuationScale = 1;
  std::size_t frustumCulled = 0; ///< entirely outside the view volume
  std::size_t sorted = 0;        ///< cells sorted and given a slot
  std::size_t pixelCulled = 0;   ///< covering no pixel centre (before the sort; pieces after)
  std::size_t notDrawable = 0;   ///< slots that cannot be drawn (bad cells, behind the eye)
  /// Sorted, then left undecomposed: every pixel they cover was opaque already (batches front
  /// to back, DrawBatches).
  std::size_t hidden = 0;
  std::size_t nearClipped = 0;      ///< cells cut by the near plane (NearPlane.h)
  std::size_t nearPieces = 0;       ///< tetrahedra drawn in their place (in `sorted`)
  std::size_t batches = 0;          ///< decomposition windows run this frame
  bool transformReused = false;     ///< the projected points of the previous frame served
  bool orderReused = false;         ///< no key was computed and nothing sorted
  bool orderFromPrevious = false;   ///< sorted from the previous order (nearly sorted)
  bool unordered = false;           ///< kept in cell order, not sorted (FrameInput::ordered)
  bool decompositionReused = false; ///< the buffers of the previous frame served
};

/// What a frame needs to know about the mesh and the view.
struct FrameInput
{
  PointsView points;
  CellsView cells;
  ScalarsView scalars;
  /// Dependent components (DecomposeInput::colours): RGBA per point or cell, as `scalars`
  /// are associated, and `scalars` the attenuations. Then cells whose attenuation is 0 at
  /// every corner are culled (with `opacity.table` set or not: it is not read). Null: the
  /// scalars are looked up in the transfer functions.
  const float* colours = nullptr;
  Matrix4 modelView = IdentityMatrix();  ///< view * model
  Matrix4 projection = IdentityMatrix(); ///< eye to clip coordinates
  bool perspective = false;
  /// The composited image's size; when set, cells covering no pixel centre of it are culled
  /// (see DecomposeInput). Leave it empty for multisampled targets.
  ImageSize imageSize;
  /// Opacity culling: when `opacity.table` is set, cells whose opacity is zero over their
  /// scalar range under this table are skipped (exact for both backends, Culling.h).
  TransferFunctionTable opacity;
  /// Skip cells entirely outside the view volume before sorting.
  bool cullFrustum = true;
  /// The level of detail of a moving frame: the fraction of the visible cells drawn, a
  /// CellFractionLevel (LevelOfDetail.h; another fraction takes its nearest level,
  /// DetailLevelOf). 1: every cell, the full frame.
  double cellFraction = 1;
  /// False when the blend mode reduces fragments in any order (BlendMode): the cells are
  /// culled as always but kept in cell order, and nothing is sorted.
  bool ordered = true;
  /**
   * Shading (Lighting.h; FramePlan::lit): each cell lit by `lighting` with its normal of
   * `normals` (CellNormals: 3 floats per cell, model coordinates; `normalsVersion` changes
   * whenever they do), in the batches of DrawBatches. False: unlit.
   */
  bool lit = false;
  Lighting lighting;
  const float* normals = nullptr;
  std::uint64_t normalsVersion = 0;
  /// Change counters, read only with reuse on (FramePipeline::SetReuse): change
  /// `dataVersion` whenever the content of the points, cells or scalars changes,
  /// `opacityVersion` whenever the content of the opacity table changes, and
  /// `placementVersion` whenever a part's model matrix (MeshPart::model) changes.
  std::uint64_t dataVersion = 0, opacityVersion = 0, placementVersion = 0;
};

/**
 * Sets what `plan` decides of `input`: the culling (the opacity table is left out when the
 * plan does not cull by it; the composited image's size only where cells covering no pixel
 * centre may be culled), the cell fraction, the order and the lighting. The data, matrices,
 * table and lights stay the caller's.
 */
void ApplyPlan(const FramePlan& plan, FrameInput& input);

/**
 * Called after each stage of Prepare with the stage just finished; returning false stops
 * the frame there (Prepare then returns false and nothing is sorted). The mapper reports
 * progress and polls the render window's abort flag with it.
 */
using StageCallback = std::function<bool(Stage)>;

/// The lighting of a frame (FrameInput::lit and what it reads), as Prepare took it.
struct FrameLighting
{
  bool lit = false;
  Lighting lighting;
  const float* normals = nullptr;
  std::uint64_t normalsVersion = 0;
  Matrix4 modelView = IdentityMatrix();
};

/// How FramePipeline::DrawBatches ended.
struct BatchesDrawn
{
  int batches = 0;      ///< batches decomposed and handed to the drawer
  bool stopped = false; ///< the batch callback stopped the frame (what was drawn stays)
  bool failed = false;  ///< the drawer failed on a batch; no later batch was drawn
};

/**
 * One window of the order, decomposed into the plan's target and lit where the plan is,
 * for a backend to draw (FramePipeline::DrawBatches). Valid until the next batch.
 */
struct Batch
{
  std::size_t first = 0; ///< the rank of its first cell
  std::size_t count = 0; ///< its fans or slots
  /// BatchTarget::Fans: `count` fans. Slots: `count` slots of VerticesPerTetrahedron
  /// vertices and IndicesPerTetrahedron indices each.
  const Fan* fans = nullptr;
  const TetVertex* vertices = nullptr;
  const std::uint32_t* indices = nullptr;
  /// Lit frames: each fan's or slot's lighting (Lighting.h); null when unlit.
  const LightFactors* lights = nullptr;
  /// Each fan's or slot's class (`count` of them): a reader skips those not Drawn
  /// (Records.h), a hidden fan being left unwritten.
  const ProjectionClass* classes = nullptr;
  /// Change whenever the buffers' (the lights') content changes: a consumer that copied
  /// them (an OpenGL upload) is current exactly when it holds these.
  std::uint64_t version = 0, lightsVersion = 0;
};

/// Draws one batch; false when drawing failed (no later batch is drawn).
using BatchDrawer = std::function<bool(const Batch&)>;

/**
 * Called after each batch but the last with the fraction of the order drawn so far;
 * returning false stops the frame there. The mapper reports progress and polls the render
 * window's abort flag with it.
 */
using BatchCallback = std::function<bool(double)>;

/// What the memory policy found for a frame (CheckMemory).
struct MemoryVerdict
{
  bool fits = true;
  std::size_t bytes = 0; ///< FramePipeline::BytesNeeded of the frame
  std::size_t limit = 0; ///< what it was compared with
};

/**
 * The memory policy: a frame of `need` fits when FramePipeline::BytesNeeded(need) is at most
 * `limit`, or, with `limit` 0, at most the memory `available()` returns (asked only then)
 * plus the `held` bytes the pipeline's buffers take already (they are reused). Thread-safe
 * when `available` is.
 */
MemoryVerdict CheckMemory(const MemoryNeed& need, std::size_t limit, std::size_t held,
  const std::function<std::size_t()>& available);

/**
 * Runs the CPU stages and keeps their results until the next frame. Buffers grow to the
 * largest mesh (or batch) seen and are reused, so steady-state frames allocate nothing.
 * Thread safety: one object per thread of control; the stages use OpenMP inside.
 */
class FramePipeline
{
public:
  FramePipeline() = default;

  void SetOrderMethod(OrderMethod method, std::size_t maxSubArraySize = DefaultMaxSubArraySize)
  {
    this->Method = method;
    this->MaxSubArraySize = maxSubArraySize;
  }
  OrderMethod GetOrderMethod() const { return this->Method; }

  /**
   * Reuse results across frames (default off). With reuse on, the caller promises that the
   * arrays behind FrameInput change content only together with a change of
   * FrameInput::dataVersion (or of their address or size), and the opacity table only
   * together with FrameInput::opacityVersion.
   */
  void SetReuse(bool reuse) { this->Reuse = reuse; }
  bool GetReuse() const { return this->Reuse; }

  /// Testing only: see OrderMutation. Takes effect at the next sort.
  void SetOrderMutationForTesting(OrderMutation mutation) { this->Mutation = mutation; }

  /// Called after each stage of Prepare (see StageCallback); empty: none.
  void SetStageCallback(StageCallback callback) { this->Callback = std::move(callback); }
  /// Called after each batch of DrawBatches but the last (see BatchCallback); empty: none.
  void SetBatchCallback(BatchCallback callback) { this->AfterBatch = std::move(callback); }

  /**
   * Stages 1 to 4 and the order's inverse: transform, culling, keys (with the near plane),
   * order. Returns false (and sorts nothing) if the mesh is too large for 32-bit indices or
   * the stage callback stopped the frame (Stopped() tells which). Then decompose with
   * DecomposeBatch, or use Run for the whole order at once. Where an allocation fails
   * (std::bad_alloc) it goes on to the caller, and every stage has forgotten its result:
   * the next frame computes all of them anew. So do PrepareLevelOfDetail and DrawBatches.
   */
  bool Prepare(const FrameInput& input, int threads);
  /**
   * The analysis a frame of `input` with a cell fraction below 1 needs once per mesh (the
   * level of detail's importance order, LevelOfDetail.h), done now so that it is not part
   * of the frame's time; nothing when it is done or the fraction is 1.
   */
  void PrepareLevelOfDetail(const FrameInput& input, int threads);
  /// Whether the last Prepare was stopped by the stage callback.
  bool Stopped() const { return this->WasStopped; }

  /**
   * Stage 5: decomposes the order's window [first, first + count) (clamped to
   * SortedCount()) into Vertices() and Indices(), slot 0 being rank `first`. Call after
   * Prepare, for the same input, in any order of windows.
   */
  void DecomposeBatch(std::size_t first, std::size_t count, int threads);

  /**
   * As DecomposeBatch, into fans (Decompose.h), the CPU compositor's input: fan 0 is rank
   * `first`; culled and undrawable cells have count 0. With `hidden` (DecomposeInput::hidden)
   * the cells behind its opaque pixels are left unwritten, their class Hidden (FanClasses).
   * Kept apart from the slot buffers: a frame may use either, or both.
   */
  void DecomposeFans(
    std::size_t first, std::size_t count, int threads, const OpaquePixels* hidden = nullptr);

  /**
   * Shading (Lighting.h): the factors of the order's window [first, first + count) (clamped
   * to SortedCount()), entry k for rank first + k, into `factors`: each cell lit by
   * LightCell at its centroid with its normal of `normals` (CellNormals, 3 floats per cell,
   * model coordinates) taken to eye coordinates by `modelView`; a near-plane piece as its
   * cell. Call after Prepare, for the same input; the slots and fans of that window (entry k
   * for slot or fan k) then need no other change.
   */
  void LightWindow(std::size_t first, std::size_t count, const Lighting& lighting,
    const float* normals, const Matrix4& modelView, std::vector<LightFactors>& factors,
    int threads);

  /// Prepare, then decompose the whole order in one batch.
  bool Run(const FrameInput& input, int threads);

  /**
   * Stage 5 for the whole frame: after Prepare, the order in windows of `plan.batchSize`
   * cells (all at once for 0), back to front, or front to back with `plan.frontToBack`; each
   * decomposed into the plan's target, lit (FrameInput::lit), then handed to `draw`. Front
   * to back, `hidden` (null: none) holds the pixels the batches drawn so far made opaque,
   * as `draw` leaves them: the cells of later batches behind them are not decomposed
   * (DecomposeFans). Between batches the batch callback may stop the frame. The backends
   * draw what this gives them; they decompose nothing themselves.
   * Deterministic: the batches' content is the same for any thread count.
   */
  BatchesDrawn DrawBatches(
    const FramePlan& plan, const BatchDrawer& draw, const OpaquePixels* hidden = nullptr);

  const StageTimes& Times() const { return LastTimes; }
  const FrameStats& Stats() const { return LastStats; }
  /// Cells in the order (after culling): the slots of the whole frame.
  std::size_t SortedCount() const { return SortedSize; }
  /// Slots in the buffers: the last batch decomposed.
  std::size_t TetrahedronCount() const { return BatchCount; }
  const LargeVector<ProjectedPoint>& Points() const { return this->Transform.Points(); }
  /// The order: SortedCount() keys, back to front.
  const LargeVector<SortKey>& Keys() const { return this->Order.Keys(); }
  const LargeVector<TetVertex>& Vertices() const { return this->Slots.Vertices(); }
  const LargeVector<std::uint32_t>& Indices() const { return this->Slots.Indices(); }

  /// Fans of the last DecomposeFans, and their classes (FanCount() of each: a fan whose class
  /// is not Drawn holds nothing to draw, or was not written).
  const LargeVector<Fan>& Fans() const { return this->FanBuffers.Fans(); }
  const ProjectionClass* FanClasses() const { return this->FanBuffers.Classes(); }
  std::size_t FanCount() const { return FanBatchCount; }
  /// Changes whenever the fans' content changes (as BufferVersion for the slots).
  std::uint64_t FanVersion() const { return this->FanBuffers.Version(); }

  /**
   * Changes whenever the buffers' content changes: a new decomposition, another batch, or
   * Release. A consumer that copied the buffers (an OpenGL upload) is current exactly when
   * it holds this version; never 0 once a batch has been decomposed.
   */
  std::uint64_t BufferVersion() const { return this->Slots.Version(); }
  /// Changes whenever the visibility order (or the set of cells in it) changes.
  std::uint64_t OrderVersionNumber() const { return this->Order.Version(); }
  /// The lighting of the last Prepare.
  const FrameLighting& LightingOfFrame() const { return this->FrameShading; }
  /// The view's projected points and the inputs of the decomposition of the last Prepare.
  const DecomposeInput& Decomposition() const { return this->DecomposeState; }

  /// Bytes held by the pipeline's buffers (capacity, not size).
  std::size_t MemoryBytes() const;
  /**
   * An upper bound of MemoryBytes() over frames of one mesh (`need`), computed before any of
   * them: what a caller compares with the memory it has before the buffers are allocated.
   */
  static std::size_t BytesNeeded(const MemoryNeed& need);
  /// Frees every buffer and forgets what could be reused.
  void Release();

  /// Largest tetrahedron count whose fixed-stride buffers fit 32-bit indices.
  static std::size_t MaxTetrahedra() { return MaxFrameTetrahedra; }

  /// See OrderStage::NearlySortedMaxAngle.
  static constexpr double NearlySortedMaxAngle = OrderStage::NearlySortedMaxAngle;

private:
  FramePipeline(const FramePipeline&) = delete;
  void operator=(const FramePipeline&) = delete;

  /// body()'s result; when it throws, every stage forgets its result first (a failure
  /// partway may leave buffers half written), and the exception goes on.
  template <typename Body>
  auto ForgettingOnFailure(Body&& body);
  /// Prepare, PrepareLevelOfDetail and DrawBatches inside ForgettingOnFailure.
  bool PrepareStages(const FrameInput& input, int threads);
  void PrepareImportance(const FrameInput& input, int threads);
  BatchesDrawn DrawBatchesInOrder(
    const FramePlan& plan, const BatchDrawer& draw, const OpaquePixels* hidden);
  /// Runs `stage`, adds its seconds to `seconds` when it computed, and returns whether it did.
  template <typename Body>
  static bool Timed(double& seconds, Body&& stage);
  bool Continue(Stage finished);
  /// Stages 3 and 4 (keys, near plane, order); false when the callback stopped the frame.
  bool UpdateOrder(const FrameInput& input, const MeshKey& mesh, int threads);
  DecompositionKey WindowKey(std::size_t& first, std::size_t& count, const OpaquePixels* hidden);
  /**
   * The decomposition's input for the window [first, first + count) of the order: for a
   * window smaller than the order, the cells of its rank groups (OrderStage::Group). `size`
   * is the size asked for (at least `count`: the last window of the order may be shorter),
   * the length of the groups when the order is grouped now: every window of a frame then
   * overlaps one group, whichever window comes first.
   */
  DecomposeInput WindowInput(std::size_t first, std::size_t count, std::size_t size, int threads);
  /// DecomposeBatch and DecomposeFans: the window into `buffers` (Slots or FanBuffers), its
  /// size into `decomposed`.
  template <typename Buffers>
  void DecomposeWindow(Buffers& buffers, std::size_t first, std::size_t count, int threads,
    const OpaquePixels* hidden, std::size_t& decomposed);
  /// The stages in the order a frame runs them; ForgetFrom(k) forgets the results of stages
  /// k and later.
  static constexpr std::size_t StageCount = 8;
  static constexpr std::size_t DepthKeysStage = 3; ///< after transform, culling, selection
  template <typename Self>
  static auto StagesOf(Self& self)
  {
    using Pointer = std::conditional_t<std::is_const_v<Self>, const StageBase*, StageBase*>;
    return std::array<Pointer, StageCount>{ &self.Transform, &self.Culling, &self.Selection,
      &self.DepthKeys, &self.NearPlaneCut, &self.Order, &self.Slots, &self.FanBuffers };
  }
  void ForgetFrom(std::size_t first);

  // The stages, in the order they run (Documentation/architecture.md, "The stages").
  TransformStage Transform;
  CullingStage Culling;
  CellSelectionStage Selection;
  DepthKeyStage DepthKeys;
  NearPlaneStage NearPlaneCut;
  OrderStage Order;
  SlotStage Slots;
  FanStage FanBuffers;

  OrderMethod Method = OrderMethod::RadixSort;
  std::size_t MaxSubArraySize = DefaultMaxSubArraySize;
  OrderMutation Mutation = OrderMutation::None;
  bool Reuse = false;
  StageCallback Callback;
  BatchCallback AfterBatch;

  // The frame being prepared.
  DecomposeInput DecomposeState;
  FrameLighting FrameShading;
  /// A lit batch's lighting (DrawBatches), and what it was computed from: kept while the
  /// batch's buffers, the lights, the normals and the view stay the same. A window's
  /// factors, left out of MemoryBytes as the caller's normals are.
  struct LightKey
  {
    BatchTarget target = BatchTarget::Fans;
    std::uint64_t buffers = 0; ///< the target's buffer version
    Lighting lighting;
    std::uint64_t normals = 0;
    Matrix4 modelView = IdentityMatrix();
    bool operator==(const LightKey& o) const
    {
      return target == o.target && buffers == o.buffers && lighting == o.lighting &&
        normals == o.normals && modelView == o.modelView;
    }
  };
  /// The lighting of the batch [first, first + count) just decomposed into `target`.
  const LightFactors* LightBatch(
    BatchTarget target, std::size_t first, std::size_t count, int threads);
  StageRecord<LightKey> LightsRecord;
  std::vector<LightFactors> Lights;
  std::size_t SortedSize = 0, BatchCount = 0, FanBatchCount = 0;
  bool WasStopped = false;
  StageTimes LastTimes;
  FrameStats LastStats;
};

} // namespace mtpt

#endif
