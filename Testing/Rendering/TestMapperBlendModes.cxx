// SPDX-License-Identifier: BSD-3-Clause
// Blend modes (vtkVolumeMapper's values 1 to 4): maximum and minimum intensity, average
// intensity in a scalar range, additive. In both backends, in windows as VTK makes them
// (multisampled), each mode's image is compared with the exact reference, which takes the
// mode from the mapper; their frames sort nothing; the backends agree in the targets they
// draw into; and the mapper goes back to composite blending cleanly.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkImageData.h"
#include "vtkPlane.h"
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

const int Modes[] = { Mapper::MAXIMUM_INTENSITY_BLEND, Mapper::MINIMUM_INTENSITY_BLEND,
  Mapper::AVERAGE_INTENSITY_BLEND, Mapper::ADDITIVE_BLEND };

const char* NameOf(int mode)
{
  switch (mode)
  {
    case Mapper::MAXIMUM_INTENSITY_BLEND:
      return "maximum";
    case Mapper::MINIMUM_INTENSITY_BLEND:
      return "minimum";
    case Mapper::AVERAGE_INTENSITY_BLEND:
      return "average";
    default:
      return "additive";
  }
}

class MapperBlendModes : public ShuffledBoxTest
{
protected:
  /// The box with `mapper` in `mode` from the oblique view; the average takes the scalars
  /// in [0.2, 0.9] (the box's field runs over [0, 1]).
  Stage Blended(Mapper* mapper, int mode, bool perspective, WindowSettings window = {})
  {
    mapper->SetBlendMode(mode);
    mapper->SetAverageIPScalarRange(0.2, 0.9);
    Stage stage = MakeStage(Box, MakeProperty(-0.3, 1.3, 0.5), mapper, 200, 200, window);
    SetView(stage.renderer, Views[2], perspective);
    stage.window->Render();
    return stage;
  }
};

TEST_P(MapperBlendModes, EachModeMatchesTheExactReferenceAndSortsNothing)
{
  for (bool perspective : { true, false })
  {
    for (int mode : Modes)
    {
      auto mapper = MakeMapper(GetParam());
      vtkNew<MessageObserver> messages;
      mapper->AddObserver(vtkCommand::ErrorEvent, messages);
      mapper->AddObserver(vtkCommand::WarningEvent, messages);
      const Stage stage = Blended(mapper, mode, perspective);
      const std::string label = std::string("blend-") + NameOf(mode) + "-" +
        ShortBackendName(GetParam()) + (perspective ? "-perspective" : "-ortho");
      EXPECT_TRUE(mapper->GetLastFrameReuse() & Mapper::ORDER_NOT_NEEDED) << label;
      auto image = Grab(stage.window, false);
      auto reference = ReferenceImage(stage);
      ASSERT_TRUE(reference);
      Save(image, label);
      Save(reference, label + "-reference");
      // Measured, both backends alike: covered RMSE 0.0000 to 0.0028, worst 0.004 in
      // perspective. In the orthographic view rays run along two of the box's faces: at
      // 0.02% of the pixels one image takes such a ray in and the other leaves it out, a
      // difference of up to 0.2 where the ray counts whole (maximum, minimum) or long.
      ExpectClose(image, reference, { 0.004, perspective ? 0.01 : 0.25, 0.0005 },
        label + " vs reference", 0.1);
      // Each mode is its own image: not the composite one.
      mapper->SetBlendModeToComposite();
      stage.window->Render();
      EXPECT_FALSE(mapper->GetLastFrameReuse() & Mapper::ORDER_NOT_NEEDED) << label;
      EXPECT_GT(Compare(image, Grab(stage.window, false)).coveredRmse, 0.03) << label;
      EXPECT_TRUE(messages->errors.empty()) << label << ": " << messages->errors.front();
      EXPECT_TRUE(messages->warnings.empty()) << label << ": " << messages->warnings.front();
      mapper->ReleaseGraphicsResources(stage.window);
    }
  }
}

TEST_P(MapperBlendModes, PlanesAndOpaqueGeometryCutTheRays)
{
  // A clipping plane and an opaque box inside the volume: each ray reduces only what the
  // plane keeps in front of the box. The reference knows the plane but not the box, so the
  // image is compared with the other backend's.
  for (int mode : Modes)
  {
    vtkSmartPointer<vtkImageData> images[2];
    for (int b = 0; b < 2; ++b)
    {
      auto mapper = MakeMapper(b == 0 ? GetParam()
                                      : (GetParam() == Mapper::CPU_BACKEND ? Mapper::OPENGL_BACKEND
                                                                           : Mapper::CPU_BACKEND));
      vtkNew<vtkPlane> plane;
      plane->SetOrigin(0.1, 0.0, 0.0);
      plane->SetNormal(0.6, -0.3, 0.7);
      mapper->AddClippingPlane(plane);
      mapper->SetBlendMode(mode);
      mapper->SetAverageIPScalarRange(0.2, 0.9);
      Stage stage = MakeStage(Box, MakeProperty(-0.3, 1.3, 0.5), mapper, 200, 200);
      AddOpaqueCube(stage.renderer, 0.3);
      SetView(stage.renderer, Views[2], true);
      stage.window->Render();
      images[b] = Grab(stage.window, false);
      if (b == 0)
      {
        // Without the plane the image changes: the plane took part.
        mapper->RemoveAllClippingPlanes();
        stage.window->Render();
        EXPECT_GT(Compare(images[0], Grab(stage.window, false)).coveredRmse, 0.02)
          << NameOf(mode);
      }
      mapper->ReleaseGraphicsResources(stage.window);
    }
    // Measured: covered RMSE below 0.001.
    ExpectClose(images[0], images[1], { 0.003, 0.03, 0.001 },
      std::string(NameOf(mode)) + " with a plane and a box: the two backends", 0.1);
  }
}

TEST(MapperBlendModesTargets, BackendsAgreeInEveryTargetTheyDrawInto)
{
  // The OpenGL backend reduces in a float target of its own, at the viewport's size (here
  // also off the window's origin) or at a sampled image's, which it maps to colour and
  // magnifies as the CPU backend does.
  struct Case
  {
    const char* name;
    double distance;
    bool offsetViewport;
  };
  const Case cases[] = { { "viewport's size", 1.0, false }, { "offset viewport", 1.0, true },
    { "image sample distance 2", 2.0, false } };
  auto box = MakeTetrahedralBox(8);
  for (const Case& c : cases)
  {
    for (int mode : Modes)
    {
      vtkSmartPointer<vtkImageData> images[2];
      for (int b = 0; b < 2; ++b)
      {
        auto mapper = MakeMapper(b == 0 ? Mapper::CPU_BACKEND : Mapper::OPENGL_BACKEND);
        mapper->AutoAdjustSampleDistancesOff();
        mapper->SetImageSampleDistance(static_cast<float>(c.distance));
        mapper->SetBlendMode(mode);
        Stage stage = MakeStage(box, MakeProperty(-0.3, 1.3, 0.5), mapper, 200, 160);
        if (c.offsetViewport)
        {
          stage.renderer->SetViewport(0.25, 0.2, 1.0, 1.0);
        }
        SetView(stage.renderer, Views[2], true);
        stage.window->Render();
        images[b] = Grab(stage.window, false);
        mapper->ReleaseGraphicsResources(stage.window);
      }
      // Measured: covered RMSE 0.0002 to 0.001, worst at most 0.008.
      ExpectClose(images[1], images[0], { 0.003, 0.02, 0.001 },
        std::string(c.name) + ", " + NameOf(mode) + ": OpenGL vs CPU", 0.05);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, MapperBlendModes,
  ::testing::Values(Mapper::CPU_BACKEND, Mapper::OPENGL_BACKEND),
  [](const ::testing::TestParamInfo<int>& info)
  { return std::string(ShortBackendName(info.param)); });

} // namespace
