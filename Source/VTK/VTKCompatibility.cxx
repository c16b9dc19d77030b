// SPDX-License-Identifier: BSD-3-Clause
#include "VTKCompatibility.h"

#include "vtkCellIterator.h"
#include "vtkCellType.h"
#include "vtkCellTypes.h"
#include "vtkUnstructuredGrid.h"

#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
#include "vtkCellTypeUtilities.h"
#endif

namespace mtpt
{

const char* CellTypeName(int type)
{
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
  return vtkCellTypeUtilities::GetClassNameFromTypeId(type);
#else
  return vtkCellTypes::GetClassNameFromTypeId(type);
#endif
}

vtkIdList* PolyhedronFaces(vtkCellIterator* cell)
{
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 4, 0)
  return cell->GetSerializedCellFaces();
#else
  return cell->GetFaces();
#endif
}

bool OnlyTetrahedra(vtkUnstructuredGrid* grid)
{
  if (grid->GetNumberOfCells() == 0)
  {
    return true;
  }
  return grid->IsHomogeneous() && grid->GetCellType(0) == VTK_TETRA;
}

} // namespace mtpt
