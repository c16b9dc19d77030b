// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Tetrahedralizer.h
 * @brief Private glue: turns any unstructured grid into the tetrahedra the mapper draws,
 * once per input change.
 *
 * A grid of tetrahedra only is passed through untouched (no copy). Any other grid
 * (hexahedra, voxels, wedges, pyramids, polyhedra, higher-order or mixed cells) is split
 * into tetrahedra by vtkDataSetTriangleFilter, which adds no points: point data is passed
 * as it is and cell data is copied from each cell to every tetrahedron made from it. The
 * result is kept until the input or its modification time changes (any change of the grid,
 * its points or its data arrays), so an unchanged input is never split again.
 *
 * What cannot be drawn is left out, with one message per input change: cells of
 * dimension below 3 (vertices, lines, polygons: they enclose no volume) and, for grids that
 * need splitting, cells naming a point id outside the point array (vtkDataSetTriangleFilter
 * would read past the points). Tetrahedra with such ids are left to MeshAdapter,
 * which reports them and whose core skips them.
 */
#ifndef Tetrahedralizer_h
#define Tetrahedralizer_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkNew.h"
#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <string>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkDataSetTriangleFilter;
class vtkUnstructuredGrid;
class vtkUnstructuredGridBase;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class Tetrahedralizer
{
public:
  Tetrahedralizer();
  ~Tetrahedralizer();

  /**
   * The grid to draw for `input`: `input` itself when all its cells are tetrahedra,
   * otherwise its tetrahedralization (cached: redone only when `input` or its MTime
   * changes). Never null for a non-null input; it may have no cells.
   */
  vtkUnstructuredGridBase* Update(vtkUnstructuredGridBase* input);

  /// Cells of the last input that are not drawn and why; empty if every cell is drawn.
  const std::string& Warning() const { return this->WarningMessage; }

  /// How many times an input was split into tetrahedra (the cache missed).
  vtkIdType GetNumberOfTetrahedralizations() const { return this->Tetrahedralizations; }

private:
  Tetrahedralizer(const Tetrahedralizer&) = delete;
  void operator=(const Tetrahedralizer&) = delete;

  /// What one pass over a grid's cells finds.
  struct Survey
  {
    vtkIdType tetrahedra = 0;
    vtkIdType lowerDimensional = 0; ///< vertices, lines, polygons
    vtkIdType firstLower = -1;
    int firstLowerType = 0;
    std::vector<vtkIdType> badCells; ///< cells naming a point id out of range, ascending
  };
  static Survey SurveyCells(vtkUnstructuredGridBase* input);
  /// `input` without `cells` (ascending ids), sharing its points and point data.
  static vtkSmartPointer<vtkUnstructuredGrid> WithoutCells(
    vtkUnstructuredGridBase* input, const std::vector<vtkIdType>& cells);

  vtkNew<vtkDataSetTriangleFilter> Filter;
  vtkSmartPointer<vtkUnstructuredGrid> Output; // null when the input is passed through
  vtkUnstructuredGridBase* LastInput = nullptr;
  vtkMTimeType InputTime = 0;
  std::string WarningMessage;
  vtkIdType Tetrahedralizations = 0;
};

} // namespace mtpt

#endif
