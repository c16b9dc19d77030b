// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshAdapter.h
 * @brief Private glue: presents a vtkUnstructuredGridBase to mtpt_core as views, without
 * copying where VTK's storage already has the core's layout.
 *
 * Points stored as float or double (AOS) and a vtkUnstructuredGrid's vtkCellArray (32- or
 * 64-bit ids; explicit offsets, or VTK 9.6's fixed-size storage) are used in place. Other
 * storage (implicit arrays, VTK 9.6's generic cell storage, vtkUnstructuredGridBase
 * subclasses) is copied once per input change; a grid's cells copied so say so in
 * Warning(). Scalars become one float per tuple (a component or the magnitude),
 * recomputed only when the array or the selection changes.
 */
#ifndef MeshAdapter_h
#define MeshAdapter_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/MeshView.h"

#include "vtkNew.h"
#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <cstddef>
#include <string>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkCellArray;
class vtkDataArray;
class vtkDoubleArray;
class vtkUnstructuredGridBase;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class MeshAdapter
{
public:
  MeshAdapter();
  ~MeshAdapter();

  /**
   * Brings the views up to date with `input` (cheap when nothing changed). Returns false
   * with a message in Error() when the input cannot be rendered at all (no points, or
   * cells that are not tetrahedra).
   */
  bool Update(vtkUnstructuredGridBase* input);
  const std::string& Error() const { return this->ErrorMessage; }
  /// A problem that does not stop rendering (ids out of range, NaN points); empty if none.
  const std::string& Warning() const { return this->WarningMessage; }

  PointsView Points() const { return this->PointData; }
  CellsView Cells() const { return this->CellData; }

  /**
   * One float scalar per tuple of `array`: its `component`, or its magnitude when
   * component is -1 (single-component arrays: the value; a component beyond the last reads
   * the last: SelectScalars warns about it). With component AllComponents (dependent
   * components), every component of each tuple, four unsigned chars divided by 255.
   * Cached; returns the values and sets the finite range and the number of tuples with a
   * non-finite value. Recomputed when the array, its MTime, the component or the MTime of
   * the input of the last Update() changes.
   */
  const float* Scalars(vtkDataArray* array, int component, double range[2], vtkIdType& nonFinite);

private:
  MeshAdapter(const MeshAdapter&) = delete;
  void operator=(const MeshAdapter&) = delete;

  bool AdaptPoints(vtkUnstructuredGridBase* input);
  bool CheckCellTypes(vtkUnstructuredGridBase* input);
  vtkCellArray* AdaptCells(vtkUnstructuredGridBase* input);
  /// Points the cell view at `cells` in place; false when its storage is not the core's.
  bool ViewCells(vtkCellArray* cells, std::size_t cellCount);
  /// Ids out of range and non-finite points, as one warning (empty: none).
  static std::string Problems(vtkCellArray* cells, vtkDataArray* coordinates);

  PointsView PointData;
  CellsView CellData;
  std::string ErrorMessage;
  std::string WarningMessage;
  vtkMTimeType InputTime = 0;
  vtkUnstructuredGridBase* LastInput = nullptr;
  vtkSmartPointer<vtkDoubleArray> PointCopy;
  vtkSmartPointer<vtkCellArray> CellCopy;

  std::vector<float> ScalarValues;
  vtkDataArray* ScalarArray = nullptr;
  vtkMTimeType ScalarTime = 0;
  vtkMTimeType ScalarInputTime = 0; // InputTime when the values were computed
  int ScalarComponent = -2;
  double ScalarRange[2] = { 0, 0 };
  vtkIdType ScalarNonFinite = 0;
};

} // namespace mtpt

#endif
