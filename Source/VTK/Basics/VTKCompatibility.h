// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file VTKCompatibility.h
 * @brief Private glue: the parts of VTK's cell API that changed between VTK 9.1 and the
 * current release, behind one name each (see Documentation/vtk-versions.md).
 */
#ifndef mtpt_VTKCompatibility_h
#define mtpt_VTKCompatibility_h

#include "vtkMTPTVTKCompatibility.h"

VTK_ABI_NAMESPACE_BEGIN
class vtkCellIterator;
class vtkIdList;
class vtkUnstructuredGrid;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

/// VTK's class name of a cell type ("vtkTetra"); vtkCellTypeUtilities from VTK 9.6 on.
const char* CellTypeName(int type);

/// The face stream of the polyhedron at the iterator (number of faces, then per face its
/// point count and ids), as vtkUnstructuredGrid::InsertNextCell takes it.
vtkIdList* PolyhedronFaces(vtkCellIterator* cell);

/// Whether every cell of `grid` is a tetrahedron (true for no cells), from the grid's own
/// list of distinct cell types, without visiting the cells.
bool OnlyTetrahedra(vtkUnstructuredGrid* grid);

} // namespace mtpt

#endif
