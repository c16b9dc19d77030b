// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshSource.h
 * @brief Private glue: the mapper's input as the core sees it.
 *
 * The input is one unstructured grid (vtkUnstructuredGridBase) or a composite data set
 * (vtkMultiBlockDataSet, vtkPartitionedDataSet, vtkPartitionedDataSetCollection: any
 * vtkDataObjectTree) whose leaves are unstructured grids. Each grid is split into
 * tetrahedra where it needs it (Tetrahedralizer), presented to the core without copying
 * (MeshAdapter), and gives its scalars by the mapper's selection (SelectScalars). The
 * leaves of a composite input become the parts of one mesh (mtpt::MeshPart): the core sorts
 * the cells of all blocks in one visibility order, with no merged copy of their points or
 * cells. Only their scalars are gathered into one array (one float per point or cell, or
 * every component of each with dependent components).
 *
 * Skipped, with one warning each: leaves that are not unstructured grids, leaves without
 * cells, leaves without the selected scalars, and leaves whose scalars are point data where
 * the others' are cell data (or the other way round).
 *
 * Several volumes drawn together (the mapper's CompositeWithOtherVolumes) are one mesh too:
 * each volume's grids are parts, each with the scalars its own mapper selects. Volumes that
 * share a property object share a segment of the transfer-function table
 * (TransferFunctionTables); where there are several, each volume's scalars are gathered
 * mapped into its segment's entry coordinates, so that one table serves every cell.
 *
 * Kept between frames, per grid: the tetrahedralization and the adapted views, keyed on the
 * grid object and its modification time (Tetrahedralizer, MeshAdapter). A change to one
 * block redoes that block's work only. Version() changes whenever what the views show
 * changes (any grid, its scalar array, the component or the association), which is the
 * data version the pipeline's reuse is keyed on.
 */
#ifndef mtpt_MeshSource_h
#define mtpt_MeshSource_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/MeshView.h"

#include "vtkType.h"

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkAbstractVolumeMapper;
class vtkDataArray;
class vtkDataObject;
class vtkObject;
class vtkUnstructuredGridBase;
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

/// One volume of several drawn together: its input, the mapper whose scalar selection
/// applies to it, and its property.
struct GroupedVolume
{
  vtkDataObject* input = nullptr;
  vtkAbstractVolumeMapper* mapper = nullptr;
  vtkVolumeProperty* property = nullptr;
  /// Its matrix (vtkMatrix4x4's 16 elements, row-major) where the volumes drawn together
  /// differ in it: its grids become parts placed by it (MeshPart::model). Null: the mesh's
  /// model coordinates are its own.
  const double* matrix = nullptr;
};

class MeshSource
{
public:
  MeshSource();
  ~MeshSource();

  /// Receives each problem: the object it is about (the caller reports it once per that
  /// object's modification time), the message, and whether it stops the frame.
  using Reporter = std::function<void(vtkObject* subject, const std::string& text, bool error)>;

  /**
   * Brings the views up to date with `input` (cheap when nothing changed). Returns false
   * when there is nothing to draw; `report` has then been told why, unless the input is
   * merely empty of drawable cells in a way already reported.
   */
  bool Update(vtkDataObject* input, vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property,
    const Reporter& report);

  /// The same for several volumes as one mesh, their grids in order (messages name each
  /// volume by its place: "volume 2").
  bool Update(const std::vector<GroupedVolume>& volumes, const Reporter& report);
  /// The property and scalar range of each segment of the last Update: one per property
  /// object, in the order the volumes first name them.
  struct Segment
  {
    vtkVolumeProperty* property = nullptr;
    double range[2] = { 0, 1 };
  };
  const std::vector<Segment>& Segments() const { return this->SegmentData; }
  /**
   * Where there are several segments, the scalars are given in entry coordinates: `entry`
   * maps a scalar of segment k to its coordinate (TransferFunctionTables::EntryOf of the
   * table built over Segments()). Call after Update, before reading Scalars(); cheap when
   * the data have not changed since the last call.
   */
  void MapToSegments(const std::function<double(int segment, double scalar)>& entry);

  PointsView Points() const { return this->PointData; }
  CellsView Cells() const { return this->CellData; }
  /// The scalars, Channels() floats per point or cell.
  ScalarsView Scalars() const { return this->ScalarData; }
  /// Values per point or cell in Scalars(): 1, or 2 or 4 with dependent components.
  int Channels() const { return this->ScalarChannels; }
  /// Changes whenever the content the views show changes.
  std::uint64_t Version() const { return this->DataVersion; }
  /// Changes whenever a part's matrix (GroupedVolume::matrix) changes: the points' placement,
  /// not their content (FrameInput::placementVersion).
  std::uint64_t PlacementVersion() const { return this->Placement; }
  /// Grids drawn by the last Update: 1 for a grid input, the usable leaves for a composite.
  std::size_t GridCount() const { return this->Used.size(); }
  /// Splits into tetrahedra done so far, over every grid.
  vtkIdType Tetrahedralizations() const;

  /**
   * The unstructured grids of `input`: itself, or the leaves of a composite data set in
   * order, each with a name for messages ("block 3 'fin'"). Leaves of other types and empty
   * nodes are not listed (`skipped` receives one message per leaf of another type).
   */
  static std::vector<std::pair<vtkUnstructuredGridBase*, std::string>> Grids(
    vtkDataObject* input, std::vector<std::pair<vtkDataObject*, std::string>>* skipped = nullptr);

private:
  MeshSource(const MeshSource&) = delete;
  void operator=(const MeshSource&) = delete;

  struct Grid;
  /// Prepares one grid; false (reported) when it cannot be drawn.
  bool PrepareGrid(Grid& grid, vtkUnstructuredGridBase* input, const std::string& name, bool single,
    vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property, const Reporter& report);
  /// Prepares the grids of a volume's input and lists in Used those that can be drawn
  /// together, in segment `segment`.
  void UseGrids(const std::vector<std::pair<vtkUnstructuredGridBase*, std::string>>& grids,
    bool single, const GroupedVolume& volume, int segment, const std::string& prefix,
    const Reporter& report);
  /// Forgets the grids no longer in the input.
  void RetireUnseen();
  /// The views of the Used grids, and a new data version, unless they are those of last time.
  void MakeViews(bool single);
  void GatherScalars();
  /// The parts' matrices of this Update, and a new placement version where they changed.
  void PlaceParts();
  /// Drops the views: the next Update makes them again (a new data version).
  void Forget();

  /// Grids by object, the mapper selecting their scalars and the property (one grid may be
  /// the input of several volumes, with scalars of their own).
  using GridKey =
    std::tuple<vtkUnstructuredGridBase*, vtkAbstractVolumeMapper*, vtkVolumeProperty*>;
  std::map<GridKey, std::unique_ptr<Grid>> Cache;
  std::vector<Grid*> Used; ///< the grids drawn, in order
  /// The segment of each grid drawn, and its matrix (GroupedVolume::matrix).
  std::vector<int> UsedSegments;
  std::vector<const double*> UsedMatrices;
  std::vector<Segment> SegmentData;
  /// Gathered holds entry coordinates (MapToSegments) for the current data version.
  bool Mapped = false;
  /// The parts' matrices (MeshPart::model points into it), whether each has one, and their
  /// version.
  std::vector<Matrix4> Models;
  std::vector<bool> Placed;
  std::uint64_t Placement = 0;
  std::vector<MeshPart> Parts; ///< one per used grid (composite input)
  std::vector<float> Gathered; ///< the scalars of every used grid, in order (composite)
  PointsView PointData;
  CellsView CellData;
  ScalarsView ScalarData;
  int ScalarChannels = 1;

  /// What the views were made from: a change of any of these is a new data version.
  struct Key
  {
    vtkUnstructuredGridBase* grid;
    vtkMTimeType gridTime;
    vtkDataArray* scalars;
    vtkMTimeType scalarTime;
    int component;
    bool cellData;
    int segment;
    bool operator==(const Key& o) const
    {
      return grid == o.grid && gridTime == o.gridTime && scalars == o.scalars &&
        scalarTime == o.scalarTime && component == o.component && cellData == o.cellData &&
        segment == o.segment;
    }
  };
  std::vector<Key> LastKeys;
  std::uint64_t DataVersion = 0;
  vtkIdType RetiredTetrahedralizations = 0; ///< of grids no longer in the input
};

} // namespace mtpt

#endif
