// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Culling.h
 * @brief Stage 2 of a frame: the cells a frame can skip before it sorts, those the opacity transfer
 * function makes fully transparent, so that per-frame work follows what the scene shows, not the
 * mesh size (Documentation/algorithm.md, "Culling and reuse").
 *
 * Exactness: both backends shade a fragment from transfer-function values looked up at
 * scalars interpolated inside its cell, so they lie in the cell's scalar range [min, max].
 * A look-up reads the two table entries around its scalar (TransferFunctionTable). If every
 * entry that a scalar in [min, max] can read (with one entry of margin on each side for
 * rounding) has opacity 0, every fragment of the cell has opacity 0 and adds nothing to
 * the image: culling it changes no pixel.
 */
#ifndef mtpt_Culling_h
#define mtpt_Culling_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/Stage.h"
#include "mtpt/TransferFunctionTable.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/**
 * The scalar range of every cell: ranges[2c] = minimum and ranges[2c + 1] = maximum of its
 * four point scalars (its own value for cell scalars). NaN for a cell that is not a
 * tetrahedron, names a point id outside [0, pointCount), or has a non-finite scalar: such a
 * cell is never drawn. Without scalars (null values) every range is [0, 0].
 * Thread safety: reentrant; `threads` OpenMP threads (<= 0: all).
 */
void ComputeCellScalarRanges(const CellsView& cells, std::size_t pointCount,
  const ScalarsView& scalars, float* ranges, int threads);

/**
 * Which scalar intervals an opacity transfer function leaves fully transparent, from the
 * table both backends shade with (see the file comment for why the test is exact).
 */
class OpacityCulling
{
public:
  /// Reads the opacity channel of `table` (copied: the table may change afterwards).
  void SetTable(const TransferFunctionTable& table);

  /**
   * Dependent components: the scalars are the attenuations themselves (FrameInput::colours),
   * interpolated linearly inside a cell and never negative, so a cell is visible exactly when
   * its largest is above 0. Replaces the table until the next SetTable.
   */
  void SetAttenuations();

  /// True if a scalar in [low, high] can read a non-zero opacity. False for NaN bounds.
  bool Visible(float low, float high) const;

  /**
   * Writes the ids of the cells with a visible range (ComputeCellScalarRanges) to `cells`
   * in ascending order and returns their number. `cells` needs cellCount entries.
   * Determinism: identical for any thread count.
   */
  std::size_t SelectVisibleCells(
    const float* ranges, std::size_t cellCount, std::uint32_t* cells, int threads) const;

  /// The same, from the mesh's scalars: each cell's range found on the way, none stored.
  std::size_t SelectVisibleCells(const CellsView& cells, std::size_t pointCount,
    const ScalarsView& scalars, std::uint32_t* list, int threads) const;

  /**
   * Whether SelectVisibleCells would write exactly the `count` ascending ids of `list`,
   * found by reading them, not by writing a second list.
   */
  bool SelectsExactly(const CellsView& cells, std::size_t pointCount, const ScalarsView& scalars,
    const std::uint32_t* list, std::size_t count, int threads) const;

private:
  std::vector<std::uint32_t> NonZeroBefore; ///< entries before i with opacity != 0
  int Size = 0;
  bool Attenuations = false; ///< SetAttenuations: visible when the range's top is above 0
  float Low = 0, Scale = 0;
};

/// What the culling culls by.
enum class CullingMode
{
  None,        ///< every cell is a candidate
  Table,       ///< by the opacity table (OpacityCulling::SetTable)
  Attenuations ///< the scalars are attenuations (OpacityCulling::SetAttenuations)
};

/// The opacity table as the culling's key sees it (CullingMode::Table only; zero otherwise).
struct OpacityTableKey
{
  const float* table = nullptr;
  int size = 0;
  double low = 0, high = 0;
  std::uint64_t version = 0; ///< FrameInput::opacityVersion
  bool operator==(const OpacityTableKey& o) const
  {
    return table == o.table && size == o.size && low == o.low && high == o.high &&
      version == o.version;
  }
};

/// What the visible list depends on: CullingStage's key.
struct CullingKey
{
  MeshKey mesh;
  CullingMode mode = CullingMode::None;
  OpacityTableKey table;
  bool operator==(const CullingKey& o) const
  {
    return mesh == o.mesh && mode == o.mode && table == o.table;
  }
};

/**
 * Stage 2 as a stage of FramePipeline (Stage.h): the cells left after opacity culling,
 * kept until the data, the culling mode or the opacity table change. A new table that leaves the
 * same cells visible (a colour change) keeps the version, so the later stages keep their results.
 */
class CullingStage : public StageOf<CullingKey>
{
public:
  /// Brings the visible list up to date with `key`; true when it computed anything.
  bool Update(const Key& key, const CellsView& cells, std::size_t pointCount,
    const ScalarsView& scalars, const TransferFunctionTable& table, int threads);

  /// The visible cells in ascending order, or null when nothing is culled (CullingMode::None).
  const std::uint32_t* Visible() const
  {
    return this->Record.Inputs().mode == CullingMode::None ? nullptr : this->List.data();
  }
  /// How many cells Visible() lists (every cell of the mesh without culling).
  std::size_t VisibleCount() const;
  /// Cells culled as transparent.
  std::size_t Culled() const { return this->Record.Inputs().mesh.cellCount - this->VisibleCount(); }
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  LargeVector<std::uint32_t> List;
  OpacityCulling Opacity;
};

} // namespace mtpt

#endif
