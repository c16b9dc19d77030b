// SPDX-License-Identifier: BSD-3-Clause
// The scenes VTK's own projected-tetrahedra regression tests draw, set up again here in
// this project's terms and drawn in VTK's default window (multisampled): the iron protein
// thresholded and tetrahedralized with an opaque contour in it; a camera zoomed inside that
// volume; two small volumes, one moved by a user transform, among opaque cones; colouring by
// one component of a point vector array chosen by name; one window drawn on-screen, then
// off-screen, then on-screen again. Each is compared with VTK's PT drawing the same scene in
// the same process (and with the exact reference where VTK's PT is known to be wrong), with
// thresholds from measurement (Mesa llvmpipe; figures in the comments) and a non-blank
// check.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkCellTypeSource.h"
#include "vtkColorTransferFunction.h"
#include "vtkConeSource.h"
#include "vtkContourFilter.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkDoubleArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyDataMapper.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkStructuredPoints.h"
#include "vtkStructuredPointsReader.h"
#include "vtkThreshold.h"
#include "vtkTransform.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;
using NewMapper = std::function<vtkSmartPointer<vtkUnstructuredGridVolumeMapper>()>;

/// Builds a scene in `renderer` with volumes drawn by mappers from `newMapper`, and returns
/// the volume whose exact reference the test may compare with.
using Build = std::function<vtkVolume*(vtkRenderer* renderer, const NewMapper& newMapper)>;

/// "gl", "cpu", or "vtkpt" for VTK's PT.
const char* Name(int backend)
{
  return backend == Mapper::CPU_BACKEND ? "cpu" : (backend < 0 ? "vtkpt" : "gl");
}

/// The scene `build` makes, drawn in a window of VTK's default kind by VTK's PT (backend
/// -1) or this mapper through `backend` with `shading`; `reference`, when given, receives
/// the exact reference image of the volume `build` returned.
vtkSmartPointer<vtkImageData> Draw(const Build& build, int backend, int size,
  vtkSmartPointer<vtkImageData>* reference = nullptr, int shading = Mapper::VTK_COMPATIBLE_SHADING)
{
  std::vector<vtkSmartPointer<vtkUnstructuredGridVolumeMapper>> mappers;
  NewMapper newMapper = [&]() -> vtkSmartPointer<vtkUnstructuredGridVolumeMapper>
  {
    if (backend < 0)
    {
      mappers.push_back(vtkSmartPointer<vtkProjectedTetrahedraMapper>::New());
    }
    else
    {
      auto mapper = vtkSmartPointer<Mapper>::New();
      mapper->SetBackend(backend);
      mapper->SetShadingMode(shading);
      mappers.push_back(mapper);
    }
    return mappers.back();
  };
  Stage stage;
  stage.renderer = vtkSmartPointer<vtkRenderer>::New();
  stage.renderer->SetBackground(Background[0], Background[1], Background[2]);
  stage.window = vtkSmartPointer<vtkRenderWindow>::New();
  stage.window->SetOffScreenRendering(1);
  stage.window->SetSize(size, size);
  stage.window->AddRenderer(stage.renderer);
  stage.volume = build(stage.renderer, newMapper);
  // Twice, as an interactive application does: VTK's PT draws no volume in the first
  // frame of some scenes (the two cubes below).
  stage.window->Render();
  stage.window->Render();
  auto image = Grab(stage.window, false);
  if (reference)
  {
    *reference = ReferenceImage(stage);
  }
  for (auto& mapper : mappers)
  {
    mapper->ReleaseGraphicsResources(stage.window);
  }
  return image;
}

/// What an ExpectScene compares with the exact reference, when anything.
struct ToReference
{
  Limits vtkCompatible; ///< this mapper's default shading
  Limits preIntegrated; ///< pre-integrated shading
};

/// Draws `build` with VTK's PT and this mapper's two backends and checks each of this
/// mapper's images against VTK's, and, with `toReference`, against the exact reference in
/// both shading modes. Covered pixels are those unlike the renderer's background,
/// `background`.
void ExpectScene(const Build& build, const std::string& name, int size, const Limits& toVTK,
  const ToReference* toReference = nullptr, const double* background = Background)
{
  auto theirs = Draw(build, -1, size);
  Save(theirs, name + "-vtkpt");
  vtkSmartPointer<vtkImageData> reference;
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    auto ours = Draw(build, backend, size, toReference && !reference ? &reference : nullptr);
    const std::string label = name + " (" + Name(backend) + ")";
    Save(ours, name + "-" + Name(backend));
    ExpectClose(ours, theirs, toVTK, label + " vs VTK's PT", 0.05, background);
    if (!toReference)
    {
      continue;
    }
    ASSERT_TRUE(reference);
    ExpectClose(ours, reference, toReference->vtkCompatible, label + " vs the exact reference",
      0.05, background);
    auto preIntegrated = Draw(build, backend, size, nullptr, Mapper::PRE_INTEGRATED_SHADING);
    ExpectClose(preIntegrated, reference, toReference->preIntegrated,
      label + ", pre-integrated, vs the exact reference", 0.05, background);
  }
  if (reference)
  {
    Save(reference, name + "-reference");
    const ImageDifference d = Compare(theirs, reference, background);
    std::printf("%s: VTK's PT vs the exact reference: RMSE over covered pixels %.5f, worst "
                "%.3f, covered pixels over 0.1: %.3f%%\n",
      name.c_str(), d.coveredRmse, d.worst, 100 * d.fractionOver);
  }
}

/// The iron protein above 80, tetrahedralized, with the transfer functions of VTK's test.
vtkSmartPointer<vtkUnstructuredGrid> IronProtein(vtkSmartPointer<vtkImageData>* image)
{
  vtkNew<vtkStructuredPointsReader> reader;
  reader->SetFileName(MTPT_SOURCE_DIR "/Testing/Data/ironProt.vtk");
  vtkNew<vtkThreshold> threshold;
  threshold->SetThresholdFunction(vtkThreshold::THRESHOLD_UPPER);
  threshold->SetUpperThreshold(80.0);
  threshold->SetInputConnection(reader->GetOutputPort());
  vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
  tetrahedralize->SetInputConnection(threshold->GetOutputPort());
  tetrahedralize->Update();
  if (image)
  {
    *image = reader->GetOutput();
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(tetrahedralize->GetOutput());
  return grid;
}

vtkSmartPointer<vtkVolumeProperty> IronProteinProperty()
{
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(80.0, 0.0);
  opacity->AddPoint(120.0, 0.2);
  opacity->AddPoint(255.0, 0.2);
  vtkNew<vtkColorTransferFunction> colour;
  colour->AddRGBPoint(80.0, 0.0, 0.0, 0.0);
  colour->AddRGBPoint(120.0, 0.0, 0.0, 1.0);
  colour->AddRGBPoint(160.0, 1.0, 0.0, 0.0);
  colour->AddRGBPoint(200.0, 0.0, 1.0, 0.0);
  colour->AddRGBPoint(255.0, 0.0, 1.0, 1.0);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetInterpolationTypeToLinear();
  return property;
}

vtkVolume* AddVolume(vtkRenderer* renderer, vtkUnstructuredGridVolumeMapper* mapper,
  vtkUnstructuredGrid* grid, vtkVolumeProperty* property)
{
  mapper->SetInputData(grid);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  renderer->AddVolume(volume);
  return volume;
}

/**
 * `mapper`, drawing its volume by itself when it is MTPT's (CompositeWithOtherVolumes off):
 * as VTK's PT draws the volumes of a renderer, one after the other, for the scenes that
 * compare two volumes with VTK's PT. Where such volumes overlap on screen, VTK's PT lays the
 * one drawn second over the other whatever their depth; MTPT draws them together by default
 * (MapperComposite's tests).
 */
vtkSmartPointer<vtkUnstructuredGridVolumeMapper> Apart(
  vtkSmartPointer<vtkUnstructuredGridVolumeMapper> mapper)
{
  if (auto* ours = Mapper::SafeDownCast(mapper))
  {
    ours->SetCompositeWithOtherVolumes(false);
  }
  return mapper;
}

class MapperVTKScenarios : public ::testing::Test
{
protected:
  static void SetUpTestSuite() { Protein = IronProtein(&ProteinImage); }
  static void TearDownTestSuite()
  {
    Protein = nullptr;
    ProteinImage = nullptr;
  }
  static vtkSmartPointer<vtkUnstructuredGrid> Protein;
  static vtkSmartPointer<vtkImageData> ProteinImage;
};
vtkSmartPointer<vtkUnstructuredGrid> MapperVTKScenarios::Protein;
vtkSmartPointer<vtkImageData> MapperVTKScenarios::ProteinImage;

TEST_F(MapperVTKScenarios, IronProteinWithAnOpaqueContour)
{
  std::printf("iron protein above 80: %lld tetrahedra\n",
    static_cast<long long>(Protein->GetNumberOfCells()));
  auto property = IronProteinProperty();
  const Build build = [&](vtkRenderer* renderer, const NewMapper& newMapper)
  {
    vtkVolume* volume = AddVolume(renderer, newMapper(), Protein, property);
    // An opaque surface inside the volume: the densest core of the protein.
    vtkNew<vtkContourFilter> contour;
    contour->SetValue(0, 200);
    contour->SetInputData(ProteinImage);
    vtkNew<vtkPolyDataMapper> surfaceMapper;
    surfaceMapper->SetInputConnection(contour->GetOutputPort());
    surfaceMapper->ScalarVisibilityOff();
    vtkNew<vtkActor> surface;
    surface->SetMapper(surfaceMapper);
    surface->GetProperty()->SetColor(0.9, 0.85, 0.7);
    renderer->AddViewProp(surface);
    renderer->ResetCamera();
    renderer->GetActiveCamera()->Azimuth(20.0);
    renderer->GetActiveCamera()->Elevation(10.0);
    renderer->GetActiveCamera()->Zoom(1.5);
    renderer->ResetCameraClippingRange();
    return volume;
  };
  // Measured RMSE 0.017, worst 0.21, 0.5% of covered pixels over 0.1: VTK's PT speckles in
  // this multisampled window, and the two mappers test different depths against the surface.
  ExpectScene(build, "iron-protein", 300, { 0.03, 0.35, 0.015 });
}

TEST_F(MapperVTKScenarios, CameraZoomedInsideTheVolume)
{
  auto property = IronProteinProperty();
  const Build build = [&](vtkRenderer* renderer, const NewMapper& newMapper)
  {
    vtkVolume* volume = AddVolume(renderer, newMapper(), Protein, property);
    renderer->ResetCamera();
    vtkCamera* camera = renderer->GetActiveCamera();
    camera->SetFocalPoint(33, 33, 33);
    camera->SetPosition(43, 38, 61);
    camera->SetViewUp(0, 1, 0);
    camera->SetViewAngle(20);
    camera->SetClippingRange(0.1, 135);
    return volume;
  };
  // Measured against VTK's PT: RMSE 0.010, worst 0.086 (it drops the cells the near plane cuts,
  // this mapper draws their visible part). Against the exact reference: VTK-compatible
  // shading 0.019 and 0.12 (vertex classification over a steep transfer function; VTK's PT
  // 0.028 and 0.17), pre-integrated 0.0012 and 0.004.
  const ToReference reference{ { 0.025, 0.2, 0.01 }, { 0.003, 0.02, 0 } };
  ExpectScene(build, "zoomed-in", 300, { 0.02, 0.15, 0.005 }, &reference);
}

/// A unit cube of tetrahedra with the scalar x + y + z, coloured `r, g, b`.
vtkSmartPointer<vtkUnstructuredGrid> Cube()
{
  vtkNew<vtkCellTypeSource> source;
  source->SetCellType(VTK_TETRA);
  source->SetBlocksDimensions(3, 3, 3);
  source->Update();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(source->GetOutput());
  vtkNew<vtkDoubleArray> scalars;
  scalars->SetName("sum");
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i)
  {
    const double* p = grid->GetPoint(i);
    scalars->InsertNextValue((p[0] + p[1] + p[2]) / 3.0);
  }
  grid->GetPointData()->SetScalars(scalars);
  return grid;
}

vtkSmartPointer<vtkVolumeProperty> CubeProperty(double r, double g, double b)
{
  vtkNew<vtkColorTransferFunction> colour;
  colour->AddRGBPoint(0.0, r, g, b);
  colour->AddRGBPoint(3.0, 0.5 * r, 0.5 * g, 0.5 * b);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.2);
  opacity->AddPoint(3.0, 0.9);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(0.5);
  return property;
}

vtkSmartPointer<vtkActor> Cone(double r, double g, double b, vtkTransform* transform)
{
  vtkNew<vtkConeSource> source;
  source->SetCenter(0.0, 0.0, 0.0);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputConnection(source->GetOutputPort());
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(r, g, b);
  actor->SetUserTransform(transform);
  return actor;
}

TEST_F(MapperVTKScenarios, TwoVolumesOneMovedByAUserTransformAmongCones)
{
  auto cube = Cube();
  auto red = CubeProperty(1, 0.2, 0.1), blue = CubeProperty(0.1, 0.3, 1);
  vtkNew<vtkTransform> transform;
  transform->Translate(1.5, 0.5, -1.0);
  transform->RotateY(30);
  // Drawn one after the other, as VTK's PT draws them: together, the red cube lies over the
  // blue one behind it where the two overlap on screen, where VTK's PT, drawing the blue one
  // second, puts the blue over the red (MapperComposite's tests draw volumes together).
  const Build build = [&](vtkRenderer* renderer, const NewMapper& newMapper)
  {
    vtkVolume* first = AddVolume(renderer, Apart(newMapper()), cube, red);
    vtkVolume* second = AddVolume(renderer, Apart(newMapper()), cube, blue);
    second->SetUserTransform(transform);
    renderer->AddActor(Cone(1, 0.5, 0.5, nullptr));
    renderer->AddActor(Cone(0.5, 0.5, 1, transform));
    renderer->SetBackground(1, 1, 1);
    renderer->ResetCamera();
    renderer->GetActiveCamera()->Azimuth(25);
    renderer->GetActiveCamera()->Elevation(15);
    renderer->ResetCameraClippingRange();
    return first;
  };
  const double white[3] = { 1, 1, 1 };
  // Measured RMSE 0.0045, worst 0.30 (VTK's PT speckles in the multisampled window).
  ExpectScene(build, "two-volumes", 300, { 0.01, 0.4, 0.005 }, nullptr, white);
}

TEST_F(MapperVTKScenarios, ColouredByOneComponentOfAVectorArrayChosenByName)
{
  // VTK's test: tetrahedra of a 10^3 block source, a point vector array "coords" (a copy of
  // the point coordinates), coloured and made opaque by its y component, chosen by name.
  vtkNew<vtkCellTypeSource> source;
  source->SetCellType(VTK_TETRA);
  source->SetBlocksDimensions(10, 10, 10);
  source->Update();
  auto grid = ShuffleCells(vtkUnstructuredGrid::SafeDownCast(source->GetOutput()), 4);
  vtkNew<vtkDoubleArray> coords;
  coords->DeepCopy(grid->GetPoints()->GetData());
  coords->SetName("coords");
  grid->GetPointData()->AddArray(coords);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(10.0, 0.3);
  vtkNew<vtkColorTransferFunction> colour;
  colour->AddRGBPoint(0.0, 0.1, 0.1, 0.1);
  colour->AddRGBPoint(10.0, 0.1, 1.0, 0.2);
  colour->SetVectorMode(vtkScalarsToColors::COMPONENT);
  colour->SetVectorComponent(1); // y
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(2.0);
  const Build build = [&](vtkRenderer* renderer, const NewMapper& newMapper)
  {
    auto mapper = newMapper();
    mapper->SetScalarModeToUsePointFieldData();
    mapper->SetArrayAccessMode(VTK_GET_ARRAY_BY_NAME);
    mapper->SelectScalarArray("coords");
    vtkVolume* volume = AddVolume(renderer, mapper, grid, property);
    SetView(renderer, Views[2], true);
    return volume;
  };
  // Measured: against VTK's PT RMSE 0.0034, worst 0.18 (its speckles); against the exact
  // reference 0.0015-0.0016 and 0.004 in both shadings (VTK's PT: 0.0035 and 0.18).
  const ToReference reference{ { 0.003, 0.02, 0 }, { 0.003, 0.02, 0 } };
  ExpectScene(build, "vector-component", 250, { 0.006, 0.25, 0.003 }, &reference);
}

TEST_F(MapperVTKScenarios, OneWindowOnScreenThenOffScreenThenOnScreen)
{
  // VTK's test: a window drawn on-screen, then switched off-screen with another background
  // and a cone added, then on-screen again. Each state against VTK's PT doing the same.
  auto cube = Cube();
  auto red = CubeProperty(1, 0.2, 0.1), blue = CubeProperty(0.1, 0.3, 1);
  auto run = [&](int backend)
  {
    std::vector<vtkSmartPointer<vtkImageData>> images;
    vtkSmartPointer<vtkUnstructuredGridVolumeMapper> first, second;
    if (backend < 0)
    {
      first = vtkSmartPointer<vtkProjectedTetrahedraMapper>::New();
      second = vtkSmartPointer<vtkProjectedTetrahedraMapper>::New();
    }
    else
    {
      auto a = vtkSmartPointer<Mapper>::New(), b = vtkSmartPointer<Mapper>::New();
      a->SetBackend(backend);
      b->SetBackend(backend);
      first = Apart(a); // compared with VTK's PT (see Apart)
      second = Apart(b);
    }
    vtkNew<vtkRenderer> renderer;
    vtkNew<vtkRenderWindow> window;
    window->SetSize(300, 300);
    window->AddRenderer(renderer);
    window->SetOffScreenRendering(0);
    renderer->SetBackground(1, 1, 1);
    AddVolume(renderer, first, cube, red);
    vtkNew<vtkTransform> transform;
    transform->Translate(1.0, 1.0, 1.0);
    AddVolume(renderer, second, cube, blue)->SetUserTransform(transform);
    SetView(renderer, Views[0], true);
    auto frame = [&]()
    {
      window->Render(); // twice: see Draw
      window->Render();
      images.push_back(Grab(window, false));
    };
    frame();
    window->SetOffScreenRendering(1);
    renderer->SetBackground(0.4, 0.8, 0.4);
    renderer->AddActor(Cone(1, 0, 0, nullptr));
    renderer->ResetCamera();
    frame();
    window->SetOffScreenRendering(0);
    frame();
    first->ReleaseGraphicsResources(window);
    second->ReleaseGraphicsResources(window);
    return images;
  };
  const auto theirs = run(-1);
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    const auto ours = run(backend);
    const char* states[3] = { "on-screen", "then off-screen", "then on-screen again" };
    const double white[3] = { 1, 1, 1 }, green[3] = { 0.4, 0.8, 0.4 };
    for (int i = 0; i < 3; ++i)
    {
      // Measured RMSE 0.0030-0.0032, worst 0.09.
      ExpectClose(ours[i], theirs[i], { 0.006, 0.15, 0.002 },
        std::string("two cubes ") + states[i] + " (" + Name(backend) + ") vs VTK's PT", 0.05,
        i == 0 ? white : green);
    }
  }
}

} // namespace
