// SPDX-License-Identifier: BSD-3-Clause
// Shading by lights (vtkVolumeProperty::ShadeOn, mtpt/Lighting.h). In both backends, in
// windows as VTK makes them (multisampled): pre-integrated images against the exact reference,
// which lights the cells from the same normals and the renderer's lights (the headlight, or a
// light kit); the two backends against each other in VTK-compatible shading and at an image
// sample distance; against VTK's GPU ray caster on image data of the same field; and shading
// that cannot apply reported once, the volume drawn unlit.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkGPUVolumeRayCastMapper.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRTAnalyticSource.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkLight.h"
#include "vtkLightCollection.h"
#include "vtkLightKit.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <string>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

class MapperShading : public ShuffledBoxTest
{
protected:
  /// The box, shaded, with `mapper` from the oblique view; with a light kit (four lights)
  /// instead of the renderer's headlight when `kit` is set.
  Stage Shaded(Mapper* mapper, bool perspective, bool kit, WindowSettings window = {})
  {
    auto property = MakeProperty(-0.3, 1.3, 0.5);
    property->ShadeOn();
    property->SetSpecular(0.3);
    property->SetSpecularPower(6.0);
    Stage stage = MakeStage(Box, property, mapper, 200, 200, window);
    if (kit)
    {
      vtkNew<vtkLightKit> lights;
      lights->AddLightsToRenderer(stage.renderer);
    }
    SetView(stage.renderer, Views[2], perspective);
    stage.window->Render();
    return stage;
  }
};

TEST_P(MapperShading, MatchesTheExactReference)
{
  for (bool perspective : { true, false })
  {
    for (bool kit : { false, true })
    {
      auto mapper = MakeMapper(GetParam());
      mapper->SetShadingMode(Mapper::PRE_INTEGRATED_SHADING);
      vtkNew<MessageObserver> messages;
      mapper->AddObserver(vtkCommand::ErrorEvent, messages);
      mapper->AddObserver(vtkCommand::WarningEvent, messages);
      const Stage stage = Shaded(mapper, perspective, kit);
      const std::string label = std::string("shading-") + (kit ? "kit-" : "headlight-") +
        ShortBackendName(GetParam()) + (perspective ? "-perspective" : "-ortho");
      auto image = Grab(stage.window, false);
      auto reference = ReferenceImage(stage);
      ASSERT_TRUE(reference);
      Save(image, label);
      Save(reference, label + "-reference");
      ExpectClose(image, reference, { 0.004, 0.25, 0.0005 }, label + " vs reference", 0.1);
      // A change of a light alone (the view and the property still, so every stage and, but
      // for the light, the image are reused) is drawn as a fresh mapper draws it.
      stage.renderer->GetLights()->InitTraversal();
      vtkLight* light = stage.renderer->GetLights()->GetNextItem();
      light->SetIntensity(0.8);
      light->SetDiffuseColor(1.0, 0.6, 0.3);
      stage.window->Render();
      auto brighter = Grab(stage.window, false);
      EXPECT_GT(Compare(image, brighter).coveredRmse, 0.005) << label;
      const int backend = GetParam();
      auto fresh = FreshMapperImage(stage, mapper,
        [backend](Mapper* m)
        {
          m->SetBackend(backend);
          m->SetShadingMode(Mapper::PRE_INTEGRATED_SHADING);
        });
      ExpectClose(brighter, fresh, { 1e-9, 1e-9, 0 }, label + ", relit vs a fresh mapper");
      // The light shows: unlit, the image is another.
      stage.volume->GetProperty()->ShadeOff();
      stage.window->Render();
      EXPECT_GT(Compare(image, Grab(stage.window, false)).coveredRmse, 0.03) << label;
      EXPECT_TRUE(messages->errors.empty()) << label << ": " << messages->errors.front();
      EXPECT_TRUE(messages->warnings.empty()) << label << ": " << messages->warnings.front();
      mapper->ReleaseGraphicsResources(stage.window);
    }
  }
}

TEST(MapperShadingTargets, BackendsAgreeInVTKCompatibleShadingAndSampledImages)
{
  // VTK-compatible shading (no exact reference to compare with) and a sampled image: the
  // OpenGL backend lights each slot's fragments by the primitive's slot, the CPU backend by
  // the fan's.
  struct Case
  {
    const char* name;
    int shading;
    double distance;
  };
  const Case cases[] = { { "VTK-compatible", Mapper::VTK_COMPATIBLE_SHADING, 1.0 },
    { "pre-integrated, image sample distance 2", Mapper::PRE_INTEGRATED_SHADING, 2.0 } };
  auto box = MakeTetrahedralBox(8);
  for (const Case& c : cases)
  {
    vtkSmartPointer<vtkImageData> images[2];
    for (int b = 0; b < 2; ++b)
    {
      auto mapper = MakeMapper(b == 0 ? Mapper::CPU_BACKEND : Mapper::OPENGL_BACKEND);
      mapper->SetShadingMode(c.shading);
      mapper->AutoAdjustSampleDistancesOff();
      mapper->SetImageSampleDistance(static_cast<float>(c.distance));
      auto property = MakeProperty(-0.3, 1.3, 0.5);
      property->ShadeOn();
      Stage stage = MakeStage(box, property, mapper, 200, 160);
      SetView(stage.renderer, Views[2], true);
      stage.window->Render();
      images[b] = Grab(stage.window, false);
      mapper->ReleaseGraphicsResources(stage.window);
    }
    ExpectClose(images[1], images[0], { 0.003, 0.03, 0.001 },
      std::string(c.name) + ": OpenGL vs CPU", 0.05);
  }
}

TEST_P(MapperShading, WithoutPointScalarsIsReportedOnceAndDrawnUnlit)
{
  // Cell scalars have no gradient to light: one warning, and the unlit image.
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(Box);
  vtkDataArray* points = grid->GetPointData()->GetScalars();
  vtkNew<vtkFloatArray> perCell;
  perCell->SetName("cellField");
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    vtkIdType n;
    const vtkIdType* ids;
    grid->GetCellPoints(c, n, ids);
    perCell->InsertNextValue(static_cast<float>(points->GetTuple1(ids[0])));
  }
  grid->GetCellData()->SetScalars(perCell);
  grid->GetPointData()->SetScalars(nullptr);
  auto mapper = MakeMapper(GetParam());
  vtkNew<MessageObserver> messages;
  mapper->AddObserver(vtkCommand::WarningEvent, messages);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  Stage stage = MakeStage(grid, property, mapper, 160, 160);
  SetView(stage.renderer, Views[2], true);
  stage.window->Render();
  auto unlit = Grab(stage.window, false);
  property->ShadeOn();
  stage.window->Render();
  stage.window->Render();
  ASSERT_EQ(messages->warnings.size(), 1u);
  EXPECT_NE(messages->warnings.front().find("cell scalars"), std::string::npos)
    << messages->warnings.front();
  ExpectClose(Grab(stage.window, false), unlit, { 1e-9, 1e-9, 0 }, "shaded cell scalars");
  mapper->ReleaseGraphicsResources(stage.window);
}

/// `input` drawn by `mapper` (lit, with a light kit when `kit`), as the figures show it.
vtkSmartPointer<vtkImageData> RenderLit(
  vtkDataObject* input, vtkAbstractVolumeMapper* mapper, bool kit, bool shade = true)
{
  vtkNew<vtkColorTransferFunction> colour;
  colour->AddRGBPoint(40, 0.2, 0.3, 0.9);
  colour->AddRGBPoint(160, 0.95, 0.95, 0.6);
  colour->AddRGBPoint(280, 0.9, 0.2, 0.1);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(40, 0.0);
  opacity->AddPoint(120, 0.15);
  opacity->AddPoint(200, 0.6);
  opacity->AddPoint(280, 0.9);
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(5.0);
  property->SetInterpolationTypeToLinear();
  property->SetShade(shade ? 1 : 0);
  property->SetAmbient(0.2);
  property->SetDiffuse(0.7);
  property->SetSpecular(0.3);
  property->SetSpecularPower(12.0);
  mapper->SetInputDataObject(input);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(Background[0], Background[1], Background[2]);
  renderer->AddVolume(volume);
  if (kit)
  {
    vtkNew<vtkLightKit> lights;
    lights->AddLightsToRenderer(renderer);
  }
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(200, 200);
  window->AddRenderer(renderer);
  renderer->ResetCamera();
  renderer->GetActiveCamera()->Azimuth(35);
  renderer->GetActiveCamera()->Elevation(20);
  renderer->GetActiveCamera()->OrthogonalizeViewUp();
  renderer->ResetCameraClippingRange();
  window->Render();
  return Grab(window, false);
}

TEST(MapperShadingAgainstVTK, LitAsVTKsGPURayCasterLightsImageData)
{
  // The whole chain against VTK itself: the wavelet as image data through VTK's GPU ray
  // caster, and tetrahedralized through MTPT (pre-integrated), lit by the renderer's
  // headlight and by a light kit, in VTK's default window.
  vtkNew<vtkRTAnalyticSource> source;
  source->SetWholeExtent(-10, 10, -10, 10, -10, 10);
  source->Update();
  vtkNew<vtkDataSetTriangleFilter> tetrahedra;
  tetrahedra->SetInputConnection(source->GetOutputPort());
  tetrahedra->Update();
  for (bool kit : { false, true })
  {
    vtkNew<vtkGPUVolumeRayCastMapper> rayCast;
    rayCast->AutoAdjustSampleDistancesOff();
    rayCast->SetSampleDistance(0.05f);
    auto theirs = RenderLit(source->GetOutput(), rayCast, kit);
    auto mapper = MakeMapper(Mapper::CPU_BACKEND);
    mapper->SetShadingMode(Mapper::PRE_INTEGRATED_SHADING);
    auto ours = RenderLit(tetrahedra->GetOutput(), mapper, kit);
    auto unlit = RenderLit(tetrahedra->GetOutput(), MakeMapper(Mapper::CPU_BACKEND), kit, false);
    const std::string label = std::string("shading-vs-gpu-ray-cast-") + (kit ? "kit" : "headlight");
    Save(ours, label);
    Save(theirs, label + "-ray-cast");
    // Measured: covered RMSE with the headlight 8.3/255 against VTK 9.1's ray caster (2% of
    // the pixels over 0.1, on the highlights), 5.4 against VTK 9.6's, whose lighting MTPT
    // follows; with the kit 5.5 and 5.9. The goal is 10/255. Unlit, more than twice as far.
    ExpectClose(ours, theirs, { 10.0 / 255, 1.0, 0.1 }, label, 0.1);
    const double lit = Compare(ours, theirs).coveredRmse;
    EXPECT_GT(Compare(unlit, theirs).coveredRmse, 2 * lit) << label << ": the light matters";
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperShading,
  ::testing::Values(Mapper::CPU_BACKEND, Mapper::OPENGL_BACKEND),
  [](const ::testing::TestParamInfo<int>& info)
  { return std::string(ShortBackendName(info.param)); });

} // namespace
