// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Decompose.h
 * @brief Stage 4 of a frame: classify each tetrahedron's projection and decompose it into
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

#include "mtpt/DepthKeys.h"
#include "mtpt/MeshView.h"
#include "mtpt/Transform.h"

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace mtpt
{

/// One vertex of the decomposition (24 bytes).
struct TetVertex
{
  float x, y, z;     ///< NDC; z is the front of the segment
  float scalarFront; ///< scalar where the ray enters the tetrahedron
  float scalarBack;  ///< scalar where the ray leaves it
  float thickness;   ///< eye-space length of the ray segment inside the tetrahedron
};

/**
 * Dependent components (Documentation/algorithm.md, "Dependent components"): where the data
 * give colour and opacity themselves rather than a scalar to look up, the decomposition
 * classifies at the vertices (DecomposeInput::colours) and the bytes of a record's
 * scalarFront and scalarBack hold the vertex's colour instead: red, green, blue and the
 * attenuation (per ScalarOpacityUnitDistance), each clamped to [0, 1] and stored as a
 * 16-bit unsigned normalized integer, in that memory order. OpenGL reads them as a
 * normalized GL_UNSIGNED_SHORT vec4; VTK's PT keeps 8 bits per channel.
 */
inline void StoreVertexColour(TetVertex& vertex, const float rgba[4])
{
  std::uint16_t packed[4];
  for (int c = 0; c < 4; ++c)
  {
    const float v = rgba[c] > 0.0f ? (rgba[c] < 1.0f ? rgba[c] : 1.0f) : 0.0f; // NaN: 0
    packed[c] = static_cast<std::uint16_t>(v * 65535.0f + 0.5f);
  }
  static_assert(sizeof(packed) == 2 * sizeof(float), "two record fields hold the colour");
  std::memcpy(&vertex.scalarFront, packed, sizeof(packed));
}

/// The colour StoreVertexColour put in `vertex`.
inline void LoadVertexColour(const TetVertex& vertex, float rgba[4])
{
  std::uint16_t packed[4];
  std::memcpy(packed, &vertex.scalarFront, sizeof(packed));
  for (int c = 0; c < 4; ++c)
  {
    rgba[c] = static_cast<float>(packed[c]) * (1.0f / 65535.0f);
  }
}

constexpr std::size_t VerticesPerTetrahedron = 5;
constexpr std::size_t IndicesPerTetrahedron = 12;

/**
 * One tetrahedron's projection as the CPU compositor draws it: a fan of triangles around the
 * thick vertex (the centre), over the silhouette's corners (the boundary) in cyclic order.
 * Triangle i is (boundary[i], boundary[i + 1], centre), and when `closed`,
 * (boundary[count - 1], boundary[0], centre) closes the fan. The records and their values
 * are those of the slot DecomposeTetrahedron writes for the same tetrahedron (both are
 * written from one computation): 128 bytes (two cache lines) against a slot's 168, and no
 * index buffer. count 0: nothing to draw (not drawable, or culled). count 2 with `closed`
 * 0 is a single triangle (the compositor's slot entry point makes those).
 */
struct Fan
{
  TetVertex centre;      ///< the thick vertex
  TetVertex boundary[4]; ///< the silhouette's corners (front = back, length 0 for a cell's)
  std::uint8_t count;    ///< boundary corners: 0, 2, 3 or 4
  std::uint8_t closed;   ///< whether the last triangle closes the fan
  std::uint8_t padding[6];
};
static_assert(sizeof(Fan) == 128, "a fan is two cache lines");

/**
 * Shirley-Tuchman classes of a projected tetrahedron. Classes 3 and 4 are the limits of
 * class 1 and are drawn as class 1 with a degenerate triangle or two.
 */
enum class ProjectionClass : std::uint8_t
{
  NotDrawable = 0,
  Triangle = 1,           ///< class 1: one point projects strictly inside the other three
  Quadrilateral = 2,      ///< class 2: two opposite edges cross
  VertexOnEdge = 3,       ///< class 3: one point projects onto an edge of the other three
  CoincidentVertices = 4, ///< class 4: two points project onto the same position
  /// Culled (only with DecomposeInput::viewportWidth/Height set): the projection's bounding
  /// box contains no pixel centre of the viewport, so no rasterizer that samples at pixel
  /// centres (OpenGL without multisampling, the CPU compositor) would produce a fragment.
  /// The slot is degenerate, as for NotDrawable.
  CoversNoPixel = 5,
};

/**
 * The classification of one projected tetrahedron.
 * Quadrilateral: edges (vertex[0], vertex[1]) and (vertex[2], vertex[3]) cross at
 *   position alpha along the first and beta along the second (both in [0, 1]).
 * Triangle, VertexOnEdge, CoincidentVertices: vertex[3] is the thick (inner) point and
 *   vertex[0..2] the outer triangle; weights[0..2] are the screen-space barycentric
 *   coordinates of the inner point in that triangle (non-negative, sum 1).
 */
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
  TetVertex vertices[5], std::uint32_t indices[12], const float* const* colours = nullptr);

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
  /// Viewport size in pixels. When both are > 0, cells whose projection covers no pixel
  /// centre (sub-pixel cells, cells off screen) become CoversNoPixel slots: same image,
  /// much less work for small images. 0: no culling.
  int viewportWidth = 0, viewportHeight = 0;
  /// Set when the cells of the order were already tested against this viewport (the depth
  /// keys' culling, KeyCulling): the by-rank decompositions then skip the test for cells
  /// and keep it for near-plane pieces (DecomposeIntoSlot, DecomposeIntoFan).
  bool cellsCoverPixels = false;
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
 * is not drawable or covers no pixel centre. Returns its class.
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

/// Rank of a cell that is not in the order (InvertOrder).
constexpr std::uint32_t NotInOrder = 0xffffffffu;

/**
 * The inverse of a visibility order: rank[c] = k where order[k] holds cell c, and
 * NotInOrder for the cells of [0, cellCount) that the order leaves out.
 * Thread safety: reentrant; `threads` OpenMP threads. Determinism: a pure function.
 */
void InvertOrder(
  const SortKey* order, std::size_t count, std::size_t cellCount, std::uint32_t* rank, int threads);

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
 * Thread safety and determinism: as DecomposeTetrahedra; each slot has exactly one writer.
 */
void DecomposeTetrahedraByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, TetVertex* vertices, std::uint32_t* indices,
  ProjectionClass* classes, int threads);

} // namespace mtpt

#endif
