// SPDX-License-Identifier: BSD-3-Clause
#include "Input/MeshAdapter.h"

#include "Basics/VTKCompatibility.h"
#include "Input/VolumeInput.h"

#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkDataArrayRange.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPoints.h"
#include "vtkAOSDataArrayTemplate.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace mtpt
{

MeshAdapter::MeshAdapter() = default;
MeshAdapter::~MeshAdapter() = default;

bool MeshAdapter::Update(vtkUnstructuredGridBase* input)
{
  if (input == this->LastInput && input->GetMTime() == this->InputTime)
  {
    return this->ErrorMessage.empty(); // unchanged: the same verdict, no rescan
  }
  this->LastInput = input;
  this->InputTime = input->GetMTime();
  this->ErrorMessage.clear();
  this->WarningMessage.clear();
  this->PointData = PointsView{};
  this->CellData = CellsView{};
  if (!this->AdaptPoints(input) || !this->CheckCellTypes(input))
  {
    return false;
  }
  vtkCellArray* cells = this->AdaptCells(input); // may say that it copied them
  const std::string problems = this->Problems(cells, input->GetPoints()->GetData());
  if (!problems.empty())
  {
    this->WarningMessage += (this->WarningMessage.empty() ? "" : "; ") + problems;
  }
  return true;
}

bool MeshAdapter::AdaptPoints(vtkUnstructuredGridBase* input)
{
  // Float or double arrays in VTK's interleaved layout are used in place.
  vtkPoints* points = input->GetPoints();
  if (!points || points->GetNumberOfPoints() == 0)
  {
    this->ErrorMessage = "the input has no points";
    return false;
  }
  vtkDataArray* coordinates = points->GetData();
  const auto pointCount = static_cast<std::size_t>(points->GetNumberOfPoints());
  if (auto* f = vtkFloatArray::FastDownCast(coordinates))
  {
    this->PointData = PointsView::FromFloat(f->GetPointer(0), pointCount);
  }
  else if (auto* d = vtkDoubleArray::FastDownCast(coordinates))
  {
    this->PointData = PointsView::FromDouble(d->GetPointer(0), pointCount);
  }
  else
  {
    this->PointCopy = vtkSmartPointer<vtkDoubleArray>::New();
    this->PointCopy->DeepCopy(coordinates);
    this->PointData = PointsView::FromDouble(this->PointCopy->GetPointer(0), pointCount);
  }
  return true;
}

bool MeshAdapter::CheckCellTypes(vtkUnstructuredGridBase* input)
{
  // Every cell must be a tetrahedron (the mapper splits other cells first: see
  // Tetrahedralizer; this guards the core against anything else).
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  if (grid && OnlyTetrahedra(grid))
  {
    return true;
  }
  const vtkIdType cellCount = input->GetNumberOfCells();
  vtkIdType nonTetrahedra = 0, firstBad = -1;
  int firstBadType = VTK_EMPTY_CELL;
  for (vtkIdType c = 0; c < cellCount; ++c)
  {
    const int type = input->GetCellType(c);
    if (type != VTK_TETRA && nonTetrahedra++ == 0)
    {
      firstBad = c;
      firstBadType = type;
    }
  }
  if (nonTetrahedra == 0)
  {
    return true;
  }
  std::ostringstream message;
  message << nonTetrahedra << " of " << cellCount << " cells are not tetrahedra (first: cell "
          << firstBad << ", " << CellTypeName(firstBadType)
          << "); tetrahedralize the input first, e.g. with vtkDataSetTriangleFilter";
  this->ErrorMessage = message.str();
  return false;
}

namespace
{
using Ids32 = vtkAOSDataArrayTemplate<vtkTypeInt32>;
using Ids64 = vtkAOSDataArrayTemplate<vtkTypeInt64>;

/// The points per cell of a fixed-size storage (VTK 9.6: the offsets are implicit), or 0
/// where the storage has explicit offsets or there is none.
vtkIdType FixedCellSize(vtkCellArray* cells)
{
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
  if (cells->IsStorageFixedSize() && cells->GetNumberOfCells() > 0)
  {
    return cells->GetCellSize(0);
  }
#else
  (void)cells;
#endif
  return 0;
}
} // namespace

bool MeshAdapter::ViewCells(vtkCellArray* cells, std::size_t cellCount)
{
  // vtkTypeInt64 is long long, std::int64_t may be long: same size and representation.
  static_assert(sizeof(vtkTypeInt64) == sizeof(std::int64_t), "64-bit ids");
  static_assert(sizeof(vtkTypeInt32) == sizeof(std::int32_t), "32-bit ids");
  vtkDataArray* connectivity = cells->GetConnectivityArray();
  vtkDataArray* offsets = cells->GetOffsetsArray();
  auto* c64 = Ids64::FastDownCast(connectivity);
  auto* c32 = Ids32::FastDownCast(connectivity);
  auto* o64 = Ids64::FastDownCast(offsets);
  auto* o32 = Ids32::FastDownCast(offsets);
  if (c64 && o64)
  {
    this->CellData = CellsView::FromInt64(reinterpret_cast<const std::int64_t*>(c64->GetPointer(0)),
      reinterpret_cast<const std::int64_t*>(o64->GetPointer(0)), cellCount);
    return true;
  }
  if (c32 && o32)
  {
    this->CellData = CellsView::FromInt32(reinterpret_cast<const std::int32_t*>(c32->GetPointer(0)),
      reinterpret_cast<const std::int32_t*>(o32->GetPointer(0)), cellCount);
    return true;
  }
  const vtkIdType size = FixedCellSize(cells);
  if (size > 0 && (c64 || c32))
  {
    this->CellData = c64
      ? CellsView::FromFixedSizeInt64(
          reinterpret_cast<const std::int64_t*>(c64->GetPointer(0)), size, cellCount)
      : CellsView::FromFixedSizeInt32(
          reinterpret_cast<const std::int32_t*>(c32->GetPointer(0)), size, cellCount);
    return true;
  }
  return false;
}

vtkCellArray* MeshAdapter::AdaptCells(vtkUnstructuredGridBase* input)
{
  // A vtkUnstructuredGrid's own vtkCellArray is used in place when its storage has the
  // core's layout (32- or 64-bit ids, explicit offsets or VTK 9.6's fixed-size cells). Any
  // other storage, and any other vtkUnstructuredGridBase, is copied through VTK's cell
  // interface into a 64-bit vtkCellArray once per input change.
  const vtkIdType cellCount = input->GetNumberOfCells();
  auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
  vtkCellArray* own = grid ? grid->GetCells() : nullptr;
  if (own && this->ViewCells(own, static_cast<std::size_t>(cellCount)))
  {
    return own;
  }
  this->CellCopy = vtkSmartPointer<vtkCellArray>::New();
  this->CellCopy->Use64BitStorage();
  this->CellCopy->AllocateEstimate(cellCount, 4);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < cellCount; ++c)
  {
    input->GetCellPoints(c, ids);
    this->CellCopy->InsertNextCell(ids);
  }
  if (own)
  {
    // Said once per input change, with the mapper's other warnings about the input.
    std::ostringstream note;
    note << "the input's cells are stored as " << own->GetOffsetsArray()->GetClassName()
         << " offsets and " << own->GetConnectivityArray()->GetClassName()
         << " connectivity, which the mapper cannot read in place; they are copied ("
         << (this->CellCopy->GetActualMemorySize() + 1023) / 1024
         << " MiB) at every change of the input";
    this->WarningMessage = note.str();
  }
  this->ViewCells(this->CellCopy, static_cast<std::size_t>(cellCount));
  return this->CellCopy;
}

std::string MeshAdapter::Problems(vtkCellArray* cells, vtkDataArray* coordinates)
{
  // Point ids out of range: the core skips those cells.
  vtkIdType outOfRange = 0;
  const vtkIdType pointIds = coordinates->GetNumberOfTuples();
  for (const auto id : vtk::DataArrayValueRange<1>(cells->GetConnectivityArray()))
  {
    outOfRange += (id < 0 || id >= pointIds) ? 1 : 0;
  }
  // Points with a NaN or infinite coordinate: the core skips the cells using them.
  vtkIdType nonFinitePoints = 0;
  for (const auto point : vtk::DataArrayTupleRange<3>(coordinates))
  {
    nonFinitePoints +=
      std::isfinite(point[0]) && std::isfinite(point[1]) && std::isfinite(point[2]) ? 0 : 1;
  }
  std::ostringstream message;
  if (outOfRange > 0)
  {
    message << outOfRange << " connectivity entries name points outside [0, " << pointIds
            << "); the cells using them are not drawn";
  }
  if (nonFinitePoints > 0)
  {
    message << (outOfRange > 0 ? "; " : "") << nonFinitePoints << " of " << pointIds
            << " points have NaN or infinite coordinates; the cells using them are not drawn";
  }
  return message.str();
}

namespace
{

/// The finite range of the values written and the count of tuples with a non-finite one.
struct ValueRange
{
  double low = std::numeric_limits<double>::infinity(), high = -low;
  vtkIdType bad = 0;
  void Add(double v, float f)
  {
    if (std::isfinite(f))
    {
      low = v < low ? v : low;
      high = v > high ? v : high;
    }
  }
};

/// One float per tuple: component `component`, or the magnitude when it is negative.
void OneScalarPerTuple(vtkDataArray* array, int component, float* out, ValueRange& range)
{
  const int components = array->GetNumberOfComponents();
  std::size_t t = 0;
  for (const auto tuple : vtk::DataArrayTupleRange(array))
  {
    double v = 0;
    if (component >= 0)
    {
      v = tuple[component];
    }
    else
    {
      for (int k = 0; k < components; ++k)
      {
        v += static_cast<double>(tuple[k]) * tuple[k];
      }
      v = std::sqrt(v);
    }
    const auto f = static_cast<float>(v);
    out[t++] = f;
    range.Add(v, f);
    range.bad += std::isfinite(f) ? 0 : 1;
  }
}

/// Dependent components: every component of each tuple, times `unit`.
void EveryComponent(vtkDataArray* array, double unit, float* out, ValueRange& range)
{
  const int components = array->GetNumberOfComponents();
  std::size_t t = 0;
  for (const auto tuple : vtk::DataArrayTupleRange(array))
  {
    bool finite = true;
    for (int k = 0; k < components; ++k)
    {
      const auto f = static_cast<float>(tuple[k] * unit);
      out[t * components + k] = f;
      finite = finite && std::isfinite(f);
      if (finite)
      {
        range.Add(f, f);
      }
    }
    range.bad += finite ? 0 : 1;
    ++t;
  }
}

} // namespace

const float* MeshAdapter::Scalars(
  vtkDataArray* array, int component, double range[2], vtkIdType& nonFinite)
{
  const int components = array->GetNumberOfComponents();
  const bool all = component == AllComponents;
  if (components == 1 && !all)
  {
    component = 0;
  }
  else if (component >= components)
  {
    component = components - 1;
  }
  // Values changed in place with only the grid marked Modified() count as a change too.
  if (array != this->ScalarArray || array->GetMTime() != this->ScalarTime ||
    component != this->ScalarComponent || this->InputTime != this->ScalarInputTime)
  {
    this->ScalarArray = array;
    this->ScalarTime = array->GetMTime();
    this->ScalarInputTime = this->InputTime;
    this->ScalarComponent = component;
    const auto tuples = static_cast<std::size_t>(array->GetNumberOfTuples());
    ValueRange values;
    if (all)
    {
      // Four unsigned chars are a colour in 0-255 (VTK's PT uses them as they are, the
      // other types as values in [0, 1]).
      const double unit =
        components == 4 && array->GetDataType() == VTK_UNSIGNED_CHAR ? 1.0 / 255.0 : 1.0;
      this->ScalarValues.resize(tuples * components);
      EveryComponent(array, unit, this->ScalarValues.data(), values);
    }
    else
    {
      this->ScalarValues.resize(tuples);
      OneScalarPerTuple(array, component, this->ScalarValues.data(), values);
    }
    if (!(values.low <= values.high))
    {
      values.low = values.high = 0;
    }
    this->ScalarRange[0] = values.low;
    this->ScalarRange[1] = values.high;
    this->ScalarNonFinite = values.bad;
  }
  range[0] = this->ScalarRange[0];
  range[1] = this->ScalarRange[1];
  nonFinite = this->ScalarNonFinite;
  return this->ScalarValues.data();
}

} // namespace mtpt
