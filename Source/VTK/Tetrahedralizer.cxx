// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMTPTTetrahedralizer.h"

#include "vtkCellData.h"
#include "vtkCellIterator.h"
#include "vtkCellType.h"
#include "vtkCellTypes.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkIdList.h"
#include "vtkPointData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"

#include <sstream>
#include <vector>

namespace mtpt
{
namespace
{
/// True if `input` is a vtkUnstructuredGrid whose cell types are all VTK_TETRA (checked
/// from its types array, without visiting any cell).
bool OnlyTetrahedra(vtkUnstructuredGridBase* input)
{
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  vtkUnsignedCharArray* types = grid ? grid->GetCellTypesArray() : nullptr;
  if (!types)
  {
    return false;
  }
  const unsigned char* type = types->GetPointer(0);
  const vtkIdType count = grid->GetNumberOfCells();
  for (vtkIdType c = 0; c < count; ++c)
  {
    if (type[c] != VTK_TETRA)
    {
      return false;
    }
  }
  return true;
}
} // namespace

vtkMTPTTetrahedralizer::vtkMTPTTetrahedralizer()
{
  // Vertices, lines and polygons enclose no volume: the filter drops them.
  this->Filter->SetTetrahedraOnly(1);
}

vtkMTPTTetrahedralizer::~vtkMTPTTetrahedralizer() = default;

vtkUnstructuredGridBase* vtkMTPTTetrahedralizer::Update(vtkUnstructuredGridBase* input)
{
  if (input == this->LastInput && input->GetMTime() == this->InputTime)
  {
    return this->Output ? this->Output.Get() : input;
  }
  this->LastInput = input;
  this->InputTime = input->GetMTime();
  this->WarningMessage.clear();
  this->Output = nullptr;
  if (OnlyTetrahedra(input))
  {
    return input; // the common case: nothing to split, nothing copied
  }

  // One pass over the cells: which are tetrahedra, which enclose no volume, which name a
  // point that does not exist (the filter reads every cell's points: those must go first).
  const vtkIdType cellCount = input->GetNumberOfCells();
  const vtkIdType pointCount = input->GetNumberOfPoints();
  vtkIdType lowerDimensional = 0, tetrahedra = 0;
  vtkIdType firstLower = -1;
  int firstLowerType = VTK_EMPTY_CELL;
  std::vector<vtkIdType> badCells;
  auto cell = vtkSmartPointer<vtkCellIterator>::Take(input->NewCellIterator());
  for (cell->InitTraversal(); !cell->IsDoneWithTraversal(); cell->GoToNextCell())
  {
    const int type = cell->GetCellType();
    tetrahedra += type == VTK_TETRA ? 1 : 0;
    if (type != VTK_EMPTY_CELL && cell->GetCellDimension() < 3)
    {
      if (lowerDimensional++ == 0)
      {
        firstLower = cell->GetCellId();
        firstLowerType = type;
      }
    }
    for (const vtkIdType id : *cell->GetPointIds())
    {
      if (id < 0 || id >= pointCount)
      {
        badCells.push_back(cell->GetCellId());
        break;
      }
    }
  }
  if (tetrahedra == cellCount)
  {
    return input; // a vtkUnstructuredGridBase of tetrahedra: the adapter reads it directly
  }

  std::ostringstream warning;
  if (lowerDimensional > 0)
  {
    warning << lowerDimensional << " of " << cellCount
            << " cells are vertices, lines or polygons (first: cell " << firstLower << ", "
            << vtkCellTypes::GetClassNameFromTypeId(firstLowerType)
            << "); they enclose no volume and are ignored";
  }
  vtkDataSet* source = input;
  vtkNew<vtkUnstructuredGrid> valid;
  if (!badCells.empty())
  {
    if (lowerDimensional > 0)
    {
      warning << "; ";
    }
    warning << badCells.size() << " cells name points outside [0, " << pointCount
            << ") (first: cell " << badCells.front() << "); they are not drawn";
    // The same grid without those cells (points and point data shared, not copied).
    valid->SetPoints(input->GetPoints());
    valid->GetPointData()->PassData(input->GetPointData());
    valid->GetCellData()->CopyAllocate(input->GetCellData(), cellCount);
    valid->Allocate(cellCount);
    std::size_t next = 0;
    for (cell->InitTraversal(); !cell->IsDoneWithTraversal(); cell->GoToNextCell())
    {
      const vtkIdType id = cell->GetCellId();
      if (next < badCells.size() && badCells[next] == id)
      {
        ++next;
        continue;
      }
      const int type = cell->GetCellType();
      const vtkIdType newId = type == VTK_POLYHEDRON
        ? valid->InsertNextCell(type, cell->GetFaces())
        : valid->InsertNextCell(type, cell->GetPointIds());
      valid->GetCellData()->CopyData(input->GetCellData(), id, newId);
    }
    source = valid;
  }
  this->WarningMessage = warning.str();

  this->Filter->SetInputData(source);
  this->Filter->Update();
  this->Output = vtkSmartPointer<vtkUnstructuredGrid>::New();
  this->Output->ShallowCopy(this->Filter->GetOutput());
  this->Filter->SetInputData(nullptr); // hold no reference to the input between updates
  ++this->Tetrahedralizations;
  return this->Output;
}

} // namespace mtpt
