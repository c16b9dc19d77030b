// SPDX-License-Identifier: BSD-3-Clause
#include "Input/MeshSource.h"

#include "Input/MeshAdapter.h"
#include "Input/Tetrahedralizer.h"
#include "Input/VolumeInput.h"

#include "vtkCompositeDataSet.h"
#include "vtkDataArray.h"
#include "vtkDataObjectTree.h"
#include "vtkDataObjectTreeIterator.h"
#include "vtkInformation.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace mtpt
{

/// One grid of the input and what was made of it.
struct MeshSource::Grid
{
  Tetrahedralizer Split;
  MeshAdapter Adapter;
  vtkUnstructuredGridBase* Tetrahedra = nullptr; ///< the grid, or its split, drawn
  ScalarSelection Selected;
  const float* Values = nullptr; ///< ChannelsOf(Selected) floats per point or cell of Tetrahedra
  double Range[2] = { 0, 0 };
  bool Seen = false; ///< still in the input at the last Update
};

MeshSource::MeshSource() = default;
MeshSource::~MeshSource() = default;

vtkIdType MeshSource::Tetrahedralizations() const
{
  vtkIdType count = this->RetiredTetrahedralizations;
  for (const auto& entry : this->Cache)
  {
    count += entry.second->Split.GetNumberOfTetrahedralizations();
  }
  return count;
}

std::vector<std::pair<vtkUnstructuredGridBase*, std::string>> MeshSource::Grids(
  vtkDataObject* input, std::vector<std::pair<vtkDataObject*, std::string>>* skipped)
{
  std::vector<std::pair<vtkUnstructuredGridBase*, std::string>> grids;
  if (auto* grid = vtkUnstructuredGridBase::SafeDownCast(input))
  {
    grids.emplace_back(grid, "the input");
    return grids;
  }
  auto* tree = vtkDataObjectTree::SafeDownCast(input);
  if (!tree)
  {
    return grids;
  }
  auto leaf = vtkSmartPointer<vtkDataObjectTreeIterator>::Take(tree->NewTreeIterator());
  leaf->VisitOnlyLeavesOn();
  leaf->TraverseSubTreeOn();
  leaf->SkipEmptyNodesOn();
  for (leaf->InitTraversal(); !leaf->IsDoneWithTraversal(); leaf->GoToNextItem())
  {
    std::ostringstream name;
    name << "block " << leaf->GetCurrentFlatIndex();
    if (leaf->HasCurrentMetaData() && leaf->GetCurrentMetaData()->Has(vtkCompositeDataSet::NAME()))
    {
      name << " '" << leaf->GetCurrentMetaData()->Get(vtkCompositeDataSet::NAME()) << "'";
    }
    vtkDataObject* data = leaf->GetCurrentDataObject();
    if (auto* grid = vtkUnstructuredGridBase::SafeDownCast(data))
    {
      grids.emplace_back(grid, name.str());
    }
    else if (skipped)
    {
      skipped->emplace_back(data,
        name.str() + " is a " + data->GetClassName() +
          ", not an unstructured grid; it is not drawn");
    }
  }
  return grids;
}

bool MeshSource::PrepareGrid(Grid& grid, vtkUnstructuredGridBase* input, const std::string& name,
  bool single, vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property, const Reporter& report)
{
  // A single input keeps the messages it always had; a block's name its own.
  const std::string what = single ? "the input" : name;
  if (input->GetNumberOfCells() == 0)
  {
    report(input, what + " has no cells: nothing to draw" + (single ? "" : " from it"), false);
    return false;
  }
  if (input->GetNumberOfPoints() == 0)
  {
    // Before anything visits the cells: their point ids name no point (and VTK 9.6's
    // vtkUnstructuredGrid::IsHomogeneous reads the points of a cell to answer).
    report(input, what + " has no points: nothing to draw" + (single ? "" : " from it"), single);
    return false;
  }
  // Hexahedra, wedges, pyramids... are split into tetrahedra once per input change.
  grid.Tetrahedra = grid.Split.Update(input);
  if (!grid.Split.Warning().empty())
  {
    report(input, (single ? "" : name + ": ") + grid.Split.Warning(), false);
  }
  if (grid.Tetrahedra->GetNumberOfCells() == 0)
  {
    report(input, what + " has no 3D cells: nothing to draw" + (single ? "" : " from it"), false);
    return false;
  }
  if (!grid.Adapter.Update(grid.Tetrahedra))
  {
    report(grid.Tetrahedra,
      (single ? "cannot render the input: " : "cannot render " + name + ": ") +
        grid.Adapter.Error(),
      single);
    return false;
  }
  if (!grid.Adapter.Warning().empty())
  {
    report(grid.Tetrahedra, (single ? "" : name + ": ") + grid.Adapter.Warning(), false);
  }
  grid.Selected = SelectScalars(grid.Tetrahedra, mapper, property);
  if (!grid.Selected.array)
  {
    report(grid.Tetrahedra,
      single ? grid.Selected.error : name + ": " + grid.Selected.error + "; it is not drawn",
      single && !grid.Selected.errorIsWarning);
    return false;
  }
  if (!grid.Selected.warning.empty())
  {
    report(property, grid.Selected.warning, false);
  }
  vtkIdType nonFinite = 0;
  grid.Values =
    grid.Adapter.Scalars(grid.Selected.array, grid.Selected.component, grid.Range, nonFinite);
  if (nonFinite > 0)
  {
    std::ostringstream message;
    message << (single ? "" : name + ": ") << nonFinite
            << " scalar values are NaN or infinite; the cells using them are not drawn";
    report(grid.Tetrahedra, message.str(), false);
  }
  return true;
}

bool MeshSource::Update(vtkDataObject* input, vtkAbstractVolumeMapper* mapper,
  vtkVolumeProperty* property, const Reporter& report)
{
  this->Used.clear();
  if (!input)
  {
    report(
      nullptr, "no input: connect an unstructured grid, or a composite data set of them", true);
    return false;
  }
  const bool single = vtkUnstructuredGridBase::SafeDownCast(input) != nullptr;
  std::vector<std::pair<vtkDataObject*, std::string>> skipped;
  const auto grids = Grids(input, &skipped);
  for (const auto& other : skipped)
  {
    report(other.first, other.second, false);
  }
  if (!single && !vtkDataObjectTree::SafeDownCast(input))
  {
    report(input,
      std::string("cannot render a ") + input->GetClassName() +
        ": the input must be an unstructured grid or a composite data set of them",
      true);
    return false;
  }
  this->UseGrids(grids, single, mapper, property, report);
  this->RetireUnseen();
  if (this->Used.empty())
  {
    this->Forget();
    if (!single && !grids.empty())
    {
      report(input, "no block of the composite input can be drawn", false);
    }
    else if (!single)
    {
      report(input, "the composite input has no unstructured grid: nothing to draw", false);
    }
    return false;
  }
  this->MakeViews(single);
  return true;
}

void MeshSource::UseGrids(
  const std::vector<std::pair<vtkUnstructuredGridBase*, std::string>>& grids, bool single,
  vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property, const Reporter& report)
{
  for (auto& entry : this->Cache)
  {
    entry.second->Seen = false;
  }
  bool cellData = false;
  int channels = 1;
  for (const auto& item : grids)
  {
    std::unique_ptr<Grid>& grid = this->Cache[item.first];
    if (!grid)
    {
      grid.reset(new Grid);
    }
    grid->Seen = true;
    if (!this->PrepareGrid(*grid, item.first, item.second, single, mapper, property, report))
    {
      continue;
    }
    // One association and one count of values for all: the first grid drawn decides.
    if (this->Used.empty())
    {
      cellData = grid->Selected.cellData;
      channels = ChannelsOf(grid->Selected);
    }
    else if (grid->Selected.cellData != cellData)
    {
      report(grid->Tetrahedra,
        item.second + "'s scalars are " + (grid->Selected.cellData ? "cell" : "point") +
          " data where the blocks before it have " + (cellData ? "cell" : "point") +
          " data; it is not drawn",
        false);
      continue;
    }
    else if (ChannelsOf(grid->Selected) != channels)
    {
      report(grid->Tetrahedra,
        item.second + "'s scalars have " + std::to_string(ChannelsOf(grid->Selected)) +
          " dependent components where the blocks before it have " + std::to_string(channels) +
          "; it is not drawn",
        false);
      continue;
    }
    this->Used.push_back(grid.get());
  }
}

void MeshSource::RetireUnseen()
{
  // Grids no longer in the input are forgotten (their counts kept).
  for (auto entry = this->Cache.begin(); entry != this->Cache.end();)
  {
    if (!entry->second->Seen)
    {
      this->RetiredTetrahedralizations += entry->second->Split.GetNumberOfTetrahedralizations();
      entry = this->Cache.erase(entry);
      this->Forget(); // the views may point into what was just freed
    }
    else
    {
      ++entry;
    }
  }
}

void MeshSource::MakeViews(bool single)
{
  std::vector<Key> keys;
  for (const Grid* grid : this->Used)
  {
    keys.push_back({ grid->Tetrahedra, grid->Tetrahedra->GetMTime(), grid->Selected.array,
      grid->Selected.array->GetMTime(), grid->Selected.component, grid->Selected.cellData });
  }
  if (keys == this->LastKeys && this->DataVersion > 0)
  {
    return; // the views, the gathered scalars and the range are those of last time
  }
  this->LastKeys = keys;
  ++this->DataVersion;
  const Grid& first = *this->Used.front();
  this->ScalarChannels = ChannelsOf(first.Selected);
  const auto association =
    first.Selected.cellData ? ScalarsView::Association::Cells : ScalarsView::Association::Points;
  this->ScalarRange[0] = std::numeric_limits<double>::infinity();
  this->ScalarRange[1] = -std::numeric_limits<double>::infinity();
  for (const Grid* grid : this->Used)
  {
    this->ScalarRange[0] = std::min(this->ScalarRange[0], grid->Range[0]);
    this->ScalarRange[1] = std::max(this->ScalarRange[1], grid->Range[1]);
  }
  if (single)
  {
    this->PointData = first.Adapter.Points();
    this->CellData = first.Adapter.Cells();
    this->ScalarData = { first.Values, association };
    return;
  }
  this->Parts.clear();
  for (const Grid* grid : this->Used)
  {
    this->Parts.push_back({ grid->Adapter.Points(), grid->Adapter.Cells() });
  }
  MeshParts(this->Parts.data(), this->Parts.size(), this->PointData, this->CellData);
  this->GatherScalars();
  this->ScalarData = { this->Gathered.data(), association };
}

void MeshSource::Forget()
{
  this->LastKeys.clear();
  this->PointData = PointsView{};
  this->CellData = CellsView{};
  this->ScalarData = ScalarsView{};
}

void MeshSource::GatherScalars()
{
  this->Gathered.clear();
  for (const Grid* grid : this->Used)
  {
    const std::size_t count =
      (grid->Selected.cellData ? grid->Adapter.Cells().cellCount : grid->Adapter.Points().count) *
      static_cast<std::size_t>(this->ScalarChannels);
    this->Gathered.insert(this->Gathered.end(), grid->Values, grid->Values + count);
  }
}

} // namespace mtpt
