// SPDX-License-Identifier: BSD-3-Clause
#include "Basics/VTKCompatibility.h"

#include "vtkCellIterator.h"
#include "vtkCellType.h"
#include "vtkCellTypes.h"
#include "vtkDataArray.h"
#include "vtkUnsignedCharArray.h"
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
  // The range of the types array, which VTK caches until the array changes (VTK 9.6 keeps
  // the types of a grid of one cell type as an implicit constant array).
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
  vtkDataArray* types = grid->GetCellTypes();
#else
  vtkDataArray* types = grid->GetCellTypesArray();
#endif
  if (!types || types->GetNumberOfTuples() != grid->GetNumberOfCells())
  {
    return false;
  }
  double range[2];
  types->GetRange(range, 0);
  return range[0] == VTK_TETRA && range[1] == VTK_TETRA;
}

} // namespace mtpt
