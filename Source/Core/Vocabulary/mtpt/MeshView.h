// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshView.h
 * @brief Non-owning views of a tetrahedral mesh as VTK holds it, and the 4x4 matrix type.
 *
 * Conventions used by every mtpt header:
 * - Matrices are row-major, 4x4, double precision, and act on column vectors:
 *   p' = M * p, element (row r, column c) is m[4*r + c]. This is vtkMatrix4x4's layout
 *   (vtkMatrix4x4::GetData() can be copied in unchanged).
 * - "Model" coordinates are the coordinates stored in the mesh. "Eye" coordinates are
 *   model coordinates mapped by the model-view matrix (VTK: view transform times the
 *   volume's matrix); the camera looks down -z in eye space, as in OpenGL.
 * - Normalized device coordinates (NDC) follow OpenGL: x and y in [-1, 1] across the
 *   viewport, z in [-1, 1] from the near to the far plane (smaller z is nearer).
 * - Connectivity follows vtkCellArray (VTK 9): cell c owns the point ids
 *   connectivity[offsets[c]] .. connectivity[offsets[c+1]-1]; offsets has cellCount+1
 *   entries. Offsets and connectivity share one integer type (int32 or int64), as in
 *   vtkCellArray's 32- and 64-bit storages. Without offsets (VTK 9.6's fixed-size
 *   storages, whose offsets are implicit), cell c owns connectivity[c * cellSize] ..
 *   connectivity[(c+1) * cellSize - 1].
 *
 * Views never copy or own data; the caller keeps the arrays alive while a view is in use.
 */
#ifndef mtpt_MeshView_h
#define mtpt_MeshView_h

#include <array>
#include <cstddef>
#include <cstdint>

namespace mtpt
{

/// Row-major 4x4 matrix acting on column vectors (see the conventions above).
using Matrix4 = std::array<double, 16>;

/// The identity matrix.
Matrix4 IdentityMatrix();

/// a * b (row-major, column vectors: apply b first, then a).
Matrix4 Multiply(const Matrix4& a, const Matrix4& b);

struct MeshPart;

/**
 * Point coordinates: `count` points of 3 components, interleaved xyz. Or, with `parts`, the
 * points of several parts one after the other (part k's after those of parts 0 to k-1;
 * `count` their total; see MeshPart).
 */
struct PointsView
{
  enum class Type
  {
    Float32,
    Float64
  };
  const void* data = nullptr;
  Type type = Type::Float32;
  std::size_t count = 0;
  const MeshPart* parts = nullptr; ///< several parts instead of `data`
  std::size_t partCount = 0;

  static PointsView FromFloat(const float* xyz, std::size_t n)
  {
    return { xyz, Type::Float32, n, nullptr, 0 };
  }
  static PointsView FromDouble(const double* xyz, std::size_t n)
  {
    return { xyz, Type::Float64, n, nullptr, 0 };
  }
};

/**
 * Cells in vtkCellArray's offsets + connectivity layout (see the conventions above). Or,
 * with `parts`, the cells of several parts one after the other (part k's after those of
 * parts 0 to k-1, their point ids local to the part; `cellCount` their total).
 */
struct CellsView
{
  enum class Type
  {
    Int32,
    Int64
  };
  const void* connectivity = nullptr;
  const void* offsets = nullptr; ///< cellCount + 1 entries; null: every cell has cellSize
  Type type = Type::Int64;
  std::size_t cellCount = 0;
  std::size_t cellSize = 0;        ///< points per cell when there are no offsets
  const MeshPart* parts = nullptr; ///< several parts instead of the arrays above
  std::size_t partCount = 0;

  static CellsView FromInt32(const std::int32_t* conn, const std::int32_t* offsets, std::size_t n)
  {
    return { conn, offsets, Type::Int32, n, 0, nullptr, 0 };
  }
  static CellsView FromInt64(const std::int64_t* conn, const std::int64_t* offsets, std::size_t n)
  {
    return { conn, offsets, Type::Int64, n, 0, nullptr, 0 };
  }
  /// Every cell `cellSize` points long, one after the other (no offsets array).
  static CellsView FromFixedSizeInt32(const std::int32_t* conn, std::size_t cellSize, std::size_t n)
  {
    return { conn, nullptr, Type::Int32, n, cellSize, nullptr, 0 };
  }
  static CellsView FromFixedSizeInt64(const std::int64_t* conn, std::size_t cellSize, std::size_t n)
  {
    return { conn, nullptr, Type::Int64, n, cellSize, nullptr, 0 };
  }
};

/**
 * One part of a mesh made of several, such as a block of a multi-block data set used in
 * place: its own points and cells, the cells' point ids local to the part. A mesh of parts
 * (MeshParts) numbers points and cells over the parts in order, so that every stage sees
 * one mesh: one visibility order over the cells of all parts.
 */
struct MeshPart
{
  PointsView points; ///< a single part: no nested parts
  CellsView cells;
  /// The matrix taking the part's points to the mesh's model coordinates, for parts placed
  /// by matrices of their own (volumes of several transforms drawn as one mesh); null: the
  /// identity. The caller keeps it alive and unchanged while the views are in use.
  const Matrix4* model = nullptr;
};

/// The points and cells of `count` parts as one mesh (the views refer to `parts`, which the
/// caller keeps alive and unchanged while the views are in use).
inline void MeshParts(
  const MeshPart* parts, std::size_t count, PointsView& points, CellsView& cells)
{
  points = PointsView{};
  cells = CellsView{};
  for (std::size_t k = 0; k < count; ++k)
  {
    points.count += parts[k].points.count;
    cells.cellCount += parts[k].cells.cellCount;
  }
  points.parts = cells.parts = parts;
  points.partCount = cells.partCount = count;
}

/// Scalars for shading: one float per point or one per cell. A null `values` pointer
/// means "no scalars": every scalar reads as 0.
struct ScalarsView
{
  enum class Association
  {
    Points,
    Cells
  };
  const float* values = nullptr;
  Association association = Association::Points;
};

/**
 * What a frame's results depend on in its data, for the stages' keys (Stage.h): the arrays
 * the views show and a version the caller changes whenever their content changes in place
 * (FrameInput::dataVersion).
 */
struct MeshKey
{
  const void* points = nullptr;
  const MeshPart* pointParts = nullptr;
  std::size_t pointCount = 0;
  const void* connectivity = nullptr;
  const void* offsets = nullptr;
  const MeshPart* cellParts = nullptr;
  std::size_t cellSize = 0, cellCount = 0;
  const float* scalars = nullptr;
  const float* colours = nullptr;
  ScalarsView::Association association = ScalarsView::Association::Points;
  std::uint64_t version = 0;

  static MeshKey Of(const PointsView& p, const CellsView& c, const ScalarsView& s,
    const float* colours, std::uint64_t version)
  {
    return { p.data, p.parts, p.count, c.connectivity, c.offsets, c.parts, c.cellSize, c.cellCount,
      s.values, colours, s.association, version };
  }
  bool operator==(const MeshKey& o) const
  {
    return points == o.points && pointParts == o.pointParts && pointCount == o.pointCount &&
      connectivity == o.connectivity && offsets == o.offsets && cellParts == o.cellParts &&
      cellSize == o.cellSize && cellCount == o.cellCount && scalars == o.scalars &&
      colours == o.colours && association == o.association && version == o.version;
  }
};

} // namespace mtpt

#endif
