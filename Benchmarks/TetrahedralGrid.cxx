// SPDX-License-Identifier: BSD-3-Clause
#include "TetrahedralGrid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace mtpt
{
namespace bench
{

namespace
{

using LocalTet = std::array<int, 4>;

// Hexahedron corners are numbered c = dx + 2 * dy + 4 * dz, dx, dy, dz in {0, 1}.
int CornerOffset(int corner, int axis)
{
  return (corner >> axis) & 1;
}

// Signed volume (times 6) of a tetrahedron of hexahedron corners, on the unit lattice.
int LatticeVolume6(const LocalTet& tet)
{
  int e[3][3];
  for (int r = 0; r < 3; ++r)
  {
    for (int a = 0; a < 3; ++a)
    {
      e[r][a] = CornerOffset(tet[r + 1], a) - CornerOffset(tet[0], a);
    }
  }
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
    e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

// Swaps two vertices where needed so every tetrahedron has positive volume: readers and
// filters downstream (and VTK's own cell quality checks) expect VTK's right-handed order.
std::vector<LocalTet> Oriented(std::vector<LocalTet> tets)
{
  for (LocalTet& tet : tets)
  {
    if (LatticeVolume6(tet) < 0)
    {
      std::swap(tet[2], tet[3]);
    }
  }
  return tets;
}

// The 5-split: the corners of even (odd) coordinate parity form the central tetrahedron
// and each of the other four corners cuts off a corner tetrahedron with its three
// neighbours. Every face diagonal then joins the two corners of the central parity; using
// the even corners in even cells (i + j + k even) and the odd corners in odd ones makes
// those the lattice points of even global parity in both cells, so shared faces agree.
const std::vector<LocalTet>& FiveSplit(int parity)
{
  static const std::vector<LocalTet> even =
    Oriented({ { 0, 3, 5, 6 }, { 1, 0, 3, 5 }, { 2, 0, 3, 6 }, { 4, 0, 5, 6 }, { 7, 3, 5, 6 } });
  static const std::vector<LocalTet> odd =
    Oriented({ { 1, 2, 4, 7 }, { 0, 1, 2, 4 }, { 3, 1, 2, 7 }, { 5, 1, 4, 7 }, { 6, 2, 4, 7 } });
  return parity == 0 ? even : odd;
}

// The Kuhn split: one tetrahedron per monotone lattice path from corner 0 to corner 7
// (one per permutation of the axes). Every face is cut along the diagonal through its
// lowest corner, whichever cell it belongs to, so the split is conforming.
const std::vector<LocalTet>& SixSplit()
{
  static const std::vector<LocalTet> tets = []
  {
    std::vector<LocalTet> result;
    int axes[3] = { 0, 1, 2 };
    do
    {
      const int first = 1 << axes[0];
      const int second = first | (1 << axes[1]);
      result.push_back({ 0, first, second, 7 });
    } while (std::next_permutation(axes, axes + 3));
    return Oriented(result);
  }();
  return tets;
}

// SplitMix64 (Steele, Lea, Flood 2014): a stateless, well-mixed hash of the point id, so
// the jitter of a point does not depend on generation order.
std::uint64_t SplitMix64(std::uint64_t x)
{
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

double RawField(double x, double y, double z)
{
  const double waves =
    0.35 * std::sin(3.0 * x + 0.5) * std::cos(2.0 * y - 0.3) + 0.25 * std::sin(2.5 * z + 1.5 * y);
  const double dx = x - 0.3, dy = y + 0.2, dz = z - 0.1;
  const double blob = 0.4 * std::exp(-(dx * dx + dy * dy + dz * dz) / 0.15);
  return waves + blob;
}

} // namespace

std::array<double, 6> TetMesh::Bounds() const
{
  std::array<double, 6> bounds = { 0, 0, 0, 0, 0, 0 };
  if (points.empty())
  {
    return bounds;
  }
  for (int a = 0; a < 3; ++a)
  {
    bounds[2 * a] = std::numeric_limits<double>::max();
    bounds[2 * a + 1] = std::numeric_limits<double>::lowest();
  }
  for (std::size_t i = 0; i < points.size(); i += 3)
  {
    for (int a = 0; a < 3; ++a)
    {
      const double v = points[i + a];
      bounds[2 * a] = std::min(bounds[2 * a], v);
      bounds[2 * a + 1] = std::max(bounds[2 * a + 1], v);
    }
  }
  return bounds;
}

int TetrahedraPerHexahedron(HexSplit split)
{
  return split == HexSplit::Five ? 5 : 6;
}

double MaxJitter(HexSplit split)
{
  // 1/6 and 0.55/6, rounded down (see the header).
  return split == HexSplit::Five ? 0.16 : 0.09;
}

std::array<int, 3> GridCellsForTetrahedra(std::size_t minimumTetrahedra, HexSplit split)
{
  const std::size_t perHex = static_cast<std::size_t>(TetrahedraPerHexahedron(split));
  const std::size_t hexahedra = std::max<std::size_t>(1, (minimumTetrahedra + perHex - 1) / perHex);
  std::size_t side = static_cast<std::size_t>(std::cbrt(static_cast<double>(hexahedra)));
  // cbrt rounds; settle on the smallest side whose cube is not short.
  while (side > 1 && side * side * side >= hexahedra)
  {
    --side;
  }
  while (side * side * side < hexahedra)
  {
    ++side;
  }
  const std::size_t layer = side * side;
  const std::size_t depth = std::max<std::size_t>(1, (hexahedra + layer - 1) / layer);
  return { static_cast<int>(side), static_cast<int>(side), static_cast<int>(depth) };
}

TetMesh GenerateTetrahedralGrid(const GridOptions& options)
{
  const int nx = options.cells[0], ny = options.cells[1], nz = options.cells[2];
  if (nx < 1 || ny < 1 || nz < 1)
  {
    throw std::invalid_argument("GenerateTetrahedralGrid: every dimension must be >= 1");
  }
  const std::size_t px = static_cast<std::size_t>(nx) + 1;
  const std::size_t py = static_cast<std::size_t>(ny) + 1;
  const std::size_t pz = static_cast<std::size_t>(nz) + 1;
  const std::size_t pointCount = px * py * pz;
  const std::size_t perHex = static_cast<std::size_t>(TetrahedraPerHexahedron(options.split));
  const std::size_t cellCount = perHex * static_cast<std::size_t>(nx) *
    static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz);

  TetMesh mesh;
  mesh.name = "grid " + std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) +
    (options.split == HexSplit::Five ? " /5" : " /6");
  mesh.scalarName = "field";

  // Longest side spans [-1, 1]; equal spacing keeps the tetrahedra well shaped.
  const double spacing = 2.0 / static_cast<double>(std::max({ nx, ny, nz }));
  const double origin[3] = { -0.5 * nx * spacing, -0.5 * ny * spacing, -0.5 * nz * spacing };
  const double jitter = std::clamp(options.jitter, 0.0, MaxJitter(options.split)) * spacing;

  mesh.points.resize(3 * pointCount);
  mesh.scalars.resize(pointCount);
  std::vector<double> field(pointCount);
  for (std::size_t k = 0; k < pz; ++k)
  {
    for (std::size_t j = 0; j < py; ++j)
    {
      for (std::size_t i = 0; i < px; ++i)
      {
        const std::size_t id = i + px * (j + py * k);
        double p[3] = { origin[0] + static_cast<double>(i) * spacing,
          origin[1] + static_cast<double>(j) * spacing,
          origin[2] + static_cast<double>(k) * spacing };
        const bool interior = i > 0 && i + 1 < px && j > 0 && j + 1 < py && k > 0 && k + 1 < pz;
        if (interior && jitter > 0)
        {
          // Three 21-bit fractions of one hash, each mapped to [-1, 1).
          const std::uint64_t h = SplitMix64(options.seed * 0x100000001b3ull ^ id);
          for (int a = 0; a < 3; ++a)
          {
            const double u = static_cast<double>((h >> (21 * a)) & 0x1fffff) / 1048576.0 - 1.0;
            p[a] += jitter * u;
          }
        }
        for (int a = 0; a < 3; ++a)
        {
          mesh.points[3 * id + a] = static_cast<float>(p[a]);
        }
        field[id] = RawField(p[0], p[1], p[2]);
      }
    }
  }

  // Normalise to [0, 1] so transfer functions written for the benchmark need no range.
  const auto [lowest, highest] = std::minmax_element(field.begin(), field.end());
  const double low = *lowest;
  const double range = *highest > low ? *highest - low : 1.0;
  for (std::size_t id = 0; id < pointCount; ++id)
  {
    mesh.scalars[id] = static_cast<float>((field[id] - low) / range);
  }

  mesh.connectivity.resize(4 * cellCount);
  mesh.offsets.resize(cellCount + 1);
  std::size_t cell = 0;
  for (int k = 0; k < nz; ++k)
  {
    for (int j = 0; j < ny; ++j)
    {
      for (int i = 0; i < nx; ++i)
      {
        std::int64_t corners[8];
        for (int c = 0; c < 8; ++c)
        {
          corners[c] = static_cast<std::int64_t>((i + CornerOffset(c, 0)) +
            px * ((j + CornerOffset(c, 1)) + py * (k + CornerOffset(c, 2))));
        }
        const std::vector<LocalTet>& tets =
          options.split == HexSplit::Five ? FiveSplit((i + j + k) & 1) : SixSplit();
        for (const LocalTet& tet : tets)
        {
          mesh.offsets[cell] = static_cast<std::int64_t>(4 * cell);
          for (int v = 0; v < 4; ++v)
          {
            mesh.connectivity[4 * cell + v] = corners[tet[v]];
          }
          ++cell;
        }
      }
    }
  }
  mesh.offsets[cellCount] = static_cast<std::int64_t>(4 * cellCount);
  return mesh;
}

} // namespace bench
} // namespace mtpt
