// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TetrahedralGrid.h
 * @brief Benchmark inputs: a plain tetrahedral mesh struct and a generator for tetrahedralized
 * regular grids of any size (no VTK needed).
 *
 * The generated mesh is conforming (neighbouring hexahedra split their shared face along the
 * same diagonal), every tetrahedron has positive volume, and the output is a pure function
 * of the options, so benchmark runs on different machines see the same input.
 */
#ifndef mtpt_bench_TetrahedralGrid_h
#define mtpt_bench_TetrahedralGrid_h

#include "mtpt/MeshView.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mtpt
{
namespace bench
{

/**
 * A tetrahedral mesh owning its arrays, laid out as mtpt's views expect (MeshView.h):
 * interleaved float xyz, vtkCellArray offsets + connectivity (offsets has CellCount() + 1
 * entries, every cell has 4 point ids) and one float scalar per point.
 */
struct TetMesh
{
  std::string name;
  std::string scalarName;
  std::vector<float> points;
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
  std::vector<float> scalars;

  std::size_t PointCount() const { return points.size() / 3; }
  std::size_t CellCount() const { return offsets.empty() ? 0 : offsets.size() - 1; }

  PointsView Points() const { return PointsView::FromFloat(points.data(), PointCount()); }
  CellsView Cells() const
  {
    return CellsView::FromInt64(connectivity.data(), offsets.data(), CellCount());
  }
  ScalarsView Scalars() const
  {
    return { scalars.empty() ? nullptr : scalars.data(), ScalarsView::Association::Points };
  }

  /// Axis-aligned bounds as { xmin, xmax, ymin, ymax, zmin, zmax } (VTK's order).
  std::array<double, 6> Bounds() const;
};

/// How each hexahedron of the grid is split.
enum class HexSplit
{
  /// 5 tetrahedra: one central tetrahedron and 4 corner ones. The pattern mirrors between
  /// neighbouring cells (checkerboard on i + j + k) so shared faces agree on their diagonal.
  Five,
  /// 6 tetrahedra around the main diagonal (Kuhn / Freudenthal split). Every cell is split
  /// the same way and the result is always conforming.
  Six,
};

struct GridOptions
{
  std::array<int, 3> cells = { 62, 62, 62 }; ///< hexahedra along x, y, z (each >= 1)
  HexSplit split = HexSplit::Five;
  /// Interior points move by up to this fraction of the grid spacing along each axis
  /// (deterministic pseudo-random). Breaks the exact depth ties of a perfect lattice, which
  /// no real mesh has. Clamped to MaxJitter(split) so no tetrahedron can invert.
  double jitter = 0.0;
  std::uint64_t seed = 1;
};

/// Tetrahedra per hexahedron for a split.
int TetrahedraPerHexahedron(HexSplit split);

/**
 * Largest jitter that provably keeps every tetrahedron positive. A tetrahedron's edge
 * matrix (in units of the spacing) moves by at most 2 * jitter per entry, so by at most
 * 6 * jitter in the spectral norm; that must stay below the matrix's smallest singular value:
 * 1 for both kinds of tetrahedra of the 5-split, 0.55 for the path tetrahedra of the 6-split.
 */
double MaxJitter(HexSplit split);

/**
 * Grid dimensions (hexahedra along x, y, z) whose split has at least `minimumTetrahedra`
 * tetrahedra and as few more as a near-cubic grid allows: x = y = ceil(cbrt(cells)) and z
 * just large enough.
 */
std::array<int, 3> GridCellsForTetrahedra(std::size_t minimumTetrahedra, HexSplit split);

/**
 * Generates the grid. The grid is centred on the origin, its longest side spans [-1, 1] and
 * its spacing is the same along every axis. The point scalar is a smooth field in [0, 1]: a
 * sum of low-frequency sines plus a Gaussian blob, so shading sees gradients in every
 * direction rather than a constant.
 */
TetMesh GenerateTetrahedralGrid(const GridOptions& options);

} // namespace bench
} // namespace mtpt

#endif
