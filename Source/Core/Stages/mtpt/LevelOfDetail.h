// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file LevelOfDetail.h
 * @brief Stage 2b of a frame: the cells a moving frame draws when it cannot draw them all
 * in the time the renderer allots, and the rule that splits that time between the cell
 * fraction and the image sample distance (Documentation/level-of-detail.md).
 *
 * The subset is a prefix of an importance order computed once per mesh: the cells sorted
 * along the Morton curve of their centroids, then taken in the van der Corput order of
 * their position on the curve (position p gets importance bitreverse(p)). Any prefix of
 * that order is spread evenly over the mesh: half the cells keep every other cell along
 * the curve, a quarter every fourth, and so on. The backends compensate the opacity of the
 * cells left out by scaling every drawn cell's attenuation by visible / drawn, so that a
 * ray keeps its expected optical depth.
 *
 * The stage keeps a byte a cell, not the 4-byte importance: the deepest level of
 * CellFractionLevel that keeps the cell (ComputeKeptLevels), which selects the same cells as
 * the importance does at every level. Its subset list holds the kept cells only.
 *
 * A fraction of 1 selects nothing: the frame is the full frame, bit for bit.
 */
#ifndef mtpt_LevelOfDetail_h
#define mtpt_LevelOfDetail_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/Stage.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/**
 * The importance of every cell (see the file comment): importance[c] for c in
 * [0, cells.cellCount), distinct values in [0, 2^ImportanceBits(cellCount)). A cell that is
 * not a tetrahedron or names a point outside the mesh gets the centroid (0, 0, 0) of the
 * bounding box's corner; it is never drawn anyway. Thread safety: reentrant; `threads`
 * OpenMP threads (<= 0: all). Determinism: the same values for any thread count.
 */
void ComputeImportance(
  const PointsView& points, const CellsView& cells, std::uint32_t* importance, int threads);

/// Bits of the importance values of a mesh of `cellCount` cells: ceil(log2(cellCount)).
int ImportanceBits(std::size_t cellCount);

/**
 * The importance below which a cell is drawn for a fraction in (0, 1] of a mesh of
 * `cellCount` cells: ceil(fraction * 2^bits), so fraction 1 keeps every cell. Pure function.
 */
std::uint64_t ImportanceThreshold(double fraction, std::size_t cellCount);

/**
 * The fractions a moving frame draws: 2^(-k/4) for k = 0, 1, 2, ..., so that the subset,
 * and what the stages can reuse with it, changes only when the wanted fraction crosses a
 * level. Returns the largest level at or below `fraction` and at least the level at or
 * below `minimum`; 1 for a fraction >= 1 or NaN. Pure function.
 */
double CellFractionLevel(double fraction, double minimum);

/// The deepest level a cell's byte records (ComputeKeptLevels): fraction 2^(-255/4).
constexpr int DeepestDetailLevel = 255;

/// The level k of a fraction 2^(-k/4) that CellFractionLevel gave; 0 for 1 or more (and NaN).
int DetailLevelOf(double fraction);

/// The fraction of level k, 2^(-k/4), the very value CellFractionLevel gives for it.
double DetailLevelFraction(int level);

/**
 * For every cell, the deepest level (at most DeepestDetailLevel) whose fraction keeps it:
 * levels[c] = the largest k with importance[c] < ImportanceThreshold(DetailLevelFraction(k),
 * cellCount), ComputeImportance's importance. So levels[c] >= k exactly when the importance
 * keeps cell c at level k: the same subsets from a byte a cell. Thread safety and determinism
 * as ComputeImportance's.
 */
void ComputeKeptLevels(
  const PointsView& points, const CellsView& cells, std::uint8_t* levels, int threads);

/// What the subset depends on: CellSelectionStage's key.
struct CellSelectionKey
{
  MeshKey mesh;
  std::uint64_t visible = 0; ///< CullingStage::Version()
  int level = 0;             ///< DetailLevelOf the cell fraction; 0: every cell
  bool operator==(const CellSelectionKey& o) const
  {
    return mesh == o.mesh && visible == o.visible && level == o.level;
  }
};

/**
 * Stage 2b as a stage of FramePipeline (Stage.h): the cells of the visible list (Culling.h)
 * that the key's level keeps, in ascending order. The cells' kept levels are kept until
 * the mesh changes; the subset until the mesh, the visible list or the level change. With
 * every cell kept it passes the visible list through, computing nothing.
 */
class CellSelectionStage : public StageOf<CellSelectionKey>
{
public:
  /**
   * Brings the subset up to date with `key`, from the visible list `visible` (ascending;
   * null: every cell) of `visibleCount` cells. True when it computed anything.
   */
  bool Update(const Key& key, const PointsView& points, const CellsView& cells,
    const std::uint32_t* visible, std::size_t visibleCount, int threads);

  /**
   * Computes the kept levels of the mesh `key`'s cells unless they are kept: what a subset
   * of it needs, once per mesh. Update calls it too; an application calls it ahead of a frame to
   * keep the work out of the frame's time. True when it computed.
   */
  bool PrepareImportance(
    const MeshKey& key, const PointsView& points, const CellsView& cells, int threads);

  /// The cells to draw in ascending order (null: every cell, as the visible list's null).
  const std::uint32_t* Selected() const { return this->Passed ? this->Visible : this->List.data(); }
  std::size_t SelectedCount() const { return this->Passed ? this->VisibleCount : this->Count; }
  /// Visible cells left out of this frame.
  std::size_t LeftOut() const { return this->VisibleCount - this->SelectedCount(); }
  /// The compensation the backends apply to every attenuation: visible / drawn cells, 1 when
  /// none is left out (FrameStats::attenuationScale).
  double AttenuationScale() const
  {
    return this->LeftOut() > 0 ? static_cast<double>(this->VisibleCount) /
        static_cast<double>(this->SelectedCount() > 0 ? this->SelectedCount() : 1)
                               : 1.0;
  }
  /// Whether `level` (DetailLevelOf) keeps every cell of a mesh of `cellCount`.
  static bool KeepsEveryCell(int level, std::size_t cellCount)
  {
    return level <= 0 ||
      ImportanceThreshold(DetailLevelFraction(level), cellCount) >=
      (std::uint64_t{ 1 } << ImportanceBits(cellCount));
  }
  /// The most cells a subset that leaves some out holds: those its largest fraction,
  /// 2^(-1/4), keeps of a mesh of `cellCount` (the list's bound, FramePipeline::BytesNeeded).
  static std::size_t LargestSubset(std::size_t cellCount)
  {
    return static_cast<std::size_t>(
      std::min<std::uint64_t>(cellCount, ImportanceThreshold(DetailLevelFraction(1), cellCount)));
  }
  void Forget() override;
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  StageRecord<MeshKey> LevelsRecord;
  LargeVector<std::uint8_t> Levels; ///< ComputeKeptLevels, a byte a cell
  LargeVector<std::uint32_t> List;  ///< the subset: Count cells
  const std::uint32_t* Visible = nullptr;
  std::size_t VisibleCount = 0, Count = 0;
  bool Passed = true;
};

/// The level of detail of one frame.
struct Detail
{
  double cellFraction = 1;   ///< CellFractionLevel of the visible cells drawn
  double sampleDistance = 1; ///< image sample distance (ImageSampling.h)
};

/// What the rule may change and within which bounds.
struct DetailLimits
{
  bool adjustFraction = true, adjustDistance = true;
  double minimumFraction = 0.05;
  double minimumDistance = 1, maximumDistance = 10;
  /// The distance the rule reaches before it lowers the fraction: a coarser image costs
  /// far less error than fewer cells (Documentation/level-of-detail.md, "The budget rule").
  double preferredDistance = 4;
};

/// A frame as the rule learns from it.
struct MeasuredFrame
{
  Detail detail;
  double seconds = 0; ///< the whole frame; 0: never timed
  /// The CPU stages that follow the cells drawn (depth keys, order, decomposition).
  double cellSeconds = 0;
  /// Work that follows the cells drawn and the samples composited (the CPU compositor's
  /// binning and rasterization); negative when it is not measured apart (OpenGL's drawing
  /// is asynchronous): it is then the rest of the frame less `viewportSeconds`.
  double sampleSeconds = -1;
  /// With `sampleSeconds` unmeasured: work that follows the viewport alone (read-back,
  /// magnification, write-back).
  double viewportSeconds = 0;
};

/**
 * The seconds the volume may take of the time the renderer allots it, `allottedSeconds`,
 * when the rest of each frame (the window's own work: clearing, resolving multisampled
 * buffers, presenting; other props) takes time too: VTK allots the whole frame's time to
 * the props. The rest is estimated from `intervalSeconds`, the time from the start of the
 * last frame to the start of this one, less `lastSeconds`, the volume's part of the last
 * frame; it is trusted only when frames follow each other (an interval of at most twice
 * the allotted time plus the volume's), as they do while the user drags, and takes at most
 * half the allotted time. Otherwise the volume gets the whole allotment. Pure function.
 */
double VolumeBudget(double allottedSeconds, double intervalSeconds, double lastSeconds);

/**
 * The level of detail of the next frame given the last one and the seconds the renderer
 * allots. Model: a frame takes Z + f * (C + R / d^2) at cell fraction f and image sample
 * distance d, with C = cellSeconds / f and R = sampleSeconds * d^2 / f measured on the last
 * frame, and Z the rest of it: the per-cell stages scale with the cells, the compositing
 * with the cells and the samples, everything else (the transform of every point, the
 * selection, the viewport's read-back and write-back) is fixed. Without sampleSeconds, Z is
 * viewportSeconds and R the rest. The compositing shrinks less than 1 / d^2 in truth (the
 * set-up of every triangle), so the model never overshoots: each frame closes part of the
 * gap from the same side. The variable part gets the allotment less Z, and at least 40% of
 * the allotment: where the fixed work nearly fills the allotment, the frame runs over it
 * rather than dropping nearly every cell. Among the details the model says fit, it takes
 * the first of: every cell at the smallest distance; every cell at a distance up to the
 * preferred one; the preferred distance and the largest fraction level; the smallest
 * fraction and the smallest distance that fits, up to the largest. A frame never timed, or
 * an allotment that is not a positive finite number, gives every cell at the smallest
 * distance, as does an allotment the full frame fits: a still frame is always the full
 * image. Settings that the limits do not let it adjust keep the value in `fixed`. Pure
 * function.
 */
Detail ChooseDetail(const MeasuredFrame& last, double allottedSeconds, const DetailLimits& limits,
  const Detail& fixed);

} // namespace mtpt

#endif
