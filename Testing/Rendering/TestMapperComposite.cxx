// SPDX-License-Identifier: BSD-3-Clause
// Composite input: the cells of all blocks in one visibility order. Blocks that interleave in
// depth (an inner part inside an outer shell; two parts of interleaved slabs seen obliquely)
// must give the exact reference of the merged grid, as well as MTPT gives it on the merged
// grid itself, where VTK's vtkMultiBlockUnstructuredGridVolumeMapper, drawing one block after
// another, cannot. Partitioned collections, nested multi-blocks, empty and bad blocks, thread
// counts, and the work redone when one block changes.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkActor.h"
#include "vtkActorCollection.h"
#include "vtkAppendFilter.h"
#include "vtkCamera.h"
#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkPoints.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiBlockUnstructuredGridVolumeMapper.h"
#include "vtkObjectFactory.h"
#include "vtkPartitionedDataSet.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPlane.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkPartitionedDataSetCollection.h"
#include "vtkPointData.h"
#include "vtkRTAnalyticSource.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
#include "vtkTransform.h"
#include "vtkTransformFilter.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// The cells of `grid` for which `inBlock(centre)` holds, as a grid of their own (their
/// points only, point and cell data copied).
vtkSmartPointer<vtkUnstructuredGrid> Block(
  vtkUnstructuredGrid* grid, const std::function<bool(const double centre[3])>& inBlock)
{
  auto block = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  block->SetPoints(points);
  block->GetPointData()->CopyAllocate(grid->GetPointData());
  block->GetCellData()->CopyAllocate(grid->GetCellData());
  std::vector<vtkIdType> newId(static_cast<std::size_t>(grid->GetNumberOfPoints()), -1);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, ids);
    double centre[3] = { 0, 0, 0 };
    for (const vtkIdType id : *ids)
    {
      const double* p = grid->GetPoint(id);
      for (int d = 0; d < 3; ++d)
      {
        centre[d] += p[d] / static_cast<double>(ids->GetNumberOfIds());
      }
    }
    if (!inBlock(centre))
    {
      continue;
    }
    for (vtkIdType& id : *ids)
    {
      vtkIdType& mapped = newId[static_cast<std::size_t>(id)];
      if (mapped < 0)
      {
        mapped = points->InsertNextPoint(grid->GetPoint(id));
        block->GetPointData()->CopyData(grid->GetPointData(), id, mapped);
      }
      id = mapped;
    }
    const vtkIdType cell = block->InsertNextCell(grid->GetCellType(c), ids);
    block->GetCellData()->CopyData(grid->GetCellData(), c, cell);
  }
  return block;
}

/// A scene of interleaved blocks and the same cells appended into one grid.
struct Parts
{
  std::string name;
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> blocks;
  vtkSmartPointer<vtkUnstructuredGrid> merged;
  double azimuth, elevation;
};

vtkSmartPointer<vtkUnstructuredGrid> Append(
  const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& blocks)
{
  vtkNew<vtkAppendFilter> append;
  for (const auto& block : blocks)
  {
    append->AddInputData(block);
  }
  append->Update();
  auto merged = vtkSmartPointer<vtkUnstructuredGrid>::New();
  merged->ShallowCopy(append->GetOutput());
  return merged;
}

/// An inner cube inside an outer shell; slabs of two blocks in turn, seen obliquely.
std::vector<Parts> InterleavedScenes()
{
  auto box = MakeTetrahedralBox(12);
  std::vector<Parts> scenes(2);
  scenes[0].name = "inner block in an outer shell";
  auto inner = [](const double* c)
  { return std::fabs(c[0]) < 0.45 && std::fabs(c[1]) < 0.45 && std::fabs(c[2]) < 0.45; };
  scenes[0].blocks = { Block(box, [&](const double* c) { return !inner(c); }), Block(box, inner) };
  scenes[0].azimuth = 30;
  scenes[0].elevation = 20;
  scenes[1].name = "interleaved slabs seen obliquely";
  auto even = [](const double* c)
  { return static_cast<int>(std::floor((c[0] + 1) / 0.5)) % 2 == 0; };
  scenes[1].blocks = { Block(box, even), Block(box, [&](const double* c) { return !even(c); }) };
  scenes[1].azimuth = 60;
  scenes[1].elevation = 25;
  for (Parts& scene : scenes)
  {
    scene.merged = Append(scene.blocks);
  }
  return scenes;
}

vtkSmartPointer<vtkMultiBlockDataSet> MultiBlock(
  const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& blocks)
{
  auto tree = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  tree->SetNumberOfBlocks(static_cast<unsigned>(blocks.size()));
  for (unsigned b = 0; b < blocks.size(); ++b)
  {
    tree->SetBlock(b, blocks[b]);
  }
  return tree;
}

/// `input` drawn by `mapper` from the scene's view, with the box's transfer functions;
/// the image, and the stage for a reference.
vtkSmartPointer<vtkImageData> Draw(vtkDataObject* input, vtkUnstructuredGridVolumeMapper* mapper,
  const Parts& scene, Stage* keep = nullptr)
{
  auto property = MakeProperty(-0.3, 1.3, 0.3);
  Stage stage = MakeStage(input, property, mapper, 220, 220);
  SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
  stage.window->Render();
  auto image = Grab(stage.window, false);
  if (keep)
  {
    *keep = stage;
  }
  else
  {
    mapper->ReleaseGraphicsResources(stage.window);
  }
  return image;
}

class MapperComposite : public ::testing::TestWithParam<int>
{
};

TEST_P(MapperComposite, InterleavedBlocksMatchTheMergedGridAndItsExactReference)
{
  for (const Parts& scene : InterleavedScenes())
  {
    SCOPED_TRACE(scene.name);
    auto tree = MultiBlock(scene.blocks);
    // MTPT on the composite: one order over both blocks.
    vtkNew<Mapper> composite;
    composite->SetBackend(GetParam());
    Stage stage;
    auto ours = Draw(tree, composite, scene, &stage);
    EXPECT_EQ(composite->GetNumberOfTetrahedra(), scene.merged->GetNumberOfCells());
    // The exact reference of the merged grid, in the same window and view.
    auto exact = ReferenceImage(stage, scene.merged);
    // The reference renderer appends a composite input's blocks itself.
    EXPECT_EQ(Compare(ReferenceImage(stage), exact).worst, 0.0);
    composite->ReleaseGraphicsResources(stage.window);
    // MTPT on the merged grid: the same cells in the same order.
    vtkNew<Mapper> single;
    single->SetBackend(GetParam());
    auto merged = Draw(scene.merged, single, scene);
    // VTK's multi-block mapper: block after block.
    vtkNew<vtkMultiBlockUnstructuredGridVolumeMapper> theirs;
    auto blockwise = Draw(tree, theirs, scene);

    EXPECT_EQ(Compare(ours, merged).worst, 0.0) << "the composite equals the merged grid";
    const ImageDifference mine = Compare(ours, exact), vtk = Compare(blockwise, exact);
    std::printf("%s: covered-pixel RMSE against the exact reference: MTPT composite %.4f, "
                "VTK's multi-block mapper %.4f (worst pixel %.3f and %.3f)\n",
      scene.name.c_str(), mine.coveredRmse, vtk.coveredRmse, mine.worst, vtk.worst);
    EXPECT_LT(mine.coveredRmse, 0.02);
    EXPECT_LT(mine.worst, 0.25);
    EXPECT_GT(vtk.coveredRmse, 2 * mine.coveredRmse) << "VTK's blockwise order is visibly wrong";
    EXPECT_GT(CoveredFraction(ours, Background), 0.2);
  }
}

/**
 * The blocks of `scene` as volumes of their own in one renderer, each drawn by a mapper of
 * its own (`together`: SetCompositeWithOtherVolumes), sharing `property` or each with a copy
 * of it; the image. `setUp`, when given, sets up each volume and its mapper after that
 * (block b's). Warnings go to `observer`; `drawn` receives each mapper's tetrahedra.
 */
vtkSmartPointer<vtkImageData> DrawVolumes(const Parts& scene, int backend, bool together,
  bool shared, MessageObserver* observer = nullptr, std::vector<vtkIdType>* drawn = nullptr,
  const std::function<void(std::size_t block, vtkVolume*, Mapper*)>& setUp = nullptr,
  vtkSmartPointer<vtkImageData>* exact = nullptr)
{
  auto property = MakeProperty(-0.3, 1.3, 0.3);
  std::vector<vtkSmartPointer<Mapper>> mappers;
  for (std::size_t b = 0; b < scene.blocks.size(); ++b)
  {
    auto mapper = vtkSmartPointer<Mapper>::New();
    mapper->SetBackend(backend);
    mapper->SetCompositeWithOtherVolumes(together);
    if (observer)
    {
      mapper->AddObserver(vtkCommand::WarningEvent, observer);
      mapper->AddObserver(vtkCommand::ErrorEvent, observer);
    }
    mappers.push_back(mapper);
  }
  Stage stage = MakeStage(scene.blocks[0], property, mappers[0], 220, 220);
  if (setUp)
  {
    setUp(0, stage.volume, mappers[0]);
  }
  for (std::size_t b = 1; b < scene.blocks.size(); ++b)
  {
    mappers[b]->SetInputData(scene.blocks[b]);
    vtkNew<vtkVolume> volume;
    volume->SetMapper(mappers[b]);
    if (shared)
    {
      volume->SetProperty(property);
    }
    else
    {
      auto copy = MakeProperty(-0.3, 1.3, 0.3); // the same functions, another object
      volume->SetProperty(copy);
    }
    if (setUp)
    {
      setUp(b, volume, mappers[b]);
    }
    stage.renderer->AddVolume(volume);
  }
  SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
  stage.window->Render();
  stage.window->Render(); // a second frame: the group kept, no warning again
  auto image = Grab(stage.window, false);
  if (exact)
  {
    *exact = VolumesReferenceImage(stage.renderer);
  }
  for (const auto& mapper : mappers)
  {
    if (drawn)
    {
      drawn->push_back(mapper->GetNumberOfTetrahedra());
    }
    mapper->ReleaseGraphicsResources(stage.window);
  }
  return image;
}

TEST_P(MapperComposite, VolumesSharingAPropertyAreOnePictureOfTheirCells)
{
  // A mesh split into two volumes (interleaved slabs; an inner block in a shell), one
  // property: drawn together they are the merged grid drawn as one volume; drawn one after
  // the other, as VTK draws volumes, they are visibly wrong.
  for (const Parts& scene : InterleavedScenes())
  {
    SCOPED_TRACE(scene.name);
    vtkNew<Mapper> single;
    single->SetBackend(GetParam());
    Stage stage;
    auto whole = Draw(scene.merged, single, scene, &stage);
    auto exact = ReferenceImage(stage, scene.merged);
    single->ReleaseGraphicsResources(stage.window);

    auto observer = vtkSmartPointer<MessageObserver>::New();
    std::vector<vtkIdType> drawn;
    auto together = DrawVolumes(scene, GetParam(), true, true, observer, &drawn);
    EXPECT_TRUE(observer->warnings.empty());
    EXPECT_TRUE(observer->errors.empty());
    // The first volume's mapper drew every cell of both; the other drew none.
    ASSERT_EQ(drawn.size(), 2u);
    EXPECT_EQ(drawn[0], scene.merged->GetNumberOfCells());
    EXPECT_EQ(drawn[1], 0);
    auto apart = DrawVolumes(scene, GetParam(), false, true);

    const ImageDifference same = Compare(together, whole), wrong = Compare(apart, whole);
    std::printf("%s: covered-pixel RMSE against one volume of all the cells: drawn together "
                "%.5f (worst %.4f), one after the other %.4f (worst %.3f); against the exact "
                "reference: together %.4f, apart %.4f\n",
      scene.name.c_str(), same.coveredRmse, same.worst, wrong.coveredRmse, wrong.worst,
      Compare(together, exact).coveredRmse, Compare(apart, exact).coveredRmse);
    EXPECT_LT(same.coveredRmse, 1.0 / 255);
    EXPECT_LT(same.worst, 4.0 / 255);
    EXPECT_GT(wrong.coveredRmse, 2.0 / 255) << "one volume after the other is visibly wrong";
    EXPECT_GT(wrong.worst, 10.0 / 255);
    EXPECT_GT(CoveredFraction(together, Background), 0.2);
  }
}

/**
 * Two volumes of their own transfer functions, unit distances and arrays: block 0 through a
 * colour ramp over "field" with unit distance 0.2; block 1 through other functions over an
 * array "doubled" (2 field + 1) with unit distance 0.1. `Apply` sets a volume up so;
 * `Equivalent` is the same scene as one volume: both blocks in one composite input, block
 * 1's scalar moved by Shift, and one property of unit distance 0.1 whose functions are
 * block 0's (opacity halved) below Shift and block 1's, moved by Shift, above.
 */
struct TwoFunctions
{
  static constexpr double Shift = 10;

  /// A copy of `block` with a point array `name`: its "field" times `scale` plus `offset`.
  static vtkSmartPointer<vtkUnstructuredGrid> WithArray(
    vtkUnstructuredGrid* block, const char* name, double scale, double offset)
  {
    auto copy = vtkSmartPointer<vtkUnstructuredGrid>::New();
    copy->ShallowCopy(block);
    vtkDataArray* field = block->GetPointData()->GetArray("field");
    vtkNew<vtkFloatArray> values;
    values->SetName(name);
    values->SetNumberOfTuples(field->GetNumberOfTuples());
    for (vtkIdType i = 0; i < field->GetNumberOfTuples(); ++i)
    {
      values->SetValue(i, static_cast<float>(scale * field->GetTuple1(i) + offset));
    }
    vtkNew<vtkPointData> data;
    data->ShallowCopy(block->GetPointData());
    copy->GetPointData()->ShallowCopy(data);
    copy->GetPointData()->AddArray(values);
    return copy;
  }

  static void AddFunctions(vtkColorTransferFunction* colour, vtkPiecewiseFunction* opacity,
    std::size_t block, double shift, double opacityScale)
  {
    if (block == 0)
    {
      colour->AddRGBPoint(-0.3 + shift, 0.2, 0.3, 0.9);
      colour->AddRGBPoint(0.5 + shift, 0.95, 0.95, 0.6);
      colour->AddRGBPoint(1.3 + shift, 0.9, 0.2, 0.1);
      opacity->AddPoint(-0.3 + shift, 0.05 * opacityScale);
      opacity->AddPoint(1.3 + shift, 0.9 * opacityScale);
      return;
    }
    colour->AddRGBPoint(0.4 + shift, 0.1, 0.8, 0.3);
    colour->AddRGBPoint(2.0 + shift, 0.9, 0.9, 0.9);
    colour->AddRGBPoint(3.6 + shift, 0.6, 0.1, 0.8);
    opacity->AddPoint(0.4 + shift, 0.8 * opacityScale);
    opacity->AddPoint(3.6 + shift, 0.1 * opacityScale);
  }

  static void Apply(std::size_t block, vtkVolume* volume, Mapper* mapper)
  {
    vtkNew<vtkColorTransferFunction> colour;
    vtkNew<vtkPiecewiseFunction> opacity;
    AddFunctions(colour, opacity, block, 0.0, 1.0);
    vtkNew<vtkVolumeProperty> property;
    property->SetColor(colour);
    property->SetScalarOpacity(opacity);
    property->SetScalarOpacityUnitDistance(block == 0 ? 0.2 : 0.1);
    volume->SetProperty(property);
    auto* input = vtkUnstructuredGrid::SafeDownCast(mapper->GetInputDataObject(0, 0));
    if (block == 1)
    {
      mapper->SetScalarModeToUsePointFieldData();
      mapper->SelectScalarArray("doubled");
      if (!input->GetPointData()->GetArray("doubled"))
      {
        mapper->SetInputData(WithArray(input, "doubled", 2, 1));
      }
    }
  }

  /// The scene as one volume: its composite input and property.
  static std::pair<vtkSmartPointer<vtkMultiBlockDataSet>, vtkSmartPointer<vtkVolumeProperty>>
  Equivalent(const Parts& scene)
  {
    // One array name in both blocks, so that the reference's appended grid keeps it.
    auto first = WithArray(scene.blocks[0], "value", 1, 0);
    auto second = WithArray(scene.blocks[1], "value", 2, 1 + Shift);
    first->GetPointData()->SetActiveScalars("value");
    second->GetPointData()->SetActiveScalars("value");
    auto tree = MultiBlock({ first, second });
    vtkNew<vtkColorTransferFunction> colour;
    vtkNew<vtkPiecewiseFunction> opacity;
    AddFunctions(colour, opacity, 0, 0.0, 0.5);
    AddFunctions(colour, opacity, 1, Shift, 1.0);
    auto property = vtkSmartPointer<vtkVolumeProperty>::New();
    property->SetColor(colour);
    property->SetScalarOpacity(opacity);
    property->SetScalarOpacityUnitDistance(0.1);
    return { tree, property };
  }
};

/**
 * The scene's blocks as volumes set up by `setUp` (sharing one property or not), drawn
 * together, checked to be drawn by the first mapper without a message, and drawn one after
 * the other: the two images; and the exact reference of the volumes together
 * (vtkMTPTReferenceRenderer::RenderVolumes).
 */
std::pair<std::pair<vtkSmartPointer<vtkImageData>, vtkSmartPointer<vtkImageData>>,
  vtkSmartPointer<vtkImageData>>
TogetherAndApart(
  const Parts& scene, int backend, bool shared,
  const std::function<void(std::size_t block, vtkVolume*, Mapper*)>& setUp)
{
  auto observer = vtkSmartPointer<MessageObserver>::New();
  std::vector<vtkIdType> drawn;
  vtkSmartPointer<vtkImageData> exact;
  auto together = DrawVolumes(scene, backend, true, shared, observer, &drawn, setUp, &exact);
  EXPECT_TRUE(observer->warnings.empty()) << observer->warnings.front();
  EXPECT_TRUE(observer->errors.empty());
  EXPECT_EQ(drawn.size(), 2u);
  EXPECT_EQ(drawn.at(0), scene.merged->GetNumberOfCells());
  EXPECT_EQ(drawn.at(1), 0);
  return { { together, DrawVolumes(scene, backend, false, shared, nullptr, nullptr, setUp) },
    exact };
}

/**
 * Volumes drawn together (`together`) are the picture of the scene as one volume (`whole`)
 * within 1/255 covered RMSE and of its exact reference within 2/255; drawn one after the
 * other (`apart`) they are at least twice as far from the reference.
 */
void ExpectOnePicture(vtkImageData* together, vtkImageData* apart, vtkImageData* whole,
  vtkImageData* exact, const std::string& what)
{
  const ImageDifference same = Compare(together, whole), right = Compare(together, exact),
                        wrong = Compare(apart, exact);
  std::printf("%s: covered-pixel RMSE against the exact reference: drawn together %.4f (worst "
              "%.3f), one after the other %.4f (worst %.3f); against the scene as one volume "
              "%.5f (worst %.4f)\n",
    what.c_str(), right.coveredRmse, right.worst, wrong.coveredRmse, wrong.worst,
    same.coveredRmse, same.worst);
  EXPECT_LT(same.coveredRmse, 1.0 / 255);
  EXPECT_LT(same.worst, 4.0 / 255);
  EXPECT_LT(right.coveredRmse, 2.0 / 255);
  EXPECT_GT(wrong.coveredRmse, 2 * right.coveredRmse) << "one after the other is wrong";
  EXPECT_GT(CoveredFraction(together, Background), 0.2);
}

TEST_P(MapperComposite, VolumesOfTheirOwnTransferFunctionsAreOnePicture)
{
  // Each cell through its own volume's transfer functions, unit distance and array, all
  // cells in one order: the image of the same scene as one volume (one composite input, one
  // property holding both functions), and of its exact reference. Both shadings.
  for (const int shading : { Mapper::VTK_COMPATIBLE_SHADING, Mapper::PRE_INTEGRATED_SHADING })
  {
    const auto setUp = [shading](std::size_t block, vtkVolume* volume, Mapper* mapper)
    {
      TwoFunctions::Apply(block, volume, mapper);
      mapper->SetShadingMode(shading);
    };
    for (const Parts& scene : InterleavedScenes())
    {
      SCOPED_TRACE(scene.name);
      SCOPED_TRACE(shading);
      const auto images = TogetherAndApart(scene, GetParam(), false, setUp);

      const auto equivalent = TwoFunctions::Equivalent(scene);
      vtkNew<Mapper> one;
      one->SetBackend(GetParam());
      one->SetShadingMode(shading);
      Stage stage = MakeStage(equivalent.first, equivalent.second, one, 220, 220);
      SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
      stage.window->Render();
      auto whole = Grab(stage.window, false);
      auto exact = ReferenceImage(stage);
      one->ReleaseGraphicsResources(stage.window);
      ExpectOnePicture(images.first.first, images.first.second, whole, exact,
        scene.name + ", two transfer functions, " + one->GetShadingModeAsString() + " shading");
      EXPECT_LE(Compare(images.second, exact).worst, 1.0 / 255)
        << "the reference of the volumes is the reference of the scene as one volume";
    }
  }
}

TEST_P(MapperComposite, VolumesOfTheirOwnMatricesAreOnePicture)
{
  // The second volume turned and moved by its own matrix: each cell placed by its volume's
  // matrix, all in one order; the image of the same scene as one volume whose second block's
  // points were moved by that matrix, and of its exact reference.
  for (const Parts& scene : InterleavedScenes())
  {
    SCOPED_TRACE(scene.name);
    const auto place = [](std::size_t block, vtkVolume* volume, Mapper*)
    {
      if (block == 1)
      {
        volume->SetOrientation(0, 0, 12);
        volume->SetPosition(0.08, -0.05, 0.1);
      }
    };
    const auto images = TogetherAndApart(scene, GetParam(), true, place);

    vtkNew<vtkVolume> moved;
    place(1, moved, nullptr);
    vtkNew<vtkTransform> transform;
    transform->SetMatrix(moved->GetMatrix());
    vtkNew<vtkTransformFilter> move;
    move->SetTransform(transform);
    move->SetInputData(scene.blocks[1]);
    move->SetOutputPointsPrecision(vtkAlgorithm::DOUBLE_PRECISION);
    move->Update();
    auto tree =
      MultiBlock({ scene.blocks[0], vtkUnstructuredGrid::SafeDownCast(move->GetOutput()) });
    vtkNew<Mapper> one;
    one->SetBackend(GetParam());
    Stage stage;
    auto whole = Draw(tree, one, scene, &stage);
    auto exact = ReferenceImage(stage);
    one->ReleaseGraphicsResources(stage.window);
    ExpectOnePicture(images.first.first, images.first.second, whole, exact,
      scene.name + ", the second volume moved by its matrix");
    EXPECT_LE(Compare(images.second, exact).worst, 1.0 / 255)
      << "the reference of the volumes is the reference of the scene as one volume";
  }
}

/// Volumes of their own properties in one renderer, added and changed by a test.
struct Group
{
  Stage stage;
  std::vector<vtkSmartPointer<vtkVolume>> volumes;
  vtkSmartPointer<MessageObserver> observer = vtkSmartPointer<MessageObserver>::New();

  Group(const Parts& scene, int backend)
  {
    stage.renderer = vtkSmartPointer<vtkRenderer>::New();
    stage.renderer->SetBackground(Background[0], Background[1], Background[2]);
    stage.window = vtkSmartPointer<vtkRenderWindow>::New();
    stage.window->SetOffScreenRendering(1);
    stage.window->SetSize(220, 220);
    stage.window->AddRenderer(stage.renderer);
    this->backend = backend;
    this->view = { scene.azimuth, scene.elevation };
  }
  /// A volume of `input` with block `block`'s functions of TwoFunctions.
  vtkVolume* Add(vtkDataObject* input, std::size_t block)
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackend(this->backend);
    mapper->SetInputDataObject(input);
    mapper->AddObserver(vtkCommand::WarningEvent, this->observer);
    mapper->AddObserver(vtkCommand::ErrorEvent, this->observer);
    auto volume = vtkSmartPointer<vtkVolume>::New();
    volume->SetMapper(mapper);
    TwoFunctions::Apply(block, volume, mapper);
    this->stage.renderer->AddVolume(volume);
    this->volumes.push_back(volume);
    return volume;
  }
  vtkIdType Drawn(std::size_t v)
  {
    return static_cast<Mapper*>(this->volumes[v]->GetMapper())->GetNumberOfTetrahedra();
  }
  vtkSmartPointer<vtkImageData> Render()
  {
    if (!this->viewSet)
    {
      SetView(this->stage.renderer, this->view, true);
      this->viewSet = true;
    }
    this->stage.window->Render();
    return Grab(this->stage.window, false);
  }
  ~Group()
  {
    for (const auto& volume : this->volumes)
    {
      volume->GetMapper()->ReleaseGraphicsResources(this->stage.window);
    }
  }
  int backend = 0;
  View view;
  bool viewSet = false;
};

TEST_P(MapperComposite, TheGroupFollowsItsVolumes)
{
  // Two volumes of their own functions, and a third that is hidden, then shown, then
  // removed; an empty one; one input drawn twice; a multi-block input among them.
  const Parts scene = InterleavedScenes()[1];
  const vtkIdType cells0 = scene.blocks[0]->GetNumberOfCells();
  const vtkIdType cells1 = scene.blocks[1]->GetNumberOfCells();
  Group two(scene, GetParam());
  two.Add(scene.blocks[0], 0);
  two.Add(scene.blocks[1], 1);
  auto pair = two.Render();
  EXPECT_EQ(two.Drawn(0), cells0 + cells1);

  Group more(scene, GetParam());
  more.Add(scene.blocks[0], 0);
  more.Add(scene.blocks[1], 1);
  vtkVolume* third = more.Add(scene.merged, 0);
  third->SetVisibility(0);
  EXPECT_EQ(Compare(more.Render(), pair).worst, 0.0) << "a hidden volume is not drawn";
  EXPECT_EQ(more.Drawn(0), cells0 + cells1);
  third->SetVisibility(1);
  auto three = more.Render();
  EXPECT_EQ(more.Drawn(0), 2 * (cells0 + cells1));
  EXPECT_EQ(more.Drawn(2), 0);
  EXPECT_GT(Compare(three, pair).coveredRmse, 2.0 / 255) << "the third volume is drawn";
  more.stage.renderer->RemoveVolume(third);
  EXPECT_EQ(Compare(more.Render(), pair).worst, 0.0) << "a removed volume is not drawn";
  EXPECT_EQ(more.Drawn(0), cells0 + cells1);
  EXPECT_TRUE(more.observer->warnings.empty());
  EXPECT_TRUE(more.observer->errors.empty());

  // A volume without cells: said once, the others drawn as without it.
  Group empty(scene, GetParam());
  empty.Add(scene.blocks[0], 0);
  empty.Add(scene.blocks[1], 1);
  vtkNew<vtkUnstructuredGrid> nothing;
  empty.Add(nothing, 0);
  EXPECT_EQ(Compare(empty.Render(), pair).worst, 0.0);
  empty.Render();
  ASSERT_EQ(empty.observer->warnings.size(), 1u);
  EXPECT_NE(empty.observer->warnings[0].find("volume 3: its input has no cells"), std::string::npos)
    << empty.observer->warnings[0];

  // One input in two volumes of their own functions: every cell drawn once for each.
  Group shared(scene, GetParam());
  auto both = TwoFunctions::WithArray(scene.blocks[0], "doubled", 2, 1);
  shared.Add(both, 0);
  shared.Add(both, 1);
  shared.Render();
  EXPECT_EQ(shared.volumes[0]->GetMapper()->GetInputDataObject(0, 0),
    shared.volumes[1]->GetMapper()->GetInputDataObject(0, 0));
  EXPECT_EQ(shared.Drawn(0), 2 * cells0);
  EXPECT_TRUE(shared.observer->warnings.empty());

  // One tetrahedron beside thousands: drawn with them, in the same order.
  Group tiny(scene, GetParam());
  tiny.Add(scene.blocks[0], 0);
  vtkNew<vtkUnstructuredGrid> one;
  vtkNew<vtkPoints> corners;
  const double corner[4][3] = { { 0.1, 0.1, 0.1 }, { 0.4, 0.1, 0.1 }, { 0.1, 0.4, 0.1 },
    { 0.1, 0.1, 0.4 } };
  for (const double* p : corner)
  {
    corners->InsertNextPoint(p);
  }
  one->SetPoints(corners);
  const vtkIdType ids[4] = { 0, 1, 2, 3 };
  one->InsertNextCell(VTK_TETRA, 4, ids);
  vtkNew<vtkFloatArray> field;
  field->SetName("field");
  for (const float value : { 0.2f, 0.9f, 0.5f, 1.1f })
  {
    field->InsertNextValue(value);
  }
  one->GetPointData()->SetScalars(field);
  tiny.Add(one, 1);
  tiny.Render();
  EXPECT_EQ(tiny.Drawn(0), cells0 + 1);
  EXPECT_EQ(tiny.Drawn(1), 0);
  EXPECT_TRUE(tiny.observer->warnings.empty()) << tiny.observer->warnings.front();

  // The second volume's cells as a multi-block of two: the same picture.
  Group tree(scene, GetParam());
  tree.Add(scene.blocks[0], 0);
  vtkVolume* composite = tree.Add(scene.blocks[1], 1);
  auto* second =
    vtkUnstructuredGrid::SafeDownCast(composite->GetMapper()->GetInputDataObject(0, 0));
  auto low = Block(second, [](const double* c) { return c[1] < 0; });
  auto high = Block(second, [](const double* c) { return c[1] >= 0; });
  static_cast<Mapper*>(composite->GetMapper())->SetInputDataObject(MultiBlock({ low, high }));
  const ImageDifference blocks = Compare(tree.Render(), pair);
  std::printf("the second volume as two blocks: covered-pixel RMSE %.5f (worst %.4f) against "
              "it as one grid\n",
    blocks.coveredRmse, blocks.worst);
  EXPECT_EQ(tree.Drawn(0), cells0 + cells1);
  EXPECT_LT(blocks.coveredRmse, 0.5 / 255);
  EXPECT_LT(blocks.worst, 2.0 / 255);
  EXPECT_TRUE(tree.observer->warnings.empty());
}

TEST_P(MapperComposite, ClippingLightingPeelingAndRenderersKeepTheGroup)
{
  // Volumes of their own functions with one clipping plane, with lighting, and through depth
  // peeling beside a translucent sphere: the picture of the scene as one volume under the
  // same plane, lights or peeling. Two renderers side by side: each draws its own group.
  const Parts scene = InterleavedScenes()[1];
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(0.1, 0.0, 0.0);
  plane->SetNormal(-0.3, 1.0, 0.2);
  vtkNew<vtkSphereSource> sphere;
  sphere->SetCenter(0.3, 0.2, 0.9);
  sphere->SetRadius(0.45);
  sphere->SetThetaResolution(32);
  sphere->SetPhiResolution(32);
  enum Case
  {
    Clipped,
    Lit,
    Peeled
  };
  for (const Case c : { Clipped, Lit, Peeled })
  {
    SCOPED_TRACE(c);
    // Sets a mapper, its volume and the renderer up for the case.
    const auto setUp = [&](Mapper* mapper, vtkVolume* volume, vtkRenderer* renderer)
    {
      if (c == Clipped)
      {
        mapper->AddClippingPlane(plane);
      }
      else if (c == Lit)
      {
        volume->GetProperty()->ShadeOn();
      }
      else if (renderer->GetActors()->GetNumberOfItems() == 0)
      {
        vtkNew<vtkPolyDataMapper> surface;
        surface->SetInputConnection(sphere->GetOutputPort());
        vtkNew<vtkActor> actor;
        actor->SetMapper(surface);
        actor->GetProperty()->SetColor(0.15, 0.85, 0.35);
        actor->GetProperty()->SetOpacity(0.45);
        actor->GetProperty()->LightingOff();
        renderer->AddActor(actor);
        renderer->SetUseDepthPeeling(1);
        renderer->SetUseDepthPeelingForVolumes(1);
        renderer->SetMaximumNumberOfPeels(8);
        renderer->SetOcclusionRatio(0.0);
      }
    };
    Group two(scene, GetParam());
    if (c == Peeled)
    {
      two.stage.window->SetMultiSamples(0); // VTK's depth peeling needs a single-sampled window
    }
    for (std::size_t b = 0; b < 2; ++b)
    {
      vtkVolume* volume = two.Add(scene.blocks[b], b);
      setUp(static_cast<Mapper*>(volume->GetMapper()), volume, two.stage.renderer);
    }
    auto together = two.Render();
    EXPECT_EQ(two.Drawn(1), 0);
    EXPECT_TRUE(two.observer->warnings.empty()) << two.observer->warnings.front();
    EXPECT_TRUE(two.observer->errors.empty()) << two.observer->errors.front();

    const auto equivalent = TwoFunctions::Equivalent(scene);
    vtkNew<Mapper> one;
    one->SetBackend(GetParam());
    Stage stage = MakeStage(equivalent.first, equivalent.second, one, 220, 220,
      WindowSettings{ true, c == Peeled ? 0 : -1 });
    setUp(one, stage.volume, stage.renderer);
    SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
    stage.window->Render();
    auto whole = Grab(stage.window, false);
    one->ReleaseGraphicsResources(stage.window);
    const ImageDifference same = Compare(together, whole);
    std::printf("two transfer functions, %s: covered-pixel RMSE %.5f (worst %.4f) against the "
                "scene as one volume\n",
      c == Clipped ? "one clipping plane" : (c == Lit ? "lit" : "peeled with a sphere"),
      same.coveredRmse, same.worst);
    EXPECT_LT(same.coveredRmse, 1.0 / 255);
    EXPECT_LT(same.worst, 4.0 / 255);
    EXPECT_GT(CoveredFraction(together, Background), 0.1);
  }

  // Two renderers side by side, each with two volumes: each group is its renderer's.
  Group left(scene, GetParam());
  left.Add(scene.blocks[0], 0);
  left.Add(scene.blocks[1], 1);
  left.stage.renderer->SetViewport(0.0, 0.0, 0.5, 1.0);
  vtkNew<vtkRenderer> right;
  right->SetViewport(0.5, 0.0, 1.0, 1.0);
  std::vector<vtkSmartPointer<Mapper>> rightMappers;
  for (std::size_t b = 0; b < 2; ++b)
  {
    auto mapper = vtkSmartPointer<Mapper>::New();
    mapper->SetBackend(GetParam());
    mapper->SetInputData(scene.blocks[b]);
    vtkNew<vtkVolume> volume;
    volume->SetMapper(mapper);
    TwoFunctions::Apply(b, volume, mapper);
    right->AddVolume(volume);
    rightMappers.push_back(mapper);
  }
  left.stage.window->AddRenderer(right);
  SetView(right, left.view, true);
  left.Render();
  EXPECT_EQ(left.Drawn(0), scene.merged->GetNumberOfCells());
  EXPECT_EQ(left.Drawn(1), 0);
  EXPECT_EQ(rightMappers[0]->GetNumberOfTetrahedra(), scene.merged->GetNumberOfCells());
  EXPECT_EQ(rightMappers[1]->GetNumberOfTetrahedra(), 0);
  for (const auto& mapper : rightMappers)
  {
    mapper->ReleaseGraphicsResources(left.stage.window);
  }
}

/**
 * A volume that draws through an inner volume of its own with its mapper, property and
 * matrix, as ParaView's vtkPVLODVolume draws (the renderer lists the outer volume; the mapper
 * is given the inner one).
 */
class OuterVolume : public vtkVolume
{
public:
  static OuterVolume* New();
  vtkTypeMacro(OuterVolume, vtkVolume);
  int RenderVolumetricGeometry(vtkViewport* viewport) override
  {
    this->Inner->SetMapper(this->GetMapper());
    this->Inner->SetProperty(this->GetProperty());
    this->Inner->SetUserMatrix(this->GetMatrix());
    this->Inner->SetAllocatedRenderTime(this->GetAllocatedRenderTime(), viewport);
    return this->Inner->RenderVolumetricGeometry(viewport);
  }

protected:
  OuterVolume() = default;
  ~OuterVolume() override = default;

private:
  OuterVolume(const OuterVolume&) = delete;
  void operator=(const OuterVolume&) = delete;
  vtkNew<vtkVolume> Inner;
};
vtkStandardNewMacro(OuterVolume);

TEST_P(MapperComposite, VolumesDrawnThroughInnerVolumesJoinTheirGroup)
{
  // Both volumes draw through inner volumes of their own: still one picture, the first
  // volume's mapper drawing both.
  const Parts scene = InterleavedScenes()[1];
  Group plain(scene, GetParam());
  plain.Add(scene.blocks[0], 0);
  plain.Add(scene.blocks[1], 1);
  auto expected = plain.Render();
  Group outer(scene, GetParam());
  for (std::size_t b = 0; b < 2; ++b)
  {
    vtkVolume* volume = outer.Add(scene.blocks[b], b);
    vtkNew<OuterVolume> holder;
    holder->SetMapper(volume->GetMapper());
    holder->SetProperty(volume->GetProperty());
    outer.stage.renderer->RemoveVolume(volume);
    outer.stage.renderer->AddVolume(holder);
    outer.volumes[b] = holder;
  }
  const ImageDifference d = Compare(outer.Render(), expected);
  EXPECT_EQ(outer.Drawn(0), scene.merged->GetNumberOfCells());
  EXPECT_EQ(outer.Drawn(1), 0);
  EXPECT_EQ(d.worst, 0.0);
  EXPECT_TRUE(outer.observer->warnings.empty());
}

TEST_P(MapperComposite, VolumesOfAnotherBlendModeAreDrawnApartWithOneWarning)
{
  // The second volume's mapper blends by maximum intensity: not one picture; each mapper
  // says so once, over two frames, and draws its own cells as VTK would.
  const Parts scene = InterleavedScenes()[1];
  const auto maximum = [](std::size_t block, vtkVolume*, Mapper* mapper)
  {
    if (block == 1)
    {
      mapper->SetBlendModeToMaximumIntensity();
    }
  };
  auto observer = vtkSmartPointer<MessageObserver>::New();
  std::vector<vtkIdType> drawn;
  auto image = DrawVolumes(scene, GetParam(), true, true, observer, &drawn, maximum);
  EXPECT_TRUE(observer->errors.empty());
  EXPECT_EQ(observer->warnings.size(), 2u); // one from each mapper
  for (const std::string& w : observer->warnings)
  {
    EXPECT_NE(w.find("another blend mode"), std::string::npos) << w;
    EXPECT_NE(w.find("one after the other"), std::string::npos) << w;
  }
  ASSERT_EQ(drawn.size(), 2u);
  EXPECT_EQ(drawn[0], scene.blocks[0]->GetNumberOfCells());
  EXPECT_EQ(drawn[1], scene.blocks[1]->GetNumberOfCells());
  EXPECT_EQ(
    Compare(image, DrawVolumes(scene, GetParam(), false, true, nullptr, nullptr, maximum)).worst,
    0.0)
    << "drawn apart, as with the switch off";
}

TEST_P(MapperComposite, EveryKindOfTreeDrawsTheSameImage)
{
  const Parts scene = InterleavedScenes()[1];
  vtkNew<Mapper> reference;
  reference->SetBackend(GetParam());
  auto expected = Draw(MultiBlock(scene.blocks), reference, scene);

  // A partitioned data set collection, and a partitioned data set.
  vtkNew<vtkPartitionedDataSetCollection> collection;
  vtkNew<vtkPartitionedDataSet> partitions;
  for (unsigned b = 0; b < scene.blocks.size(); ++b)
  {
    vtkNew<vtkPartitionedDataSet> one;
    one->SetPartition(0, scene.blocks[b]);
    collection->SetPartitionedDataSet(b, one);
    partitions->SetPartition(b, scene.blocks[b]);
  }
  // A nested multi-block: block 0, then a multi-block holding block 1.
  auto nested = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  nested->SetNumberOfBlocks(2);
  nested->SetBlock(0, scene.blocks[0]);
  nested->SetBlock(1, MultiBlock({ scene.blocks[1] }));
  for (vtkDataObject* tree : { static_cast<vtkDataObject*>(collection),
         static_cast<vtkDataObject*>(partitions), static_cast<vtkDataObject*>(nested) })
  {
    SCOPED_TRACE(tree->GetClassName());
    vtkNew<Mapper> mapper;
    mapper->SetBackend(GetParam());
    EXPECT_EQ(Compare(Draw(tree, mapper, scene), expected).worst, 0.0);
  }
}

TEST_P(MapperComposite, EmptyAndBadBlocksAreWarnedAboutOnceAndSkipped)
{
  const Parts scene = InterleavedScenes()[0];
  vtkNew<Mapper> reference;
  reference->SetBackend(GetParam());
  auto expected = Draw(MultiBlock(scene.blocks), reference, scene);

  vtkNew<vtkUnstructuredGrid> empty;
  vtkNew<vtkImageData> image;
  image->SetDimensions(3, 3, 3);
  auto unnamed = vtkSmartPointer<vtkUnstructuredGrid>::New();
  unnamed->DeepCopy(scene.blocks[1]);
  unnamed->GetPointData()->RemoveArray("field"); // no scalars to draw
  auto cellScalars = vtkSmartPointer<vtkUnstructuredGrid>::New();
  cellScalars->DeepCopy(scene.blocks[1]);
  cellScalars->GetPointData()->RemoveArray("field");
  cellScalars->GetCellData()->SetScalars(cellScalars->GetCellData()->GetArray("cellField"));
  auto tree = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  tree->SetNumberOfBlocks(7);
  tree->SetBlock(0, scene.blocks[0]);
  tree->SetBlock(1, empty);
  tree->SetBlock(2, image);
  tree->SetBlock(3, unnamed);
  tree->SetBlock(4, scene.blocks[1]);
  tree->SetBlock(5, cellScalars);
  // Block 6 left null: an empty node, silently skipped.
  tree->GetMetaData(3u)->Set(vtkCompositeDataSet::NAME(), "no field");

  auto observer = vtkSmartPointer<MessageObserver>::New();
  vtkNew<Mapper> mapper;
  mapper->SetBackend(GetParam());
  mapper->AddObserver(vtkCommand::WarningEvent, observer);
  mapper->AddObserver(vtkCommand::ErrorEvent, observer);
  auto property = MakeProperty(-0.3, 1.3, 0.3);
  Stage stage = MakeStage(tree, property, mapper, 220, 220);
  SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
  stage.window->Render();
  stage.window->Render(); // a second frame: no warning again
  auto ours = Grab(stage.window, false);
  EXPECT_EQ(Compare(ours, expected).worst, 0.0);
  EXPECT_TRUE(observer->errors.empty());
  ASSERT_EQ(observer->warnings.size(), 4u);
  auto has = [&](const std::string& text)
  {
    for (const std::string& w : observer->warnings)
    {
      if (w.find(text) != std::string::npos)
      {
        return true;
      }
    }
    return false;
  };
  EXPECT_TRUE(has("has no cells"));
  EXPECT_TRUE(has("is a vtkImageData, not an unstructured grid"));
  EXPECT_TRUE(has("'no field'"));
  EXPECT_TRUE(has("cell data where the blocks before it have point data"));
  mapper->ReleaseGraphicsResources(stage.window);
}

TEST_P(MapperComposite, EveryThreadCountDrawsTheSameImage)
{
  const Parts scene = InterleavedScenes()[1];
  auto tree = MultiBlock(scene.blocks);
  vtkSmartPointer<vtkImageData> first;
  for (int threads : { 1, 2, 3, 5 })
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackend(GetParam());
    mapper->SetNumberOfThreads(threads);
    auto image = Draw(tree, mapper, scene);
    if (!first)
    {
      first = image;
      continue;
    }
    EXPECT_EQ(Compare(image, first).worst, 0.0) << threads << " threads";
  }
}

TEST(MapperCompositeWork, AChangeToOneBlockRedoesOnlyThatBlock)
{
  // Block 0 is made of hexahedra (split into tetrahedra by the mapper), block 1 of
  // tetrahedra: changing block 1 must not split block 0 again, changing block 0 must.
  vtkNew<vtkRTAnalyticSource> source;
  source->SetWholeExtent(-4, 4, -4, 4, -4, 4);
  source->Update();
  vtkNew<vtkAppendFilter> hexahedra;
  hexahedra->AddInputData(source->GetOutput());
  hexahedra->Update();
  auto block0 = vtkSmartPointer<vtkUnstructuredGrid>::New();
  block0->DeepCopy(hexahedra->GetOutput());
  vtkNew<vtkDataSetTriangleFilter> split;
  split->SetInputData(source->GetOutput());
  split->Update();
  auto block1 = vtkSmartPointer<vtkUnstructuredGrid>::New();
  block1->DeepCopy(split->GetOutput());
  for (vtkIdType i = 0; i < block1->GetNumberOfPoints(); ++i)
  {
    double p[3];
    block1->GetPoint(i, p);
    block1->GetPoints()->SetPoint(i, p[0] + 10, p[1], p[2]); // beside block 0
  }
  auto tree = MultiBlock({ block0, block1 });
  vtkNew<Mapper> mapper;
  vtkNew<vtkVolumeProperty> property;
  property->DeepCopy(MakeProperty(40, 280, 2.0));
  Stage stage = MakeStage(tree, property, mapper, 120, 120);
  SetView(stage.renderer, { 20, 10 }, true);
  stage.window->Render();
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 1);
  // Every voxel of block 0 becomes 5 or 6 tetrahedra; all of both blocks are in view.
  EXPECT_GE(
    mapper->GetNumberOfTetrahedra(), 5 * block0->GetNumberOfCells() + block1->GetNumberOfCells());
  stage.window->Render();
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 1) << "nothing changed";
  EXPECT_TRUE(mapper->GetLastFrameReuse() & Mapper::REUSED_ORDER);
  auto* field1 = block1->GetPointData()->GetScalars();
  field1->SetTuple1(0, field1->GetTuple1(0) + 1);
  field1->Modified();
  block1->Modified();
  stage.window->Render();
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 1) << "block 0 was not split again";
  EXPECT_FALSE(mapper->GetLastFrameReuse() & Mapper::REUSED_ORDER) << "the data changed";
  block0->Modified();
  stage.window->Render();
  EXPECT_EQ(mapper->GetNumberOfTetrahedralizations(), 2) << "block 0 split again";
  mapper->ReleaseGraphicsResources(stage.window);
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperComposite,
  ::testing::Values(Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND),
  [](const ::testing::TestParamInfo<int>& info)
  { return info.param == Mapper::CPU_BACKEND ? "CPU" : "OpenGL"; });

} // namespace
