// SPDX-License-Identifier: BSD-3-Clause
// Work that follows the scene: culled cells are counted and change no pixel, frames reuse
// exactly the stages whose inputs did not change, and batched frames equal one-batch ones.
// Every reused or batched frame is compared with a fresh mapper's image of the same state.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// One window kept across frames, so the mapper under test can reuse its results.
struct Stage
{
  vtkNew<vtkVolume> volume;
  vtkNew<vtkRenderer> renderer;
  vtkNew<vtkRenderWindow> window;
  vtkSmartPointer<Mapper> mapper = vtkSmartPointer<Mapper>::New();

  Stage(vtkUnstructuredGrid* grid, vtkVolumeProperty* property, int backend)
  {
    this->mapper->SetInputData(grid);
    this->mapper->SetBackend(backend);
    this->volume->SetMapper(this->mapper);
    this->volume->SetProperty(property);
    this->renderer->SetBackground(Background[0], Background[1], Background[2]);
    this->renderer->AddVolume(this->volume);
    this->window->SetOffScreenRendering(1);
    this->window->SetSize(160, 160);
    this->window->AddRenderer(this->renderer);
    this->renderer->ResetCamera();
    this->renderer->GetActiveCamera()->Azimuth(30);
    this->renderer->GetActiveCamera()->Elevation(20);
    this->renderer->GetActiveCamera()->OrthogonalizeViewUp();
    this->renderer->ResetCameraClippingRange();
  }
  ~Stage() { this->mapper->ReleaseGraphicsResources(this->window); }
  vtkSmartPointer<vtkImageData> Frame()
  {
    this->window->Render();
    return Grab(this->window, false);
  }
  /// The same state drawn by a new mapper (nothing to reuse), then the mapper under test
  /// put back.
  vtkSmartPointer<vtkImageData> Fresh()
  {
    vtkNew<Mapper> fresh;
    fresh->SetInputData(this->mapper->GetInput());
    fresh->SetBackend(this->mapper->GetBackend());
    this->volume->SetMapper(fresh);
    auto image = this->Frame();
    fresh->ReleaseGraphicsResources(this->window);
    this->volume->SetMapper(this->mapper);
    return image;
  }
};

class MapperWork : public ::testing::TestWithParam<int>
{
};

TEST_P(MapperWork, FramesReuseExactlyWhatDidNotChange)
{
  auto box = MakeTetrahedralBox(10);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  Stage stage(box, property, GetParam());
  Mapper* m = stage.mapper;
  const int all = Mapper::REUSED_TRANSFORM | Mapper::REUSED_ORDER | Mapper::REUSED_DECOMPOSITION;

  auto first = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), 0);
  // Unchanged: no CPU stage runs, the image is the same.
  auto again = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), all);
  EXPECT_EQ(m->GetCPUStageSeconds(), 0.0);
  EXPECT_EQ(Compare(first, again).worst, 0.0);

  // A rotation: everything again; a tiny one sorts from the previous order.
  stage.renderer->GetActiveCamera()->Azimuth(0.05);
  auto rotated = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse() & all, 0);
  EXPECT_TRUE(m->GetLastFrameReuse() & Mapper::ORDER_FROM_PREVIOUS);
  EXPECT_EQ(Compare(rotated, stage.Fresh()).worst, 0.0);
  stage.renderer->GetActiveCamera()->Azimuth(20);
  auto rotatedFar = stage.Frame();
  EXPECT_FALSE(m->GetLastFrameReuse() & Mapper::ORDER_FROM_PREVIOUS);
  EXPECT_EQ(Compare(rotatedFar, stage.Fresh()).worst, 0.0);

  // Colour only: the same visible cells, nothing recomputed, the new colours drawn.
  property->GetRGBTransferFunction()->AddRGBPoint(0.5, 0.1, 0.9, 0.2);
  auto recoloured = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), all);
  EXPECT_GT(Compare(recoloured, rotatedFar).worst, 0.1);
  EXPECT_EQ(Compare(recoloured, stage.Fresh()).worst, 0.0);

  // Opacity: cells hidden, so culling, order and decomposition again, not the transform.
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity();
  opacity->RemoveAllPoints();
  opacity->AddPoint(-0.3, 0.0);
  opacity->AddPoint(0.7, 0.0);
  opacity->AddPoint(1.3, 0.9);
  auto hidden = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), Mapper::REUSED_TRANSFORM);
  EXPECT_GT(m->GetNumberOfOpacityCulledCells(), box->GetNumberOfCells() / 4);
  EXPECT_EQ(Compare(hidden, stage.Fresh()).worst, 0.0);

  // Data changed in place and marked modified: nothing reused.
  vtkDataArray* field = box->GetPointData()->GetScalars();
  for (vtkIdType i = 0; i < field->GetNumberOfTuples(); ++i)
  {
    field->SetTuple1(i, 1.0 - field->GetTuple1(i));
  }
  field->Modified();
  auto changed = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), 0);
  EXPECT_GT(Compare(changed, hidden).worst, 0.1);
  EXPECT_EQ(Compare(changed, stage.Fresh()).worst, 0.0);

  // Reuse off: every stage every frame, same image.
  m->ReuseResultsOff();
  auto plain = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), 0);
  EXPECT_GT(m->GetCPUStageSeconds(), 0.0);
  EXPECT_EQ(Compare(plain, changed).worst, 0.0);
}

TEST_P(MapperWork, BatchedFramesEqualOneBatch)
{
  auto fin = LoadBluntFin();
  auto property = MakeProperty(0.2, 4.5, 0.5);
  Stage stage(fin, property, GetParam());
  stage.mapper->SetBatchSize(0);
  auto whole = stage.Frame();
  EXPECT_EQ(stage.mapper->GetNumberOfBatches(), 1);
  const vtkIdType memoryWhole = stage.mapper->GetMemoryBytes();
  for (vtkIdType batch : { 1000, 7777 })
  {
    stage.mapper->SetBatchSize(batch);
    auto batched = stage.Frame();
    EXPECT_EQ(stage.mapper->GetNumberOfBatches(),
      (stage.mapper->GetNumberOfTetrahedra() + batch - 1) / batch);
    EXPECT_EQ(Compare(whole, batched).worst, 0.0) << batch;
    // A second frame reuses the order but must decompose every batch again.
    auto again = stage.Frame();
    EXPECT_TRUE(stage.mapper->GetLastFrameReuse() & Mapper::REUSED_ORDER);
    EXPECT_EQ(Compare(whole, again).worst, 0.0) << batch;
  }
  // A fresh mapper with small batches holds less memory than one batch of everything.
  vtkNew<Mapper> small;
  small->SetBatchSize(1000);
  small->SetBackend(GetParam());
  stage.volume->SetMapper(small);
  small->SetInputData(fin);
  stage.Frame();
  EXPECT_LT(small->GetMemoryBytes(), memoryWhole - 100 * 1000 * 100);
  small->ReleaseGraphicsResources(stage.window);
  stage.volume->SetMapper(stage.mapper);
  // Rejected setting.
  stage.mapper->SetBatchSize(-5);
  EXPECT_EQ(stage.mapper->GetBatchSize(), 7777);
}

TEST_P(MapperWork, CulledCellsAreCountedAndChangeNothing)
{
  auto box = MakeTetrahedralBox(10);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  Stage stage(box, property, GetParam());
  stage.renderer->GetActiveCamera()->Zoom(2.5); // part of the box leaves the view
  stage.renderer->ResetCameraClippingRange();
  Mapper* m = stage.mapper;
  const vtkIdType cells = box->GetNumberOfCells();
  // Each culled frame against the same mapper drawing every cell: the same pixels.
  auto compareWithAllCells = [&](vtkImageData* ours)
  {
    m->CullInvisibleCellsOff();
    auto all = stage.Frame();
    EXPECT_EQ(m->GetNumberOfTetrahedra(), cells);
    m->CullInvisibleCellsOn();
    EXPECT_EQ(Compare(ours, all).worst, 0.0);
    EXPECT_GT(CoveredFraction(ours, Background), 0.1);
  };
  auto zoomed = stage.Frame();
  EXPECT_EQ(m->GetNumberOfOpacityCulledCells(), 0);
  EXPECT_GT(m->GetNumberOfFrustumCulledCells(), cells / 20);
  EXPECT_EQ(m->GetNumberOfFrustumCulledCells() + m->GetNumberOfPixelCulledCells() +
      m->GetNumberOfTetrahedra(),
    cells);
  compareWithAllCells(zoomed);

  vtkPiecewiseFunction* opacity = property->GetScalarOpacity();
  opacity->RemoveAllPoints();
  opacity->AddPoint(-0.3, 0.0);
  opacity->AddPoint(0.6, 0.0);
  opacity->AddPoint(1.3, 0.9);
  auto hidden = stage.Frame();
  EXPECT_GT(m->GetNumberOfOpacityCulledCells(), cells / 3);
  EXPECT_EQ(m->GetNumberOfOpacityCulledCells() + m->GetNumberOfFrustumCulledCells() +
      m->GetNumberOfPixelCulledCells() + m->GetNumberOfTetrahedra(),
    cells);
  compareWithAllCells(hidden);
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperWork,
  ::testing::Values(Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND),
  [](const ::testing::TestParamInfo<int>& info)
  { return info.param == Mapper::CPU_BACKEND ? "CPU" : "OpenGL"; });

} // namespace
