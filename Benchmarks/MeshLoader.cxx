// SPDX-License-Identifier: BSD-3-Clause
#include "MeshLoader.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellDataToPointData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkDataArrayRange.h>
#include <vtkDataSet.h>
#include <vtkDataSetReader.h>
#include <vtkDataSetTriangleFilter.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <cstring>

namespace mtpt
{
namespace bench
{

namespace
{

bool EndsWith(const std::string& text, const std::string& suffix)
{
  return text.size() >= suffix.size() &&
    text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

vtkSmartPointer<vtkDataSet> ReadDataSet(const std::string& fileName, std::string& error)
{
  vtkSmartPointer<vtkDataSet> output;
  if (EndsWith(fileName, ".vtu"))
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    if (!reader->CanReadFile(fileName.c_str()))
    {
      error = "not a readable VTK XML unstructured grid: " + fileName;
      return nullptr;
    }
    reader->SetFileName(fileName.c_str());
    reader->Update();
    output = reader->GetOutput();
  }
  else if (EndsWith(fileName, ".vtk"))
  {
    vtkNew<vtkDataSetReader> reader;
    reader->SetFileName(fileName.c_str());
    reader->Update();
    output = reader->GetOutput();
  }
  else
  {
    error = "unknown file extension (expected .vtu or .vtk): " + fileName;
    return nullptr;
  }
  if (!output || output->GetNumberOfPoints() == 0 || output->GetNumberOfCells() == 0)
  {
    error = "no points or no cells read from " + fileName;
    return nullptr;
  }
  return output;
}

// The array to shade with and where it lives (see LoadTetMesh's rules).
struct ScalarChoice
{
  vtkDataArray* array = nullptr;
  bool cellData = false;
};

ScalarChoice ChooseScalars(vtkDataSet* data, const std::string& scalarName)
{
  vtkPointData* pointData = data->GetPointData();
  vtkCellData* cellData = data->GetCellData();
  if (!scalarName.empty())
  {
    if (vtkDataArray* array = pointData->GetArray(scalarName.c_str()))
    {
      return { array, false };
    }
    if (vtkDataArray* array = cellData->GetArray(scalarName.c_str()))
    {
      return { array, true };
    }
    return {};
  }
  if (vtkDataArray* array = pointData->GetScalars())
  {
    return { array, false };
  }
  if (vtkDataArray* array = cellData->GetScalars())
  {
    return { array, true };
  }
  // GetArray(i) skips string and other non-numeric arrays by returning null.
  for (int i = 0; i < pointData->GetNumberOfArrays(); ++i)
  {
    if (vtkDataArray* array = pointData->GetArray(i))
    {
      return { array, false };
    }
  }
  for (int i = 0; i < cellData->GetNumberOfArrays(); ++i)
  {
    if (vtkDataArray* array = cellData->GetArray(i))
    {
      return { array, true };
    }
  }
  return {};
}

bool AllTetrahedra(vtkDataSet* data)
{
  auto* grid = vtkUnstructuredGrid::SafeDownCast(data);
  if (!grid)
  {
    return false;
  }
  const vtkIdType cells = grid->GetNumberOfCells();
  for (vtkIdType c = 0; c < cells; ++c)
  {
    if (grid->GetCellType(c) != VTK_TETRA)
    {
      return false;
    }
  }
  return true;
}

/// The ids of any of vtkCellArray's storages (32 or 64 bits, explicit or implicit).
void CopyIds(vtkDataArray* array, std::vector<std::int64_t>& out)
{
  out.clear();
  out.reserve(static_cast<std::size_t>(array->GetNumberOfValues()));
  for (const auto id : vtk::DataArrayValueRange<1>(array))
  {
    out.push_back(static_cast<std::int64_t>(id));
  }
}

} // namespace

bool LoadTetMesh(
  const std::string& fileName, const std::string& scalarName, TetMesh& mesh, std::string& error)
{
  vtkSmartPointer<vtkDataSet> data = ReadDataSet(fileName, error);
  if (!data)
  {
    return false;
  }

  const ScalarChoice choice = ChooseScalars(data, scalarName);
  if (!choice.array)
  {
    error = scalarName.empty() ? "no numeric array in " + fileName
                               : "no array named \"" + scalarName + "\" in " + fileName;
    return false;
  }
  // Keep the name: the array object itself does not survive the filters below.
  const std::string arrayName = choice.array->GetName() ? choice.array->GetName() : "";
  if (arrayName.empty())
  {
    error = "the scalar array of " + fileName + " has no name";
    return false;
  }

  if (choice.cellData)
  {
    vtkNew<vtkCellDataToPointData> toPoints;
    toPoints->SetInputData(data);
    toPoints->ProcessAllArraysOff();
    toPoints->AddCellDataArray(arrayName.c_str());
    toPoints->PassCellDataOff();
    toPoints->Update();
    data = toPoints->GetOutput();
  }

  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (AllTetrahedra(data))
  {
    grid = vtkUnstructuredGrid::SafeDownCast(data);
  }
  else
  {
    vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
    tetrahedralize->SetInputData(data);
    tetrahedralize->TetrahedraOnlyOn();
    tetrahedralize->Update();
    grid = tetrahedralize->GetOutput();
  }
  if (!grid || grid->GetNumberOfCells() == 0 || !grid->GetPoints())
  {
    error = "no tetrahedra in " + fileName;
    return false;
  }

  vtkDataArray* values = grid->GetPointData()->GetArray(arrayName.c_str());
  if (!values)
  {
    error = "array \"" + arrayName + "\" lost while tetrahedralizing " + fileName;
    return false;
  }

  const vtkIdType pointCount = grid->GetNumberOfPoints();
  mesh = TetMesh();
  mesh.scalarName = arrayName;
  mesh.points.resize(3 * static_cast<std::size_t>(pointCount));
  auto* floatPoints = vtkFloatArray::SafeDownCast(grid->GetPoints()->GetData());
  if (floatPoints && floatPoints->GetNumberOfComponents() == 3)
  {
    std::memcpy(mesh.points.data(), floatPoints->GetPointer(0), mesh.points.size() * sizeof(float));
  }
  else
  {
    for (vtkIdType i = 0; i < pointCount; ++i)
    {
      double p[3];
      grid->GetPoint(i, p);
      for (int a = 0; a < 3; ++a)
      {
        mesh.points[3 * static_cast<std::size_t>(i) + a] = static_cast<float>(p[a]);
      }
    }
  }

  mesh.scalars.resize(static_cast<std::size_t>(pointCount));
  const int components = values->GetNumberOfComponents();
  std::vector<double> tuple(static_cast<std::size_t>(components));
  for (vtkIdType i = 0; i < pointCount; ++i)
  {
    values->GetTuple(i, tuple.data());
    double value = tuple[0];
    if (components > 1)
    {
      double sum = 0;
      for (double component : tuple)
      {
        sum += component * component;
      }
      value = std::sqrt(sum);
    }
    mesh.scalars[static_cast<std::size_t>(i)] = static_cast<float>(value);
  }

  vtkCellArray* cells = grid->GetCells();
  CopyIds(cells->GetOffsetsArray(), mesh.offsets);
  CopyIds(cells->GetConnectivityArray(), mesh.connectivity);
  // The triangle filter's TetrahedraOnly and the all-tetrahedra check above should leave
  // nothing else; check anyway, since a stray cell would skew every rate in the table.
  for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
  {
    if (mesh.offsets[c + 1] - mesh.offsets[c] != 4)
    {
      error = "cell " + std::to_string(c) + " of " + fileName + " is not a tetrahedron";
      return false;
    }
  }
  return true;
}

const std::vector<DataSetEntry>& SharedDataSets()
{
  static const std::vector<DataSetEntry> entries = {
    { "fire_ug", "fire_ug/fire_ug.vtu", "t" },
    { "pulley", "pulley/pulley.vtu", "f_16" },
    { "bluntfin", "bluntfin/bluntfin_tets.vtu", "Density" },
    { "comb", "comb/comb_tets.vtu", "Density" },
    { "kiefer", "kiefer/kiefer.vtu", "" },
    { "ironProt", "ironProt/ironProt.vtk", "" },
  };
  return entries;
}

vtkSmartPointer<vtkUnstructuredGrid> ToUnstructuredGrid(const TetMesh& mesh)
{
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkFloatArray> xyz;
  xyz->SetNumberOfComponents(3);
  xyz->SetArray(const_cast<float*>(mesh.points.data()), static_cast<vtkIdType>(mesh.points.size()),
    1); // the mesh outlives the grid
  vtkNew<vtkPoints> points;
  points->SetData(xyz);
  grid->SetPoints(points);
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetArray(const_cast<vtkIdType*>(reinterpret_cast<const vtkIdType*>(mesh.offsets.data())),
    static_cast<vtkIdType>(mesh.offsets.size()), 1);
  connectivity->SetArray(
    const_cast<vtkIdType*>(reinterpret_cast<const vtkIdType*>(mesh.connectivity.data())),
    static_cast<vtkIdType>(mesh.connectivity.size()), 1);
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  grid->SetCells(VTK_TETRA, cells);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("scalars");
  scalars->SetArray(
    const_cast<float*>(mesh.scalars.data()), static_cast<vtkIdType>(mesh.scalars.size()), 1);
  grid->GetPointData()->SetScalars(scalars);
  return grid;
}

} // namespace bench
} // namespace mtpt
