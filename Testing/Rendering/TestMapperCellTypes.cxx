// SPDX-License-Identifier: BSD-3-Clause
// Cells other than tetrahedra: hexahedra, voxels, wedges, pyramids and mixed grids render
// as the same grid split by vtkDataSetTriangleFilter beforehand; point and cell data follow
// the split; lower-dimensional cells are ignored with one warning; the split is done once
// per input change, not per frame.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCellData.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// Largest RMSE (RGB in [0, 1]) allowed between a grid drawn by the mapper and the same grid
/// split beforehand. Both draw the same tetrahedra in the same order, so every measured
/// value is 0; the bound only leaves room for a different but equivalent split order.
constexpr double SplitRMSEBound = 1e-3;

enum class CellKind
{
  Hexahedron,
  Voxel,
  Wedge,
  Pyramid,
  Mixed
};

const char* Name(CellKind kind)
{
  switch (kind)
  {
    case CellKind::Hexahedron:
      return "hexahedra";
    case CellKind::Voxel:
      return "voxels";
    case CellKind::Wedge:
      return "wedges";
    case CellKind::Pyramid:
      return "pyramids";
    default:
      return "mixed";
  }
}

double FieldValue(const double p[3])
{
  const double r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
  return std::exp(-2.0 * r2) + 0.3 * std::sin(3.0 * p[0]) * std::cos(2.0 * p[1]);
}

/// Builds an n^3 lattice of cubes over [-1, 1]^3 made of `kind` cells (Mixed: hexahedra,
/// voxels, wedges, pyramids and tetrahedra in turn), with the point scalar "field" and the
/// cell scalar "cellField" (the field at the cell's centre).
class GridBuilder
{
public:
  GridBuilder(CellKind kind, int n)
    : Kind(kind)
    , N(n)
  {
    this->Grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    this->Field->SetName("field");
    this->CellField->SetName("cellField");
    const double h = 2.0 / n;
    for (int k = 0; k <= n; ++k)
    {
      for (int j = 0; j <= n; ++j)
      {
        for (int i = 0; i <= n; ++i)
        {
          this->AddPoint(-1 + h * i, -1 + h * j, -1 + h * k);
        }
      }
    }
    for (int k = 0; k < n; ++k)
    {
      for (int j = 0; j < n; ++j)
      {
        for (int i = 0; i < n; ++i)
        {
          this->AddCube(i, j, k);
        }
      }
    }
    this->Grid->SetPoints(this->Points);
    this->Grid->GetPointData()->SetScalars(this->Field);
    this->Grid->GetCellData()->AddArray(this->CellField);
  }
  vtkSmartPointer<vtkUnstructuredGrid> Grid;

private:
  vtkIdType AddPoint(double x, double y, double z)
  {
    const double p[3] = { x, y, z };
    this->Field->InsertNextValue(static_cast<float>(FieldValue(p)));
    return this->Points->InsertNextPoint(p);
  }
  vtkIdType Id(int i, int j, int k) const
  {
    return static_cast<vtkIdType>((k * (this->N + 1) + j) * (this->N + 1) + i);
  }
  void AddCell(int type, std::vector<vtkIdType> ids)
  {
    this->Grid->InsertNextCell(type, static_cast<vtkIdType>(ids.size()), ids.data());
    double centre[3] = { 0, 0, 0 };
    for (const vtkIdType id : ids)
    {
      double p[3];
      this->Points->GetPoint(id, p);
      for (int c = 0; c < 3; ++c)
      {
        centre[c] += p[c] / static_cast<double>(ids.size());
      }
    }
    this->CellField->InsertNextValue(static_cast<float>(FieldValue(centre)));
  }
  void AddCube(int i, int j, int k)
  {
    // Corners in VTK's hexahedron order: bottom 0-3 counter-clockwise, top 4-7 above them.
    const vtkIdType c[8] = { this->Id(i, j, k), this->Id(i + 1, j, k), this->Id(i + 1, j + 1, k),
      this->Id(i, j + 1, k), this->Id(i, j, k + 1), this->Id(i + 1, j, k + 1),
      this->Id(i + 1, j + 1, k + 1), this->Id(i, j + 1, k + 1) };
    CellKind kind = this->Kind;
    if (kind == CellKind::Mixed)
    {
      const CellKind turn[5] = { CellKind::Hexahedron, CellKind::Voxel, CellKind::Wedge,
        CellKind::Pyramid, CellKind::Mixed };
      kind = turn[(i + 2 * j + 3 * k) % 5]; // Mixed here: five tetrahedra
    }
    switch (kind)
    {
      case CellKind::Hexahedron:
        this->AddCell(VTK_HEXAHEDRON, { c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7] });
        break;
      case CellKind::Voxel: // x fastest, then y, then z
        this->AddCell(VTK_VOXEL, { c[0], c[1], c[3], c[2], c[4], c[5], c[7], c[6] });
        break;
      case CellKind::Wedge: // base triangles wound with their normals away from the top
        this->AddCell(VTK_WEDGE, { c[0], c[3], c[1], c[4], c[7], c[5] });
        this->AddCell(VTK_WEDGE, { c[1], c[3], c[2], c[5], c[7], c[6] });
        break;
      case CellKind::Pyramid:
      {
        // Six pyramids with their apex at the cube's centre; each base is wound so that its
        // normal points at the apex.
        double a[3], b[3];
        this->Points->GetPoint(c[0], a);
        this->Points->GetPoint(c[6], b);
        const vtkIdType apex =
          this->AddPoint(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]));
        const int faces[6][4] = { { 0, 1, 2, 3 }, { 4, 7, 6, 5 }, { 0, 4, 5, 1 }, { 1, 5, 6, 2 },
          { 2, 6, 7, 3 }, { 3, 7, 4, 0 } };
        for (const auto& f : faces)
        {
          this->AddCell(VTK_PYRAMID, { c[f[0]], c[f[1]], c[f[2]], c[f[3]], apex });
        }
        break;
      }
      default:
      {
        static const int even[5][4] = { { 0, 1, 3, 4 }, { 1, 2, 3, 6 }, { 1, 4, 5, 6 },
          { 3, 4, 6, 7 }, { 1, 3, 4, 6 } };
        for (const auto& t : even)
        {
          this->AddCell(VTK_TETRA, { c[t[0]], c[t[1]], c[t[2]], c[t[3]] });
        }
        break;
      }
    }
  }

  CellKind Kind;
  int N;
  vtkNew<vtkPoints> Points;
  vtkNew<vtkFloatArray> Field;
  vtkNew<vtkFloatArray> CellField;
};

/// The grid split into tetrahedra by vtkDataSetTriangleFilter (lower-dimensional cells
/// dropped), as a user would have had to do before.
vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralize(vtkUnstructuredGrid* grid)
{
  vtkNew<vtkDataSetTriangleFilter> filter;
  filter->SetInputData(grid);
  filter->TetrahedraOnlyOn();
  filter->Update();
  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  out->ShallowCopy(filter->GetOutput());
  return out;
}

bool AnyContains(const std::vector<std::string>& messages, const std::string& text)
{
  for (const auto& m : messages)
  {
    if (m.find(text) != std::string::npos)
    {
      return true;
    }
  }
  return false;
}

class MapperCellTypes : public ::testing::TestWithParam<CellKind>
{
protected:
  void SetUp() override
  {
    this->Property = MakeProperty(-0.3, 1.3, 0.5);
    this->Observer = vtkSmartPointer<MessageObserver>::New();
  }
  vtkSmartPointer<Mapper> NewMapper()
  {
    auto mapper = vtkSmartPointer<Mapper>::New();
    mapper->AddObserver(vtkCommand::ErrorEvent, this->Observer);
    mapper->AddObserver(vtkCommand::WarningEvent, this->Observer);
    return mapper;
  }
  Scene SceneOf(vtkUnstructuredGrid* grid)
  {
    Scene s;
    s.grid = grid;
    s.property = this->Property;
    s.size = 160;
    return s;
  }
  /// The grid drawn directly and split beforehand, both with fresh mappers.
  ImageDifference CompareWithPresplit(vtkUnstructuredGrid* grid, bool cellScalars)
  {
    auto direct = this->NewMapper();
    auto presplit = this->NewMapper();
    for (Mapper* m : { direct.Get(), presplit.Get() })
    {
      if (cellScalars)
      {
        m->SetScalarModeToUseCellFieldData();
        m->SelectScalarArray("cellField");
      }
    }
    auto reference = Tetrahedralize(grid);
    EXPECT_GT(reference->GetNumberOfCells(), grid->GetNumberOfCells());
    auto image = Render(SceneOf(grid), direct);
    auto expected = Render(SceneOf(reference), presplit);
    EXPECT_EQ(direct->GetNumberOfTetrahedralizations(), 1);
    EXPECT_EQ(presplit->GetNumberOfTetrahedralizations(), 0); // already tetrahedra
    EXPECT_EQ(direct->GetNumberOfTetrahedra(), presplit->GetNumberOfTetrahedra());
    EXPECT_GT(CoveredFraction(image, Background), 0.2); // not an empty picture
    const ImageDifference d = Compare(image, expected);
    if (d.rmse > SplitRMSEBound)
    {
      Save(image, std::string("CellTypes_") + Name(GetParam()));
      Save(expected, std::string("CellTypes_") + Name(GetParam()) + "_presplit");
    }
    return d;
  }
  vtkSmartPointer<vtkVolumeProperty> Property;
  vtkSmartPointer<MessageObserver> Observer;
};

TEST_P(MapperCellTypes, RenderAsTheGridSplitBeforehand)
{
  const auto grid = GridBuilder(GetParam(), 5).Grid;
  for (const bool cellScalars : { false, true })
  {
    const ImageDifference d = this->CompareWithPresplit(grid, cellScalars);
    std::cout << Name(GetParam()) << (cellScalars ? ", cell scalars" : ", point scalars")
              << ": RMSE against the grid split beforehand " << d.rmse << " (bound "
              << SplitRMSEBound << "), worst channel " << d.worst << "\n";
    EXPECT_LE(d.rmse, SplitRMSEBound);
    EXPECT_LE(d.worst, 0.01) << "measured 0: the same tetrahedra";
  }
  EXPECT_TRUE(this->Observer->errors.empty());
  EXPECT_TRUE(this->Observer->warnings.empty());
}

INSTANTIATE_TEST_SUITE_P(CellKinds, MapperCellTypes,
  ::testing::Values(
    CellKind::Hexahedron, CellKind::Voxel, CellKind::Wedge, CellKind::Pyramid, CellKind::Mixed),
  [](const ::testing::TestParamInfo<CellKind>& info) { return std::string(Name(info.param)); });

using MapperTetrahedralization = MapperCellTypes;

TEST_F(MapperTetrahedralization, LowerDimensionalCellsAreIgnoredWithOneWarning)
{
  auto grid = GridBuilder(CellKind::Mixed, 4).Grid;
  const vtkIdType volumeCells = grid->GetNumberOfCells();
  const auto reference = Tetrahedralize(grid); // before the extra cells: the same volume
  const vtkIdType triangle[3] = { 0, 1, 7 }, line[2] = { 2, 40 }, vertex[1] = { 3 };
  grid->InsertNextCell(VTK_TRIANGLE, 3, triangle);
  grid->InsertNextCell(VTK_LINE, 2, line);
  grid->InsertNextCell(VTK_VERTEX, 1, vertex);
  auto* cellField = vtkFloatArray::SafeDownCast(grid->GetCellData()->GetArray("cellField"));
  for (int c = 0; c < 3; ++c)
  {
    cellField->InsertNextValue(0.5f);
  }
  auto mapper = this->NewMapper();
  const auto image = Render(SceneOf(grid), mapper, 3);
  EXPECT_EQ(this->Observer->warnings.size(), 1u) << "one warning, not one per frame";
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "3 of " + std::to_string(volumeCells + 3)));
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "vertices, lines or polygons"));
  EXPECT_TRUE(this->Observer->errors.empty());
  auto fresh = this->NewMapper();
  const ImageDifference d = Compare(image, Render(SceneOf(reference), fresh));
  std::cout << "mixed grid with lower-dimensional cells: RMSE " << d.rmse << "\n";
  EXPECT_LE(d.rmse, SplitRMSEBound);

  // Only lower-dimensional cells: nothing to draw, said once.
  vtkNew<vtkUnstructuredGrid> flat;
  flat->SetPoints(grid->GetPoints());
  flat->GetPointData()->PassData(grid->GetPointData());
  flat->InsertNextCell(VTK_TRIANGLE, 3, triangle);
  this->Observer->Clear();
  const auto nothing = Render(SceneOf(flat), mapper, 2);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "no 3D cells"));
  EXPECT_EQ(this->Observer->warnings.size(), 2u); // the triangle, and nothing left to draw
  EXPECT_LT(CoveredFraction(nothing, Background), 0.001);
}

/// Each hexahedron of `grid` as five tetrahedra of our own split (not the filter's), with
/// the hexahedron's cell scalar on each: an independent check that cell data follows.
vtkSmartPointer<vtkUnstructuredGrid> SplitHexahedraIntoFive(vtkUnstructuredGrid* grid)
{
  auto out = vtkSmartPointer<vtkUnstructuredGrid>::New();
  out->SetPoints(grid->GetPoints());
  out->GetPointData()->PassData(grid->GetPointData());
  vtkNew<vtkFloatArray> cellField;
  cellField->SetName("cellField");
  auto* in = vtkFloatArray::SafeDownCast(grid->GetCellData()->GetArray("cellField"));
  static const int split[5][4] = { { 0, 1, 3, 4 }, { 1, 2, 3, 6 }, { 1, 4, 5, 6 }, { 3, 4, 6, 7 },
    { 1, 3, 4, 6 } };
  vtkNew<vtkIdList> corners;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, corners);
    for (const auto& t : split)
    {
      const vtkIdType ids[4] = { corners->GetId(t[0]), corners->GetId(t[1]), corners->GetId(t[2]),
        corners->GetId(t[3]) };
      out->InsertNextCell(VTK_TETRA, 4, ids);
      cellField->InsertNextValue(in->GetValue(c));
    }
  }
  out->GetCellData()->AddArray(cellField);
  return out;
}

TEST_F(MapperTetrahedralization, CellDataFollowsTheSplit)
{
  // Constant scalars per cell: any split of a cell draws the same colour and optical depth
  // along every ray, so the filter's split and our own give the same image up to rounding.
  auto grid = GridBuilder(CellKind::Hexahedron, 5).Grid;
  auto ours = SplitHexahedraIntoFive(grid);
  auto direct = this->NewMapper();
  auto reference = this->NewMapper();
  for (Mapper* m : { direct.Get(), reference.Get() })
  {
    m->SetScalarModeToUseCellFieldData();
    m->SelectScalarArray("cellField");
  }
  const ImageDifference d =
    Compare(Render(SceneOf(grid), direct), Render(SceneOf(ours), reference));
  std::cout << "hexahedra with cell scalars against an independent 5-tetrahedra split: RMSE "
            << d.rmse << ", worst channel " << d.worst << "\n";
  EXPECT_LT(d.rmse, 4e-3); // measured 0.0016 (within 2/255 everywhere: 8-bit rounding)
  EXPECT_LT(d.worst, 0.02);
  EXPECT_TRUE(this->Observer->errors.empty());
}

TEST_F(MapperTetrahedralization, BadIdsAndPointsInCellsToSplit)
{
  auto grid = GridBuilder(CellKind::Hexahedron, 4).Grid;
  const auto reference = Tetrahedralize(grid); // before the bad cells
  const vtkIdType points = grid->GetNumberOfPoints();
  const vtkIdType hexahedron[8] = { 0, 1, 2, 3, 4, 5, 6, points + 5 };
  const vtkIdType wedge[6] = { -1, 1, 2, 3, 4, 5 };
  grid->InsertNextCell(VTK_HEXAHEDRON, 8, hexahedron);
  grid->InsertNextCell(VTK_WEDGE, 6, wedge);
  auto* cellField = vtkFloatArray::SafeDownCast(grid->GetCellData()->GetArray("cellField"));
  cellField->InsertNextValue(0.5f);
  cellField->InsertNextValue(0.5f);
  auto mapper = this->NewMapper();
  mapper->SetScalarModeToUseCellFieldData();
  mapper->SelectScalarArray("cellField");
  const auto image = Render(SceneOf(grid), mapper, 2);
  EXPECT_EQ(this->Observer->warnings.size(), 1u);
  EXPECT_TRUE(AnyContains(this->Observer->warnings,
    "2 cells name points outside [0, " + std::to_string(points) + ") (first: cell 64)"));
  EXPECT_TRUE(this->Observer->errors.empty());
  auto fresh = this->NewMapper();
  fresh->SetScalarModeToUseCellFieldData();
  fresh->SelectScalarArray("cellField");
  const ImageDifference d = Compare(image, Render(SceneOf(reference), fresh));
  std::cout << "hexahedra with two bad cells against the valid ones: RMSE " << d.rmse << "\n";
  EXPECT_LE(d.rmse, SplitRMSEBound);

  // NaN and infinite points in cells to split: reported, the rest drawn.
  this->Observer->Clear();
  auto nonFinite = GridBuilder(CellKind::Wedge, 4).Grid;
  nonFinite->GetPoints()->SetPoint(7, std::nan(""), 0, 0);
  nonFinite->GetPoints()->SetPoint(30, 0, std::numeric_limits<double>::infinity(), 0);
  const auto partial = Render(SceneOf(nonFinite), mapper, 2);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "2 of 125 points have NaN or infinite"));
  EXPECT_EQ(this->Observer->warnings.size(), 1u);
  EXPECT_GT(CoveredFraction(partial, Background), 0.2);
}

TEST_F(MapperTetrahedralization, IsCachedAndRedoneAfterModified)
{
  auto grid = GridBuilder(CellKind::Hexahedron, 5).Grid;
  auto mapper = this->NewMapper();
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 0);
  Render(SceneOf(grid), mapper, 3);
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 1) << "three frames, one split";
  Render(SceneOf(grid), mapper, 2); // another window, same input
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 1);

  // The data change: the split is redone and the image follows the new data.
  auto* field = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
  for (vtkIdType i = 0; i < field->GetNumberOfTuples(); ++i)
  {
    field->SetValue(i, 1.2f - field->GetValue(i));
  }
  grid->Modified();
  const auto changed = Render(SceneOf(grid), mapper);
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 2);
  auto fresh = this->NewMapper();
  EXPECT_EQ(Compare(changed, Render(SceneOf(grid), fresh)).worst, 0.0);

  // A grid of tetrahedra is used as it is.
  auto tetrahedra = MakeTetrahedralBox(4);
  Render(SceneOf(tetrahedra), mapper);
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 2);
  // Back to the hexahedra: a new input for the cache.
  Render(SceneOf(grid), mapper);
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 3);
  EXPECT_TRUE(this->Observer->errors.empty());
}

} // namespace
