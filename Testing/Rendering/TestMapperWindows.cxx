// SPDX-License-Identifier: BSD-3-Clause
// Every window VTK makes, and every change between two frames:
// - the matrix {multisampling as VTK sets it, off} x {on-screen, off-screen} x {automatic,
//   OpenGL, CPU backend} on a real mesh, each against VTK's PT in the same process and all
//   against each other (a multisampled window once gave an all-black image);
// - switching backend, shading mode, window size, renderer or window between any two frames
//   gives exactly the image a fresh mapper gives (switching backends once drew the previous
//   view's triangles);
// - the OpenGL objects of a window the mapper leaves are freed in that window's context,
//   not in the new one's (where the same names belong to other objects).
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkConeSource.h"
#include "vtkImageData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

class MapperWindows : public ::testing::Test
{
protected:
  static void SetUpTestSuite() { BluntFin = ShuffleCells(LoadBluntFin(), 3); }
  static void TearDownTestSuite() { BluntFin = nullptr; }
  static Scene FinScene() { return MakeScene(BluntFin, MakeBluntFinProperty(), false); }
  static vtkSmartPointer<vtkUnstructuredGrid> BluntFin;
};
vtkSmartPointer<vtkUnstructuredGrid> MapperWindows::BluntFin;

TEST_F(MapperWindows, EveryWindowKindAndBackendMatchesVTK)
{
  struct Result
  {
    std::string label;
    vtkSmartPointer<vtkImageData> image;
  };
  std::vector<Result> results;
  for (const bool offScreen : { true, false })
  {
    // VTK's PT single-sampled: multisampled, it speckles along cell edges (measured below).
    Scene theirs = FinScene();
    theirs.window = { offScreen, 0 };
    vtkNew<vtkProjectedTetrahedraMapper> vtkpt;
    auto reference = Render(theirs, vtkpt);
    for (const int samples : { -1, 0 })
    {
      Scene ours = FinScene();
      ours.window = { offScreen, samples };
      const std::string window = std::string(offScreen ? "off-screen" : "on-screen") +
        (samples < 0 ? ", multisampled (VTK's default)" : ", single-sampled");
      if (samples < 0)
      {
        vtkNew<vtkProjectedTetrahedraMapper> multisampled;
        const ImageDifference d = Compare(Render(ours, multisampled), reference);
        std::printf("VTK's PT, %s against single-sampled: RMSE over covered pixels %.5f, worst "
                    "%.3f, covered pixels over 0.1: %.3f%%\n",
          window.c_str(), d.coveredRmse, d.worst, 100 * d.fractionOver);
      }
      for (const int backend :
        { Mapper::AUTOMATIC_BACKEND, Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
      {
        vtkNew<Mapper> mapper;
        mapper->SetBackend(backend);
        auto image = Render(ours, mapper);
        const std::string label = window + ", " + BackendName(backend) + " backend";
        // Measured (blunt fin, orthographic): RMSE 0.0020, worst 0.016 in every window.
        ExpectClose(image, reference, { 0.003, 0.03, 0.001 }, label + " vs VTK's PT", 0.2);
        results.push_back({ label, image });
      }
    }
  }
  // All twelve are one image, up to the two backends' rounding (measured worst 0.008).
  for (const Result& r : results)
  {
    const ImageDifference d = Compare(r.image, results.front().image);
    EXPECT_LE(d.worst, 0.02) << r.label << " vs " << results.front().label;
    EXPECT_LE(d.coveredRmse, 0.001) << r.label << " vs " << results.front().label;
  }
}

/// One window kept across frames; the mapper under test and, for comparison, a fresh
/// mapper with the same settings drawn in the same window and state.
class Sequence
{
public:
  Sequence(vtkUnstructuredGrid* grid, vtkVolumeProperty* property)
  {
    this->Under = vtkSmartPointer<Mapper>::New();
    this->Stage = MakeStage(grid, property, this->Under, 180, 150);
    SetView(this->Stage.renderer, Views[0], true);
  }
  ~Sequence() { this->Under->ReleaseGraphicsResources(this->Stage.window); }

  /// Renders with the mapper under test and with a fresh one; the images must be equal.
  void Check(const std::string& step)
  {
    this->Stage.window->Render();
    auto image = Grab(this->Stage.window, false);
    vtkNew<Mapper> fresh;
    fresh->SetInputData(this->Under->GetInput());
    fresh->SetBackend(this->Under->GetBackend());
    fresh->SetShadingMode(this->Under->GetShadingMode());
    this->Stage.volume->SetMapper(fresh);
    this->Stage.window->Render();
    auto expected = Grab(this->Stage.window, false);
    fresh->ReleaseGraphicsResources(this->Stage.window);
    this->Stage.volume->SetMapper(this->Under);
    const ImageDifference d = Compare(image, expected);
    EXPECT_EQ(d.worst, 0.0) << step << ": RMSE " << d.rmse;
    EXPECT_GT(CoveredFraction(image, Background), 0.05) << step;
  }
  void Rotate(double degrees)
  {
    this->Stage.renderer->GetActiveCamera()->Azimuth(degrees);
    this->Stage.renderer->ResetCameraClippingRange();
  }

  mtpt::rendering_test::Stage Stage;
  vtkSmartPointer<Mapper> Under;
  vtkSmartPointer<vtkRenderWindow> Other;
};

TEST_F(MapperWindows, AnyChangeBetweenFramesGivesAFreshMappersImage)
{
  Sequence s(BluntFin, MakeBluntFinProperty());
  Mapper* m = s.Under;
  m->SetBackendToOpenGL();
  s.Check("OpenGL");
  // The case that once drew the previous view: OpenGL, then CPU at a new view, then OpenGL
  // at that view (the OpenGL buffers still held the first view's triangles).
  s.Rotate(25);
  m->SetBackendToCPU();
  s.Check("CPU after a rotation");
  m->SetBackendToOpenGL();
  s.Check("OpenGL again at the CPU frame's view");
  m->SetShadingModeToPreIntegrated();
  s.Check("pre-integrated shading");
  m->SetBackendToCPU();
  s.Check("pre-integrated, CPU");
  m->SetShadingModeToVTKCompatible();
  s.Rotate(-40);
  s.Check("VTK-compatible, CPU, rotated");
  s.Stage.window->SetSize(230, 170);
  s.Check("window resized");
  m->SetBackendToOpenGL();
  s.Check("OpenGL after the resize");
  // Another renderer (another viewport) in the same window.
  vtkNew<vtkRenderer> second;
  second->SetViewport(0.3, 0.0, 1.0, 0.8);
  second->SetBackground(Background[0], Background[1], Background[2]);
  s.Stage.renderer->RemoveVolume(s.Stage.volume);
  s.Stage.window->RemoveRenderer(s.Stage.renderer);
  second->AddVolume(s.Stage.volume);
  s.Stage.window->AddRenderer(second);
  SetView(second, Views[1], true);
  s.Check("another renderer");
  m->SetBackendToCPU();
  s.Check("another renderer, CPU");
  // Another window.
  s.Other = vtkSmartPointer<vtkRenderWindow>::New();
  s.Other->SetOffScreenRendering(1);
  s.Other->SetSize(160, 200);
  s.Stage.window->RemoveRenderer(second);
  s.Other->AddRenderer(second);
  std::swap(s.Stage.window, s.Other);
  s.Check("another window, CPU");
  m->SetBackendToOpenGL();
  s.Check("another window, OpenGL");
}

/// A window with OpenGL objects of its own (a cone, a volume drawn by VTK's PT), drawn a few
/// times before a volume drawn by `mapper` joins it.
vtkSmartPointer<vtkImageData> BusyWindowImage(
  vtkUnstructuredGrid* grid, vtkVolumeProperty* property, Mapper* mapper)
{
  vtkNew<vtkProjectedTetrahedraMapper> theirs;
  const Stage stage = MakeStage(grid, property, theirs, 200, 200);
  stage.volume->SetPosition(1.2, 0.3, -0.5);
  vtkNew<vtkConeSource> cone;
  cone->SetHeight(1.5);
  cone->SetRadius(0.5);
  vtkNew<vtkPolyDataMapper> coneMapper;
  coneMapper->SetInputConnection(cone->GetOutputPort());
  vtkNew<vtkActor> actor;
  actor->SetMapper(coneMapper);
  actor->GetProperty()->SetColor(0.9, 0.4, 0.2);
  stage.renderer->AddActor(actor);
  SetView(stage.renderer, Views[0], true);
  stage.window->Render();
  stage.window->Render();
  vtkNew<vtkVolume> ours;
  mapper->SetInputData(grid);
  ours->SetMapper(mapper);
  ours->SetProperty(property);
  stage.renderer->AddVolume(ours);
  stage.window->Render();
  stage.window->Render();
  auto image = Grab(stage.window, false);
  mapper->ReleaseGraphicsResources(stage.window);
  return image;
}

TEST_F(MapperWindows, LeavingAWindowFreesItsObjectsInItsOwnContext)
{
  auto box = MakeTetrahedralBox(6);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    // The mapper draws in window A, creating its objects there, then moves to window B,
    // which has objects of its own (freeing A's names in B's context would free some of
    // those); B must draw as it draws with a mapper that never was anywhere else.
    vtkNew<Mapper> traveller;
    traveller->SetBackend(backend);
    const Stage a = MakeStage(box, property, traveller, 120, 120);
    SetView(a.renderer, Views[1], false);
    a.window->Render();
    auto image = BusyWindowImage(box, property, traveller);
    vtkNew<Mapper> homebody;
    homebody->SetBackend(backend);
    const ImageDifference d = Compare(image, BusyWindowImage(box, property, homebody));
    EXPECT_EQ(d.worst, 0.0) << BackendName(backend) << ": RMSE " << d.rmse;
    EXPECT_GT(CoveredFraction(image, Background), 0.1);
  }
}

} // namespace
