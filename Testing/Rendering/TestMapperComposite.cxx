// SPDX-License-Identifier: BSD-3-Clause
// Composite input: the cells of all blocks in one visibility order. Blocks that interleave in
// depth (an inner part inside an outer shell; two parts of interleaved slabs seen obliquely)
// must give the exact reference of the merged grid, as well as MTPT gives it on the merged
// grid itself, where VTK's vtkMultiBlockUnstructuredGridVolumeMapper, drawing one block after
// another, cannot. Partitioned collections, nested multi-blocks, empty and bad blocks, thread
// counts, and the work redone when one block changes.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkAppendFilter.h"
#include "vtkCellData.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkPoints.h"
#include "vtkFloatArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkMultiBlockDataSet.h"
#include "vtkMultiBlockUnstructuredGridVolumeMapper.h"
#include "vtkPartitionedDataSet.h"
#include "vtkPartitionedDataSetCollection.h"
#include "vtkPointData.h"
#include "vtkRTAnalyticSource.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
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
 * of it; the image. Warnings go to `observer`.
 */
vtkSmartPointer<vtkImageData> DrawVolumes(const Parts& scene, int backend, bool together,
  bool shared, MessageObserver* observer = nullptr, std::vector<vtkIdType>* drawn = nullptr)
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
    stage.renderer->AddVolume(volume);
  }
  SetView(stage.renderer, { scene.azimuth, scene.elevation }, true);
  stage.window->Render();
  stage.window->Render(); // a second frame: the group kept, no warning again
  auto image = Grab(stage.window, false);
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

TEST_P(MapperComposite, VolumesOfTheirOwnPropertiesAreDrawnApartWithOneWarning)
{
  // Two properties (equal functions, two objects): not one picture; each mapper says so
  // once, over two frames, and draws its own cells as VTK would.
  const Parts scene = InterleavedScenes()[1];
  auto observer = vtkSmartPointer<MessageObserver>::New();
  std::vector<vtkIdType> drawn;
  auto image = DrawVolumes(scene, GetParam(), true, false, observer, &drawn);
  EXPECT_TRUE(observer->errors.empty());
  EXPECT_EQ(observer->warnings.size(), 2u); // one from each mapper
  for (const std::string& w : observer->warnings)
  {
    EXPECT_NE(w.find("one after the other"), std::string::npos) << w;
  }
  ASSERT_EQ(drawn.size(), 2u);
  EXPECT_EQ(drawn[0], scene.blocks[0]->GetNumberOfCells());
  EXPECT_EQ(drawn[1], scene.blocks[1]->GetNumberOfCells());
  EXPECT_EQ(Compare(image, DrawVolumes(scene, GetParam(), false, true)).worst, 0.0)
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
