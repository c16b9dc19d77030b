// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Records.h
 * @brief The records that pass from one stage of a frame to the next: projected points
 * (stage 1), sort keys (stages 3 and 4), the decomposition's vertex records, fans and
 * projection classes (stage 5), and the size of the CPU compositor's tiles and its pixel
 * regions (stage 6). The lowest floor of the core with MeshView.h: every stage reads these,
 * none of them includes a stage.
 *
 * Conventions: see MeshView.h (row-major matrices on column vectors, OpenGL NDC, the
 * camera looking down -z in eye space) and the stage headers.
 */
#ifndef mtpt_Records_h
#define mtpt_Records_h

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace mtpt
{

/**
 * A point after projection. x, y, z are NDC (clip coordinates divided by w) and inverseW is
 * 1 / w, the clip-space w (1 for orthographic projections, the distance along the view axis
 * for perspective ones): decomposition interpolates perspective-correctly with it.
 * `usable` is 0 for a point that no cell may be drawn with: at or behind the eye plane
 * (w <= 0), a coordinate or scalar that is not finite, or a magnitude beyond
 * CoordinateLimit. Its other fields are then meaningless.
 */
struct alignas(64) ProjectedPoint
{
  double x, y, z, inverseW; ///< NDC and 1 / clip w
  double eyeX, eyeY, eyeZ;  ///< eye coordinates (model-view applied)
  float scalar;             ///< the point's scalar; 0 without point scalars
  std::int32_t usable;      ///< 1 if usable, 0 if not (checked once here, not per cell)
};

/// Beyond this magnitude a coordinate is unusable: it keeps every value written to the
/// float vertex records finite (float overflows near 3.4e38).
constexpr double CoordinateLimit = 1e30;

using SortKey = std::uint64_t;

/**
 * The 32-bit code of a depth whose ascending order is descending depth. NaN and the
 * infinities map to the code of +infinity (drawn first; such cells are not drawable
 * anyway) and -0 maps to the code of +0, so equal depths always give equal codes.
 */
std::uint32_t EncodeDepth(float depth);

/// The sort key of `cell` at `depth`: EncodeDepth(depth) in the high 32 bits, cell id low.
inline SortKey MakeSortKey(float depth, std::uint32_t cell)
{
  return (static_cast<SortKey>(EncodeDepth(depth)) << 32) | cell;
}

/// The cell id held in a sort key.
inline std::uint32_t CellOfKey(SortKey key)
{
  return static_cast<std::uint32_t>(key & 0xffffffffu);
}

/**
 * The depth that orders a tetrahedron (Documentation/algorithm.md, "Depth keys"): of the
 * centroid of its four eye-space corners, the squared distance from the eye in
 * perspective views, the distance along the view axis (-z) in orthographic ones. One
 * function for the cells' keys and the near-plane pieces' keys.
 */
inline float CentroidDepth(const ProjectedPoint* const corners[4], bool perspective)
{
  double x = 0, y = 0, z = 0;
  for (int i = 0; i < 4; ++i)
  {
    x += corners[i]->eyeX;
    y += corners[i]->eyeY;
    z += corners[i]->eyeZ;
  }
  x *= 0.25;
  y *= 0.25;
  z *= 0.25;
  return static_cast<float>(perspective ? x * x + y * y + z * z : -z);
}

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

/// Floats in a vertex record (OpenGL reads the records as floats of this stride).
constexpr std::size_t FloatsPerVertex = sizeof(TetVertex) / sizeof(float);
static_assert(FloatsPerVertex == 6, "a vertex record is the paper's 6 floats");

/// The fixed stride of the decomposition (Decompose.h): every tetrahedron writes this many
/// vertex records and triangles, a triangle projection padding its last triangle.
constexpr std::size_t VerticesPerTetrahedron = 5;
constexpr std::size_t TrianglesPerTetrahedron = 4;
constexpr std::size_t IndicesPerTetrahedron = 3 * TrianglesPerTetrahedron;

/// The most tetrahedra (cells and near-plane pieces) one frame can hold: slot k's vertices
/// are numbered from VerticesPerTetrahedron * k with 32-bit indices, and keys hold 32-bit ids.
constexpr std::size_t MaxFrameTetrahedra = 0xffffffffu / VerticesPerTetrahedron;

/**
 * Shirley-Tuchman classes of a projected tetrahedron (Decompose.h), and why a slot or fan
 * draws nothing. Classes 3 and 4 are the limits of class 1 and are drawn as class 1 with a
 * degenerate triangle or two.
 */
enum class ProjectionClass : std::uint8_t
{
  NotDrawable = 0,
  Triangle = 1,           ///< class 1: one point projects strictly inside the other three
  Quadrilateral = 2,      ///< class 2: two opposite edges cross
  VertexOnEdge = 3,       ///< class 3: one point projects onto an edge of the other three
  CoincidentVertices = 4, ///< class 4: two points project onto the same position
  /// Culled (only with DecomposeInput::imageSize set): the projection's bounding box
  /// contains no pixel centre of the image, so no rasterizer that samples at pixel
  /// centres (OpenGL without multisampling, the CPU compositor) would produce a fragment.
  /// The slot is degenerate, as for NotDrawable.
  CoversNoPixel = 5,
  /// Hidden (only with DecomposeInput::hidden set): every pixel centre of the projection's
  /// bounding box is opaque already (OpaquePixels.h), so no fragment of it could show. The
  /// by-rank decomposition leaves its fan unwritten: whoever reads the fans skips it by its
  /// class (Drawn).
  Hidden = 6,
};

/// Whether a slot or fan of class `kind` holds something to draw (classes 1 to 4).
inline bool Drawn(ProjectionClass kind)
{
  return kind >= ProjectionClass::Triangle && kind <= ProjectionClass::CoincidentVertices;
}

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
  /// Set by the compositor on its own copy: the fan straddles a clipping plane, so its
  /// fragments are cut (CompositeSettings::clipPlanes).
  std::uint8_t straddles;
  std::uint8_t padding[5];
};
static_assert(sizeof(Fan) == 128, "a fan is two cache lines");

/// The rank of a cell that is not in the visibility order (InvertOrder, VisibilityOrder.h):
/// the decomposition skips it.
constexpr std::uint32_t NotInOrder = 0xffffffffu;

/// Pixels per side of a tile of the CPU compositor (Compositor.h): tiles are binned,
/// rasterized and kept in cache one at a time.
constexpr int TileSize = 64;

/// A rectangle of pixels of an image: [x0, x1) x [y0, y1) (empty when x0 >= x1 or y0 >= y1),
/// the compositor's touched region and the regions the image sampling reads and writes.
struct PixelRegion
{
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool Empty() const { return x0 >= x1 || y0 >= y1; }
};

/**
 * The size in pixels of the image a frame is composited into: the viewport's at image sample
 * distance 1, else fewer (or more) pixels across the same view (ImageSampling.h). The one
 * name of this size from the frame's plan (FramePlan::imageSize) down to the stages, which cull
 * the cells that cover none of its pixel centres; empty (0 x 0) culls none.
 */
struct ImageSize
{
  int width = 0, height = 0;
  bool Empty() const { return width <= 0 || height <= 0; }
  bool operator==(const ImageSize& o) const { return width == o.width && height == o.height; }
};

} // namespace mtpt

#endif
