// SPDX-License-Identifier: BSD-3-Clause
// Work that follows the scene: culled cells are counted and change no pixel, frames reuse
// exactly the stages whose inputs did not change, and batched frames equal one-batch ones.
// Every reused or batched frame is compared with a fresh mapper's image of the same state.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPlane.h"
#include "vtkPointData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
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
    fresh->SetShadingMode(this->mapper->GetShadingMode());
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
  // The CPU backend also keeps its composited image for a frame that changes nothing.
  const int unchanged = all | (GetParam() == Mapper::CPU_BACKEND ? Mapper::REUSED_IMAGE : 0);

  auto first = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), 0);
  // Unchanged: no CPU stage runs, the image is the same.
  auto again = stage.Frame();
  EXPECT_EQ(m->GetLastFrameReuse(), unchanged);
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

  // Colour only: the same visible cells, no CPU stage, the new colours drawn (composited
  // again by the CPU backend).
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

TEST_P(MapperWork, BatchesFrontToBackLeaveOutWhatOpaquePixelsHide)
{
  // A box that turns opaque a short way in, drawn in batches: the CPU backend takes them
  // front to back and leaves out the cells behind the pixels the nearer batches made
  // opaque, and the image is the one batch's exactly, in either shading, cut by a plane or
  // lit; OpenGL draws every cell.
  auto box = MakeTetrahedralBox(16);
  auto property = MakeProperty(-0.3, 1.3, 0.01);
  Stage stage(box, property, GetParam());
  Mapper* m = stage.mapper;
  vtkNew<vtkPlane> plane; // keeps the half of the box on the camera's side of its centre
  plane->SetOrigin(0.0, 0.0, 0.0);
  plane->SetNormal(stage.renderer->GetActiveCamera()->GetDirectionOfProjection());
  plane->SetNormal(-plane->GetNormal()[0], -plane->GetNormal()[1], -plane->GetNormal()[2]);
  vtkSmartPointer<vtkImageData> plain;
  for (const char* variant : { "VTK-compatible", "pre-integrated", "clipped", "lit" })
  {
    const std::string what = variant;
    m->SetShadingMode(what == "pre-integrated" ? Mapper::PRE_INTEGRATED_SHADING
                                                   : Mapper::VTK_COMPATIBLE_SHADING);
    m->RemoveAllClippingPlanes();
    if (what == "clipped")
    {
      m->AddClippingPlane(plane);
    }
    property->SetShade(what == "lit");
    m->SetBatchSize(0);
    auto whole = stage.Frame();
    EXPECT_EQ(m->GetNumberOfHiddenCells(), 0) << what << ": one batch, nothing in front of it";
    EXPECT_LT(CoveredFraction(whole, Background), 0.9) << what; // the box, not the window
    if (!plain)
    {
      plain = whole;
    }
    else
    {
      EXPECT_GT(Compare(whole, plain).worst, 0.01) << what << " draws its own image";
    }
    m->SetBatchSize(1500);
    auto batched = stage.Frame();
    EXPECT_GT(m->GetNumberOfBatches(), 10) << what;
    EXPECT_EQ(Compare(batched, whole).worst, 0.0) << what;
    if (GetParam() == Mapper::CPU_BACKEND)
    {
      EXPECT_GT(m->GetNumberOfHiddenCells(), m->GetNumberOfTetrahedra() / 3) << what;
    }
    else
    {
      EXPECT_EQ(m->GetNumberOfHiddenCells(), 0) << what;
    }
  }
  // Turned: a new order, and a fresh mapper's image (one batch, its default size).
  m->SetShadingModeToVTKCompatible();
  m->RemoveAllClippingPlanes();
  property->ShadeOff();
  stage.renderer->GetActiveCamera()->Azimuth(7);
  auto turned = stage.Frame();
  if (GetParam() == Mapper::CPU_BACKEND)
  {
    EXPECT_GT(m->GetNumberOfHiddenCells(), m->GetNumberOfTetrahedra() / 3) << "turned";
  }
  EXPECT_EQ(Compare(turned, stage.Fresh()).worst, 0.0);
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

TEST(MapperImageReuse, OnlyAFrameThatChangesNothingReusesTheCompositedImage)
{
  // The CPU backend's composited image depends on the view, the data, the transfer
  // functions, the window size and the depth of the opaque geometry; the colour beneath it
  // (background, opaque surfaces) is blended in every frame. Each change below must draw
  // exactly what a fresh mapper draws, and only unchanged frames may reuse the image.
  auto box = MakeTetrahedralBox(10);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  Stage stage(box, property, Mapper::CPU_BACKEND);
  Mapper* m = stage.mapper;
  vtkNew<vtkSphereSource> ball;
  ball->SetCenter(0.5, 0.5, 0.5);
  ball->SetRadius(0.3);
  ball->SetThetaResolution(24);
  ball->SetPhiResolution(24);
  vtkNew<vtkPolyDataMapper> ballMapper;
  ballMapper->SetInputConnection(ball->GetOutputPort());
  vtkNew<vtkActor> opaque;
  opaque->SetMapper(ballMapper);
  opaque->GetProperty()->SetColor(0.9, 0.8, 0.1);
  stage.renderer->AddActor(opaque);
  auto isReused = [m] { return (m->GetLastFrameReuse() & Mapper::REUSED_IMAGE) != 0; };

  auto first = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_GT(m->GetNumberOfFragments(), 1000);
  auto again = stage.Frame();
  EXPECT_TRUE(isReused());
  EXPECT_EQ(m->GetNumberOfFragments(), 0);
  EXPECT_EQ(m->GetBinSeconds(), 0.0); // no binning, no rasterization: only the resolve
  EXPECT_EQ(m->GetRasterSeconds(), 0.0);
  EXPECT_EQ(Compare(first, again).worst, 0.0);

  // The colour beneath changes: the image is reused, blended over the new colour.
  stage.renderer->SetBackground(0.3, 0.1, 0.2);
  auto background = stage.Frame();
  EXPECT_TRUE(isReused());
  EXPECT_GT(Compare(background, first).worst, 0.05);
  EXPECT_EQ(Compare(background, stage.Fresh()).worst, 0.0);
  opaque->GetProperty()->SetColor(0.1, 0.3, 0.9);
  auto recolouredBall = stage.Frame();
  EXPECT_TRUE(isReused());
  EXPECT_EQ(Compare(recolouredBall, stage.Fresh()).worst, 0.0);

  // The opaque geometry moves: its depth differs, so the volume is composited again.
  opaque->SetPosition(0.15, 0.0, 0.0);
  auto moved = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_GT(Compare(moved, recolouredBall).worst, 0.05);
  EXPECT_EQ(Compare(moved, stage.Fresh()).worst, 0.0);
  stage.Frame();
  EXPECT_TRUE(isReused());

  // The opaque geometry goes (nothing occludes the volume: its depth is not even read back)
  // and comes back.
  stage.renderer->RemoveActor(opaque);
  auto alone = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_GT(Compare(alone, moved).worst, 0.05);
  EXPECT_EQ(Compare(alone, stage.Fresh()).worst, 0.0);
  stage.Frame();
  EXPECT_TRUE(isReused());
  stage.renderer->AddActor(opaque);
  auto back = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_EQ(Compare(back, moved).worst, 0.0);

  // The transfer function's colour and the unit distance.
  property->GetRGBTransferFunction()->AddRGBPoint(0.5, 0.1, 0.9, 0.2);
  auto recoloured = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_EQ(Compare(recoloured, stage.Fresh()).worst, 0.0);
  property->SetScalarOpacityUnitDistance(0.2);
  auto denser = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_GT(Compare(denser, recoloured).worst, 0.05);
  EXPECT_EQ(Compare(denser, stage.Fresh()).worst, 0.0);

  // Shading mode, window size and a view change.
  m->SetShadingModeToPreIntegrated();
  auto integrated = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_EQ(Compare(integrated, stage.Fresh()).worst, 0.0);
  m->SetShadingModeToVTKCompatible();
  stage.window->SetSize(130, 150);
  auto resized = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_EQ(Compare(resized, stage.Fresh()).worst, 0.0);
  stage.renderer->GetActiveCamera()->Azimuth(0.5);
  auto turned = stage.Frame();
  EXPECT_FALSE(isReused());
  EXPECT_EQ(Compare(turned, stage.Fresh()).worst, 0.0);

  // Reuse off: composited every frame.
  m->ReuseResultsOff();
  stage.Frame();
  EXPECT_FALSE(isReused());
  stage.Frame();
  EXPECT_FALSE(isReused());
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperWork,
  ::testing::Values(Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND),
  [](const ::testing::TestParamInfo<int>& info)
  { return info.param == Mapper::CPU_BACKEND ? "CPU" : "OpenGL"; });

} // namespace
