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
  vtkVolumeProperty* Property = nullptr; ///< of the volume it is drawn for
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
  return this->Update(
    std::vector<GroupedVolume>{ GroupedVolume{ input, mapper, property } }, report);
}

bool MeshSource::Update(const std::vector<GroupedVolume>& volumes, const Reporter& report)
{
  this->Used.clear();
  this->UsedSegments.clear();
  this->UsedMatrices.clear();
  for (auto& entry : this->Cache)
  {
    entry.second->Seen = false;
  }
  const bool several = volumes.size() > 1;
  bool single = false;
  std::vector<vtkVolumeProperty*> properties; // one segment each, in order of first use
  for (std::size_t v = 0; v < volumes.size(); ++v)
  {
    const GroupedVolume& volume = volumes[v];
    // A volume of several is named by its place in the renderer's group.
    const std::string prefix = several ? "volume " + std::to_string(v + 1) + ": " : "";
    vtkDataObject* input = volume.input;
    if (!input)
    {
      report(nullptr,
        prefix + "no input: connect an unstructured grid, or a composite data set of them",
        !several);
      continue;
    }
    const bool grid = vtkUnstructuredGridBase::SafeDownCast(input) != nullptr;
    single = !several && grid;
    if (!grid && !vtkDataObjectTree::SafeDownCast(input))
    {
      report(input,
        prefix + "cannot render a " + input->GetClassName() +
          ": the input must be an unstructured grid or a composite data set of them",
        !several);
      continue;
    }
    std::vector<std::pair<vtkDataObject*, std::string>> skipped;
    auto grids = Grids(input, &skipped);
    for (const auto& other : skipped)
    {
      report(other.first, prefix + other.second, false);
    }
    if (several && grid)
    {
      grids[0].second = "its input";
    }
    const auto found = std::find(properties.begin(), properties.end(), volume.property);
    const std::size_t before = this->Used.size();
    this->UseGrids(
      grids, single, volume, static_cast<int>(found - properties.begin()), prefix, report);
    if (this->Used.size() > before && found == properties.end())
    {
      properties.push_back(volume.property);
    }
    if (!grid && this->Used.size() == before)
    {
      report(input,
        prefix +
          (grids.empty() ? "the composite input has no unstructured grid: nothing to draw"
                         : "no block of the composite input can be drawn"),
        false);
    }
  }
  this->RetireUnseen();
  if (this->Used.empty())
  {
    this->Forget();
    return false;
  }
  this->MakeViews(single);
  this->PlaceParts();
  return true;
}

void MeshSource::PlaceParts()
{
  if (this->Parts.size() != this->Used.size())
  {
    return; // a single grid: no parts
  }
  // Models is sized with the parts (MakeViews) and rewritten in place: the parts point into it.
  bool changed = false;
  for (std::size_t k = 0; k < this->Parts.size(); ++k)
  {
    const double* matrix = this->UsedMatrices[k];
    Matrix4 model = IdentityMatrix();
    if (matrix)
    {
      std::copy_n(matrix, 16, model.begin());
    }
    if (model != this->Models[k] || static_cast<bool>(matrix) != this->Placed[k])
    {
      this->Models[k] = model;
      this->Placed[k] = matrix != nullptr;
      changed = true;
    }
    this->Parts[k].model = matrix ? &this->Models[k] : nullptr;
  }
  if (changed)
  {
    ++this->Placement;
  }
}

void MeshSource::UseGrids(
  const std::vector<std::pair<vtkUnstructuredGridBase*, std::string>>& grids, bool single,
  const GroupedVolume& volume, int segment, const std::string& prefix, const Reporter& report)
{
  for (const auto& item : grids)
  {
    std::unique_ptr<Grid>& grid =
      this->Cache[GridKey{ item.first, volume.mapper, volume.property }];
    if (!grid)
    {
      grid.reset(new Grid);
      grid->Property = volume.property;
    }
    grid->Seen = true;
    const std::string name = prefix + item.second;
    if (!this->PrepareGrid(*grid, item.first, name, single, volume.mapper, volume.property, report))
    {
      continue;
    }
    // One association and one count of values for all: the first grid drawn decides.
    if (!this->Used.empty())
    {
      const ScalarSelection& first = this->Used.front()->Selected;
      if (grid->Selected.cellData != first.cellData)
      {
        report(grid->Tetrahedra,
          name + "'s scalars are " + (grid->Selected.cellData ? "cell" : "point") +
            " data where the blocks before it have " + (first.cellData ? "cell" : "point") +
            " data; it is not drawn",
          false);
        continue;
      }
      if (ChannelsOf(grid->Selected) != ChannelsOf(first))
      {
        report(grid->Tetrahedra,
          name + "'s scalars have " + std::to_string(ChannelsOf(grid->Selected)) +
            " dependent components where the blocks before it have " +
            std::to_string(ChannelsOf(first)) + "; it is not drawn",
          false);
        continue;
      }
    }
    this->Used.push_back(grid.get());
    this->UsedSegments.push_back(segment);
    this->UsedMatrices.push_back(volume.matrix);
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
  for (std::size_t g = 0; g < this->Used.size(); ++g)
  {
    const Grid* grid = this->Used[g];
    keys.push_back({ grid->Tetrahedra, grid->Tetrahedra->GetMTime(), grid->Selected.array,
      grid->Selected.array->GetMTime(), grid->Selected.component, grid->Selected.cellData,
      this->UsedSegments[g] });
  }
  if (keys == this->LastKeys && this->DataVersion > 0)
  {
    return; // the views, the gathered scalars and the ranges are those of last time
  }
  this->LastKeys = keys;
  ++this->DataVersion;
  this->Mapped = false;
  const Grid& first = *this->Used.front();
  this->ScalarChannels = ChannelsOf(first.Selected);
  const auto association =
    first.Selected.cellData ? ScalarsView::Association::Cells : ScalarsView::Association::Points;
  const double inf = std::numeric_limits<double>::infinity();
  this->SegmentData.clear();
  for (std::size_t g = 0; g < this->Used.size(); ++g)
  {
    const Grid* grid = this->Used[g];
    const auto segment = static_cast<std::size_t>(this->UsedSegments[g]);
    if (segment >= this->SegmentData.size())
    {
      this->SegmentData.resize(segment + 1, Segment{ nullptr, { inf, -inf } });
      this->SegmentData[segment].property = this->Used[g]->Property;
    }
    double* range = this->SegmentData[segment].range;
    range[0] = std::min(range[0], grid->Range[0]);
    range[1] = std::max(range[1], grid->Range[1]);
  }
  if (single)
  {
    this->Parts.clear();
    this->Models.clear();
    this->Placed.clear();
    this->PointData = first.Adapter.Points();
    this->CellData = first.Adapter.Cells();
    this->ScalarData = { first.Values, association };
    return;
  }
  this->Parts.clear();
  for (const Grid* grid : this->Used)
  {
    this->Parts.push_back({ grid->Adapter.Points(), grid->Adapter.Cells(), nullptr });
  }
  this->Models.assign(this->Parts.size(), IdentityMatrix());
  this->Placed.assign(this->Parts.size(), false);
  ++this->Placement;
  MeshParts(this->Parts.data(), this->Parts.size(), this->PointData, this->CellData);
  this->GatherScalars();
  this->ScalarData = { this->Gathered.data(), association };
}

void MeshSource::MapToSegments(const std::function<double(int segment, double scalar)>& entry)
{
  if (this->SegmentData.size() <= 1 || this->ScalarChannels != 1 || this->Mapped)
  {
    return;
  }
  // Each grid's scalars into its segment: the gathered copy is rewritten in place.
  float* value = this->Gathered.data();
  for (std::size_t g = 0; g < this->Used.size(); ++g)
  {
    const Grid* grid = this->Used[g];
    const std::size_t count =
      grid->Selected.cellData ? grid->Adapter.Cells().cellCount : grid->Adapter.Points().count;
    const int segment = this->UsedSegments[g];
    for (std::size_t i = 0; i < count; ++i, ++value)
    {
      *value = static_cast<float>(entry(segment, *value));
    }
  }
  this->Mapped = true;
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
