// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Decompose.h
 * @brief Stage 5 of a frame: classify each tetrahedron's projection and decompose it into
 * exactly 4 triangles, written at a fixed stride (the paper's Algorithm 2;
 * Documentation/algorithm.md, "Classification and the thick vertex" and "Decomposition at a
 * fixed stride").
 *
 * Conventions (see also MeshView.h):
 * - Slot k (the k-th tetrahedron in visibility order) owns vertices [5k, 5k+5) and
 *   indices [12k, 12k+12): 4 triangles, no locks, identical for any thread count.
 *   Local vertices 0..3 are the cell's points in its own order, local vertex 4 the thick
 *   vertex of a quadrilateral projection. A triangle projection puts the thick vertex in
 *   the slot of the inner point, pads its 4th triangle as degenerate (all three indices on
 *   the thick vertex) and leaves vertex 4 as an unused copy of the thick vertex.
 * - A tetrahedron that cannot be drawn (not a tetrahedron, an id out of range, a point at
 *   or behind the eye plane, non-finite coordinates or scalars, zero projected area)
 *   writes a fully degenerate slot: 5 zero vertices and 12 indices equal to 5k. Nothing
 *   stale remains.
 * - Triangle winding is not meaningful (there is no culling); the 3 or 4 triangles of one
 *   tetrahedron never overlap, so their order inside a slot does not matter.
 * - The vertex record is 6 floats: NDC position, the scalar at the front and at the back of
 *   the ray segment through the tetrahedron at that vertex, and the segment's length in
 *   eye space. On the projection's silhouette front = back and the length is 0; only the
 *   thick vertex has a non-zero length. Shading classifies the scalars at draw time, so the
 *   same record serves VTK-compatible shading (colour and attenuation of the vertex
 *   scalars) and pre-integrated shading (front scalar, back scalar, length).
 */
#ifndef mtpt_Decompose_h
#define mtpt_Decompose_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/NearPlane.h"
#include "mtpt/OpaquePixels.h"
#include "mtpt/Records.h"
#include "mtpt/Stage.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace mtpt
{

struct Projection
{
  ProjectionClass kind = ProjectionClass::NotDrawable;
  int vertex[4] = { 0, 1, 2, 3 };
  double alpha = 0, beta = 0;
  double weights[3] = { 0, 0, 0 };
};

/**
 * Relative tolerance of the classification: a signed sub-triangle area whose magnitude
 * is at most this fraction of the projection's total area counts as zero. It turns
 * near-limit projections into the class 3 and 4 limits instead of producing huge or
 * signed interpolation weights; it never divides by a near-zero denominator.
 */
constexpr double ClassificationTolerance = 1e-10;

/**
 * Classifies a tetrahedron from its 4 projected (x, y) positions. Never divides by zero:
 * every weight is a ratio of areas whose denominator is at least the numerator.
 * Thread safety: pure function.
 */
Projection ClassifyProjection(const double x[4], const double y[4]);

/**
 * Decomposes one tetrahedron into slot-local records.
 * @param corners    the tetrahedron's 4 projected points (ProjectPoints)
 * @param scalars    the scalar at each corner (the cell's scalar four times for cell data)
 * @param vertices   5 records written
 * @param indices    12 slot-local indices (0..4) written
 * @param colours    null, or each corner's RGBA (dependent components): the records then
 *                   hold colours (StoreVertexColour), the thick vertex's the mean of the
 *                   colours interpolated at the front and back of its segment
 * @return the classification (NotDrawable: the slot is degenerate, all zeros)
 * Thread safety: pure function of its arguments.
 */
Projection DecomposeTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  TetVertex vertices[VerticesPerTetrahedron], std::uint32_t indices[IndicesPerTetrahedron],
  const float* const* colours = nullptr);

/// Inputs of the decomposition stage that stay fixed during a frame.
struct DecomposeInput
{
  const ProjectedPoint* points = nullptr; ///< pointCount records (ProjectPoints)
  std::size_t pointCount = 0;
  CellsView cells;
  /// Only cell scalars are read from here; point scalars travel in the records.
  ScalarsView scalars;
  /// Dependent components: RGBA (4 floats in [0, 1], the attenuation last) per point or per
  /// cell, as `scalars` are associated. Set, the records hold colours (StoreVertexColour),
  /// and `scalars` must be the attenuations (a non-finite one marks a point or cell that
  /// cannot be drawn). Null: the records hold scalars.
  const float* colours = nullptr;
  /// The composited image's size. When set, cells whose projection covers no pixel centre of
  /// it (sub-pixel cells, cells off screen) become CoversNoPixel slots: same image, much
  /// less work for small images. Empty: no culling.
  ImageSize imageSize;
  /// Set when the cells of the order were already tested against this image (the depth
  /// keys' culling, KeyCulling): the by-rank decompositions then skip the test for cells
  /// and keep it for near-plane pieces (DecomposeIntoSlot, DecomposeIntoFan).
  bool cellsCoverPixels = false;
  /**
   * The pixels already opaque in the image the cells are composited behind, front to back
   * (OpaquePixels.h; the CPU compositor's, FramePipeline::DrawBatches). When set, a
   * tetrahedron every pixel centre of whose bounding box is opaque there is Hidden: where
   * the by-rank decomposition (DecomposeFansByRank) keeps classes, its fan is left
   * unwritten (the class tells the reader to skip it); elsewhere its fan is count 0 and its
   * slot degenerate. Null: nothing is hidden.
   */
  const OpaquePixels* hidden = nullptr;
  /// The by-rank decompositions: the ascending list of the cells the order was made from
  /// (the depth keys' candidates), so that they visit those only and read no other rank;
  /// null: every cell of the mesh.
  const std::uint32_t* cellList = nullptr;
  std::size_t cellListCount = 0;
  /// Set, the by-rank decompositions visit these cells instead, each with its rank: the
  /// cell id in the high 32 bits, the rank in the low (a batch's rank groups,
  /// OrderStage::Group), and read no rank array.
  const SortKey* rankedCells = nullptr;
  std::size_t rankedCellCount = 0;

  /// How many cells the by-rank passes visit: rankedCells, else cellList, else every cell.
  std::size_t VisitedCount() const
  {
    return this->rankedCells ? this->rankedCellCount
      : this->cellList       ? this->cellListCount
                             : this->cells.cellCount;
  }
  /// Entry i of the cells the by-rank passes visit: its cell, and its rank (its entry's, or
  /// rank[cell]).
  void Visited(
    std::size_t i, const std::uint32_t* rank, std::size_t& cell, std::uint32_t& cellRank) const
  {
    if (this->rankedCells)
    {
      cell = static_cast<std::size_t>(this->rankedCells[i] >> 32);
      cellRank = static_cast<std::uint32_t>(this->rankedCells[i]);
      return;
    }
    cell = this->cellList ? this->cellList[i] : i;
    cellRank = rank[cell];
  }
};

/**
 * Decomposes the cells order[0..count) into slots 0..count-1 of `vertices`
 * (5 * count records) and `indices` (12 * count entries, global: slot k uses 5k + local).
 * `classes`, when not null, receives each slot's class (count entries).
 * Requires 5 * count < 2^32. For batches, pass order + first and fresh buffers.
 *
 * Thread safety: reentrant; `threads` OpenMP threads (<= 0: all available).
 * Determinism: every slot is a pure function of its cell: bit-identical for any thread
 * count.
 */
void DecomposeTetrahedra(const DecomposeInput& input, const SortKey* order, std::size_t count,
  TetVertex* vertices, std::uint32_t* indices, ProjectionClass* classes, int threads);

/**
 * Decomposes one tetrahedron given by its projected corners (a piece of a cell cut by the
 * near plane, NearPlane.h) into slot k of `vertices` and `indices` (global indices 5k +
 * local), with the culling of DecomposeTetrahedra. Returns its class.
 * Thread safety: writes only slot k.
 */
ProjectionClass DecomposeIntoSlot(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], std::size_t k,
  TetVertex* vertices, std::uint32_t* indices, const float* const* colours = nullptr);

/**
 * The fan of one tetrahedron (see Fan and DecomposeTetrahedron); count 0 when it cannot be
 * drawn. Thread safety: pure function of its arguments.
 */
Projection DecomposeTetrahedronToFan(const ProjectedPoint* const corners[4], const float scalars[4],
  Fan& fan, const float* const* colours = nullptr);

/**
 * As DecomposeIntoSlot, into a fan: `fan` receives the tetrahedron's fan, or count 0 when it
 * is not drawable, covers no pixel centre or is hidden. Returns its class.
 */
ProjectionClass DecomposeIntoFan(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], Fan& fan,
  const float* const* colours = nullptr);

/**
 * As DecomposeTetrahedraByRank, into fans: rank r of the window [firstRank, firstRank +
 * count) into fans[r - firstRank]. The CPU compositor's input; no vertex or index buffer.
 * Thread safety and determinism: as DecomposeTetrahedraByRank.
 */
void DecomposeFansByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, Fan* fans, ProjectionClass* classes, int threads);

/**
 * The same buffers as DecomposeTetrahedra for the order that `rank` inverts, computed by
 * visiting the cells in storage order and writing each into slot rank[cell]. Reads are then
 * sequential and the point records are reused while cached; only the slot writes scatter,
 * and writes do not stall the way dependent gathers do. On meshes larger than the cache
 * this is several times faster than gathering in visibility order (see the benchmark).
 *
 * Only ranks in the window [firstRank, firstRank + count) are decomposed, rank r into slot
 * r - firstRank of `vertices` (5 * count records) and `indices` (12 * count, numbered from
 * 0): a frame drawn in batches decomposes one window at a time into the same buffers.
 * The whole order is firstRank 0 and count = the number of ranked cells.
 *
 * Without dependent colours the cells are decomposed several at a time, one per SIMD lane
 * (Documentation/algorithm.md, "Several tetrahedra at once"), with the result of the scalar
 * decomposition (DecomposeIntoSlot) bit for bit.
 *
 * Thread safety and determinism: as DecomposeTetrahedra; each slot has exactly one writer.
 */
void DecomposeTetrahedraByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, TetVertex* vertices, std::uint32_t* indices,
  ProjectionClass* classes, int threads);

/**
 * Stage 5 as a stage of FramePipeline (Stage.h): one window of the order decomposed into
 * buffers, the cells by rank and the near-plane pieces in their slots, kept until the
 * order, the window or the viewport (pixel culling) change. Two of them run, one per kind of
 * buffer (SlotStage for OpenGL, FanStage for the CPU compositor); with several batches each
 * batch is decomposed again every frame, as the buffers hold only the last one.
 */
/// What a decomposed window depends on: DecompositionStage's key.
struct DecompositionKey
{
  std::uint64_t order = 0; ///< OrderStage::Version()
  std::size_t first = 0, count = 0;
  ImageSize imageSize;
  std::uint64_t hidden = 0; ///< DecomposeInput::hidden's OpaquePixels::Version(); 0: none
  bool operator==(const DecompositionKey& o) const
  {
    return order == o.order && first == o.first && count == o.count && imageSize == o.imageSize &&
      hidden == o.hidden;
  }
};

/**
 * The classification of one projected tetrahedron.
 * Quadrilateral: edges (vertex[0], vertex[1]) and (vertex[2], vertex[3]) cross at
 *   position alpha along the first and beta along the second (both in [0, 1]).
 * Triangle, VertexOnEdge, CoincidentVertices: vertex[3] is the thick (inner) point and
 *   vertex[0..2] the outer triangle; weights[0..2] are the screen-space barycentric
 *   coordinates of the inner point in that triangle (non-negative, sum 1).
 */
class DecompositionStage : public StageOf<DecompositionKey>
{
public:
  /// Tetrahedra of the held window.
  std::size_t Count() const { return this->Record.Inputs().count; }
  /// Slots or fans of the held window that cover no pixel centre, cannot be drawn, or are
  /// hidden behind opaque pixels (DecomposeInput::hidden).
  std::size_t PixelCulled() const { return this->CoversNoPixel; }
  std::size_t NotDrawable() const { return this->Undrawable; }
  std::size_t Hidden() const { return this->Concealed; }
  /// Each slot's or fan's class, of the held window (Count() of them): what a reader of the
  /// fans skips (Drawn, Records.h).
  const ProjectionClass* Classes() const { return this->SlotClasses.data(); }
  /**
   * Room for windows of `slots` tetrahedra (the batch size), allocated at once: the first
   * window of a frame may be the order's shorter last one (batches front to back), and
   * growing from it would hold more than a window (LargeBuffer.h, ReserveDiscarding). A
   * buffer that grows drops the held window.
   */
  virtual void Reserve(std::size_t slots) = 0;

protected:
  /// The window of `key` through `cells(input, first, count, classes, threads)` (the cells by
  /// rank) and `piece(input, corners, scalars, colours, k)` (each near-plane piece in the
  /// window, k its slot), unless it is held; true when it decomposed.
  template <typename Cells, typename Piece>
  bool Run(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
    const std::vector<NearPiece>& pieces, int threads, Cells&& cells, Piece&& piece);

  /// Reserve's part for the classes; true when a buffer dropped its content.
  bool ReserveClasses(std::size_t slots);

  LargeVector<ProjectionClass> SlotClasses; ///< per slot of the window
  std::size_t CoversNoPixel = 0, Undrawable = 0, Concealed = 0;
};

/// The OpenGL backend's buffers: slots of VerticesPerTetrahedron records and
/// IndicesPerTetrahedron indices.
class SlotStage : public DecompositionStage
{
public:
  bool Update(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
    const std::vector<NearPiece>& pieces, int threads);
  const LargeVector<TetVertex>& Vertices() const { return this->VertexBuffer; }
  const LargeVector<std::uint32_t>& Indices() const { return this->IndexBuffer; }
  void Reserve(std::size_t slots) override;
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  LargeVector<TetVertex> VertexBuffer;
  LargeVector<std::uint32_t> IndexBuffer;
};

/// The CPU compositor's input: one fan per tetrahedron.
class FanStage : public DecompositionStage
{
public:
  bool Update(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
    const std::vector<NearPiece>& pieces, int threads);
  const LargeVector<Fan>& Fans() const { return this->FanBuffer; }
  void Reserve(std::size_t slots) override;
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  LargeVector<Fan> FanBuffer;
};

} // namespace mtpt

#endif
