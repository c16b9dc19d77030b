// SPDX-License-Identifier: BSD-3-Clause
#include "Input/Tetrahedralizer.h"

#include "Basics/VTKCompatibility.h"

#include "vtkCellData.h"
#include "vtkCellIterator.h"
#include "vtkCellType.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkIdList.h"
#include "vtkPointData.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"

#include <sstream>
#include <vector>

namespace mtpt
{
Tetrahedralizer::Tetrahedralizer()
{
  // Vertices, lines and polygons enclose no volume: the filter drops them.
  this->Filter->SetTetrahedraOnly(1);
}

Tetrahedralizer::~Tetrahedralizer() = default;

vtkUnstructuredGridBase* Tetrahedralizer::Update(vtkUnstructuredGridBase* input)
{
  if (input == this->LastInput && input->GetMTime() == this->InputTime)
  {
    return this->Output ? this->Output.Get() : input;
  }
  this->LastInput = input;
  this->InputTime = input->GetMTime();
  this->WarningMessage.clear();
  this->Output = nullptr;
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  if (grid && OnlyTetrahedra(grid))
  {
    return input; // the common case: nothing to split, nothing copied
  }
  const Survey survey = SurveyCells(input);
  if (survey.tetrahedra == input->GetNumberOfCells())
  {
    return input; // a vtkUnstructuredGridBase of tetrahedra: the adapter reads it directly
  }
  std::ostringstream warning;
  if (survey.lowerDimensional > 0)
  {
    warning << survey.lowerDimensional << " of " << input->GetNumberOfCells()
            << " cells are vertices, lines or polygons (first: cell " << survey.firstLower << ", "
            << CellTypeName(survey.firstLowerType)
            << "); they enclose no volume and are ignored";
  }
  vtkSmartPointer<vtkUnstructuredGrid> valid;
  if (!survey.badCells.empty())
  {
    warning << (survey.lowerDimensional > 0 ? "; " : "") << survey.badCells.size()
            << " cells name points outside [0, " << input->GetNumberOfPoints() << ") (first: cell "
            << survey.badCells.front() << "); they are not drawn";
    valid = WithoutCells(input, survey.badCells);
  }
  this->WarningMessage = warning.str();
  this->Filter->SetInputData(valid ? static_cast<vtkDataSet*>(valid) : input);
  this->Filter->Update();
  this->Output = vtkSmartPointer<vtkUnstructuredGrid>::New();
  this->Output->ShallowCopy(this->Filter->GetOutput());
  this->Filter->SetInputData(nullptr); // hold no reference to the input between updates
  ++this->Tetrahedralizations;
  return this->Output;
}

Tetrahedralizer::Survey Tetrahedralizer::SurveyCells(vtkUnstructuredGridBase* input)
{
  // One pass over the cells: which are tetrahedra, which enclose no volume, which name a
  // point that does not exist (the filter reads every cell's points: those must go first).
  Survey survey;
  const vtkIdType pointCount = input->GetNumberOfPoints();
  auto cell = vtkSmartPointer<vtkCellIterator>::Take(input->NewCellIterator());
  for (cell->InitTraversal(); !cell->IsDoneWithTraversal(); cell->GoToNextCell())
  {
    const int type = cell->GetCellType();
    survey.tetrahedra += type == VTK_TETRA ? 1 : 0;
    if (type != VTK_EMPTY_CELL && cell->GetCellDimension() < 3 && survey.lowerDimensional++ == 0)
    {
      survey.firstLower = cell->GetCellId();
      survey.firstLowerType = type;
    }
    for (const vtkIdType id : *cell->GetPointIds())
    {
      if (id < 0 || id >= pointCount)
      {
        survey.badCells.push_back(cell->GetCellId());
        break;
      }
    }
  }
  return survey;
}

vtkSmartPointer<vtkUnstructuredGrid> Tetrahedralizer::WithoutCells(
  vtkUnstructuredGridBase* input, const std::vector<vtkIdType>& cells)
{
  // The same grid without those cells (points and point data shared, not copied).
  const vtkIdType cellCount = input->GetNumberOfCells();
  auto valid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  valid->SetPoints(input->GetPoints());
  valid->GetPointData()->PassData(input->GetPointData());
  valid->GetCellData()->CopyAllocate(input->GetCellData(), cellCount);
  valid->Allocate(cellCount);
  std::size_t next = 0;
  auto cell = vtkSmartPointer<vtkCellIterator>::Take(input->NewCellIterator());
  for (cell->InitTraversal(); !cell->IsDoneWithTraversal(); cell->GoToNextCell())
  {
    const vtkIdType id = cell->GetCellId();
    if (next < cells.size() && cells[next] == id)
    {
      ++next;
      continue;
    }
    const int type = cell->GetCellType();
    const vtkIdType newId = type == VTK_POLYHEDRON
      ? valid->InsertNextCell(type, PolyhedronFaces(cell))
      : valid->InsertNextCell(type, cell->GetPointIds());
    valid->GetCellData()->CopyData(input->GetCellData(), id, newId);
  }
  return valid;
}

} // namespace mtpt
