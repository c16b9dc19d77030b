// SPDX-License-Identifier: BSD-3-Clause
// Clipping planes (vtkAbstractMapper::AddClippingPlane, world coordinates): each fragment's
// ray segment is cut exactly where it leaves the half-space a plane keeps, in both backends
// and both shadings, in windows as VTK makes them (multisampled). The exact reference learns
// the planes from the mapper, so every image is compared with it. Moving a plane redraws
// from the kept order and decomposition, and gives a fresh mapper's image.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkImageData.h"
#include "vtkPlane.h"
#include "vtkPlaneCollection.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkTransform.h"
#include "vtkTransformFilter.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <string>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

vtkSmartPointer<vtkPlane> MakePlane(double ox, double oy, double oz, double nx, double ny, double nz)
{
  auto plane = vtkSmartPointer<vtkPlane>::New();
  plane->SetOrigin(ox, oy, oz);
  plane->SetNormal(nx, ny, nz);
  return plane;
}

class MapperClippingPlanes : public ShuffledBoxTest
{
protected:
  /// The box with `mapper` from the oblique view, two planes through it: one oblique, one
  /// that takes off a corner from behind.
  Stage Clipped(Mapper* mapper, bool perspective)
  {
    mapper->AddClippingPlane(MakePlane(0.1, 0.0, 0.0, 0.6, -0.3, 0.7));
    mapper->AddClippingPlane(MakePlane(0.0, -0.5, -0.4, -0.2, 0.5, 0.6));
    Stage stage = MakeStage(Box, MakeProperty(-0.3, 1.3, 0.5), mapper, 200, 200);
    SetView(stage.renderer, Views[2], perspective);
    stage.window->Render();
    return stage;
  }
};

TEST_P(MapperClippingPlanes, EachShadingMatchesTheExactReference)
{
  for (bool perspective : { true, false })
  {
    for (bool preIntegrated : { false, true })
    {
      auto mapper = MakeMapper(GetParam());
      if (preIntegrated)
      {
        mapper->SetShadingModeToPreIntegrated();
      }
      vtkNew<MessageObserver> messages;
      mapper->AddObserver(vtkCommand::ErrorEvent, messages);
      mapper->AddObserver(vtkCommand::WarningEvent, messages);
      const Stage stage = Clipped(mapper, perspective);
      const std::string label = std::string("clip-") + ShortBackendName(GetParam()) +
        (preIntegrated ? "-preintegrated" : "") + (perspective ? "-perspective" : "-ortho");
      auto image = Grab(stage.window, false);
      auto reference = ReferenceImage(stage);
      ASSERT_TRUE(reference);
      Save(image, label);
      Save(reference, label + "-reference");
      // Measured: covered RMSE 0.0035 and worst 0.020 (VTK-compatible), 0.0016 and 0.004
      // (pre-integrated), both backends alike: without planes the same scene gives as much.
      const Limits limits = preIntegrated ? Limits{ 0.0025, 0.01, 0.001 }
                                          : Limits{ 0.005, 0.03, 0.001 };
      ExpectClose(image, reference, limits, label + " vs reference", 0.1);
      // The planes took off a good part of the box.
      mapper->RemoveAllClippingPlanes();
      stage.window->Render();
      auto whole = Grab(stage.window, false);
      EXPECT_GT(Compare(image, whole).coveredRmse, 0.05) << label;
      EXPECT_TRUE(messages->errors.empty()) << label << ": " << messages->errors.front();
      mapper->ReleaseGraphicsResources(stage.window);
    }
  }
}

TEST_P(MapperClippingPlanes, MovingAPlaneKeepsTheOrderAndGivesAFreshMappersImage)
{
  auto mapper = MakeMapper(GetParam());
  const Stage stage = Clipped(mapper, true);
  stage.window->Render();
  vtkPlane* plane = mapper->GetClippingPlanes()->GetItem(0);
  for (double shift : { 0.2, -0.3 })
  {
    plane->SetOrigin(shift, 0.1, 0.0);
    stage.window->Render();
    const int reused = mapper->GetLastFrameReuse();
    EXPECT_TRUE(reused & Mapper::REUSED_ORDER) << "shift " << shift;
    EXPECT_TRUE(reused & Mapper::REUSED_DECOMPOSITION || GetParam() == Mapper::CPU_BACKEND)
      << "shift " << shift;
    EXPECT_FALSE(reused & Mapper::REUSED_IMAGE) << "shift " << shift;
    auto image = Grab(stage.window, false);
    auto fresh = FreshMapperImage(stage, mapper,
      [&](Mapper* m)
      {
        m->SetBackend(GetParam());
        m->AddClippingPlane(MakePlane(shift, 0.1, 0.0, 0.6, -0.3, 0.7));
        m->AddClippingPlane(MakePlane(0.0, -0.5, -0.4, -0.2, 0.5, 0.6));
      });
    const ImageDifference d = Compare(image, fresh);
    EXPECT_EQ(d.worst, 0.0) << "shift " << shift;
  }
  mapper->ReleaseGraphicsResources(stage.window);
}

TEST_P(MapperClippingPlanes, PlanesAreInWorldCoordinatesWhateverTheVolumesMatrix)
{
  // The volume moved and turned by its matrix: the planes stay where they are in the world,
  // so the image equals that of the data moved by the same transform, with the same planes.
  vtkNew<vtkTransform> transform;
  transform->Translate(0.3, -0.2, 0.1);
  transform->RotateWXYZ(25, 0.2, 1.0, 0.3);
  auto byMatrix = MakeMapper(GetParam());
  const Stage stage = Clipped(byMatrix, true);
  stage.volume->SetUserTransform(transform);
  stage.window->Render();
  auto image = Grab(stage.window, false);
  vtkNew<vtkTransformFilter> move;
  move->SetInputData(Box);
  move->SetTransform(transform);
  move->Update();
  stage.volume->SetUserTransform(nullptr);
  auto byData = FreshMapperImage(stage, byMatrix,
    [&](Mapper* m)
    {
      m->SetBackend(GetParam());
      m->SetInputData(move->GetOutput());
      m->SetClippingPlanes(byMatrix->GetClippingPlanes());
    });
  // Measured: identical images on both backends.
  ExpectClose(image, byData, { 0.001, 0.02, 0.001 }, "moved by the matrix vs the data", 0.1);
  byMatrix->ReleaseGraphicsResources(stage.window);
}

TEST_P(MapperClippingPlanes, OpaqueGeometryAndPlanesTogether)
{
  // An opaque box inside the clipped volume: fragments behind it stay hidden.
  auto mapper = MakeMapper(GetParam());
  const Stage stage = Clipped(mapper, true);
  AddOpaqueCube(stage.renderer, 0.3);
  stage.window->Render();
  auto image = Grab(stage.window, false);
  auto fresh = FreshMapperImage(stage, mapper,
    [&](Mapper* m)
    {
      m->SetBackend(GetParam() == Mapper::CPU_BACKEND ? Mapper::OPENGL_BACKEND
                                                      : Mapper::CPU_BACKEND);
      m->AddClippingPlane(MakePlane(0.1, 0.0, 0.0, 0.6, -0.3, 0.7));
      m->AddClippingPlane(MakePlane(0.0, -0.5, -0.4, -0.2, 0.5, 0.6));
    });
  // The two backends agree with the opaque box in: measured covered RMSE 0.0002.
  ExpectClose(image, fresh, { 0.002, 0.03, 0.001 }, "opaque box, CPU vs OpenGL", 0.1);
  mapper->ReleaseGraphicsResources(stage.window);
}

TEST(MapperClippingPlanesTargets, BackendsAgreeInEveryTargetTheyDrawInto)
{
  // The OpenGL backend finds each fragment's ray from its pixel in the target it draws into:
  // a sampled image's, the float target's, the window's own (a renderer viewport off the
  // origin), a depth peel's. The CPU backend cuts with the same arithmetic in double.
  struct Case
  {
    const char* name;
    double distance;
    bool floatTarget, offsetViewport, peel;
  };
  const Case cases[] = { { "image sample distance 2", 2.0, true, false, false },
    { "window target, offset viewport", 1.0, false, true, false },
    { "float target, offset viewport", 1.0, true, true, false },
    { "depth peeling", 1.0, true, false, true } };
  auto box = MakeTetrahedralBox(8);
  for (const Case& c : cases)
  {
    vtkSmartPointer<vtkImageData> images[2];
    for (int b = 0; b < 2; ++b)
    {
      auto mapper = MakeMapper(b == 0 ? Mapper::CPU_BACKEND : Mapper::OPENGL_BACKEND);
      mapper->AutoAdjustSampleDistancesOff();
      mapper->SetImageSampleDistance(static_cast<float>(c.distance));
      mapper->SetUseFloatingPointFrameBuffer(c.floatTarget);
      mapper->AddClippingPlane(MakePlane(0.1, 0.0, 0.0, 0.6, -0.3, 0.7));
      WindowSettings window;
      window.multiSamples = c.peel ? 0 : -1;
      Stage stage = MakeStage(box, MakeProperty(-0.3, 1.3, 0.5), mapper, 200, 160, window);
      if (c.offsetViewport)
      {
        stage.renderer->SetViewport(0.25, 0.2, 1.0, 1.0);
      }
      if (c.peel)
      {
        stage.renderer->SetUseDepthPeeling(1);
        stage.renderer->SetUseDepthPeelingForVolumes(1);
        stage.renderer->SetOcclusionRatio(0.0);
      }
      SetView(stage.renderer, Views[2], true);
      stage.window->Render();
      stage.window->Render();
      images[b] = Grab(stage.window, false);
      mapper->ReleaseGraphicsResources(stage.window);
    }
    // Measured: covered RMSE 0.0001-0.002, worst 0.004-0.008; blending in the window's own
    // 8 bits (no float target) differs from the CPU's rounding by up to 0.08 at single
    // pixels with or without planes (0.0028 covered RMSE), never at a tenth of the pixels.
    const Limits limits =
      c.floatTarget ? Limits{ 0.003, 0.02, 0.001 } : Limits{ 0.005, 0.1, 0.001 };
    ExpectClose(images[1], images[0], limits, std::string(c.name) + ": OpenGL vs CPU", 0.05);
  }
}

TEST(MapperClippingPlanesLimits, MoreThanEightPlanesAreReportedAndTheFirstEightKept)
{
  auto mapper = MakeMapper(Mapper::CPU_BACKEND);
  for (int i = 0; i < 9; ++i)
  {
    mapper->AddClippingPlane(MakePlane(0, 0, 0.9 - 0.05 * i, 0, 0, -1));
  }
  vtkNew<MessageObserver> messages;
  mapper->AddObserver(vtkCommand::WarningEvent, messages);
  Stage stage = MakeStage(MakeTetrahedralBox(4), MakeProperty(-0.3, 1.3, 0.5), mapper, 120, 120);
  SetView(stage.renderer, Views[0], true);
  stage.window->Render();
  stage.window->Render();
  ASSERT_EQ(messages->warnings.size(), 1u);
  EXPECT_NE(messages->warnings.front().find("first 8 of 9 clipping planes"), std::string::npos)
    << messages->warnings.front();
  mapper->ReleaseGraphicsResources(stage.window);
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperClippingPlanes,
  ::testing::Values(Mapper::CPU_BACKEND, Mapper::OPENGL_BACKEND),
  [](const ::testing::TestParamInfo<int>& info) { return std::string(BackendName(info.param)); });

} // namespace
