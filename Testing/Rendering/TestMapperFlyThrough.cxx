// SPDX-License-Identifier: BSD-3-Clause
// The camera flies into and through a mesh (Documentation/algorithm.md, "Near-plane
// clipping"): cells crossing the near plane are cut and their visible parts drawn, so no
// frame has holes, and each frame matches the exact reference (vtkMTPTReferenceRenderer).
// VTK's vtkProjectedTetrahedraMapper drops such cells whole; its errors and holes are
// reported beside ours.
#include "RenderingTestUtilities.h"

#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkDoubleArray.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct FrameError
{
  double rmse = 1;
  double worst = 1; ///< largest channel difference
  int holes = 0;    ///< pixels the reference covers (> 0.05 from the background) left empty
};

/// One frame of `mapper` from `eye` looking along -z (slightly tilted) with the given near
/// plane, compared with the reference of the same renderer.
/// `exact` is the reference image of the frame, computed by the first call (empty array).
FrameError Frame(vtkUnstructuredGridVolumeMapper* mapper, vtkUnstructuredGrid* grid,
  vtkVolumeProperty* property, double eyeZ, double nearPlane, vtkDoubleArray* exact)
{
  const Stage stage = MakeStage(grid, property, mapper, 96, 96);
  vtkRenderer* renderer = stage.renderer;
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(0.13, 0.07, eyeZ);
  camera->SetFocalPoint(0.0, 0.0, eyeZ - 1.0);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(60);
  camera->SetClippingRange(nearPlane, 20.0);
  stage.window->Render();

  FrameError e;
  if (exact->GetNumberOfTuples() == 0)
  {
    vtkNew<vtkMTPTReferenceRenderer> reference;
    if (!reference->Render(renderer, stage.volume))
    {
      ADD_FAILURE() << "no reference image";
      return e;
    }
    exact->DeepCopy(reference->GetImage());
  }
  vtkNew<vtkDoubleArray> drawn;
  double result[3];
  EXPECT_TRUE(vtkMTPTReferenceRenderer::ReadPixels(renderer, drawn));
  EXPECT_TRUE(vtkMTPTReferenceRenderer::CompareImages(drawn, exact, result));
  e.rmse = result[0];
  e.worst = result[2];
  for (vtkIdType p = 0; p < exact->GetNumberOfTuples(); ++p)
  {
    double exactOff = 0, drawnOff = 0;
    for (int c = 0; c < 3; ++c)
    {
      // Background in linear RGB as the window stores it (8-bit).
      exactOff = std::max(exactOff, std::fabs(exact->GetComponent(p, c) - Background[c]));
      drawnOff = std::max(drawnOff, std::fabs(drawn->GetComponent(p, c) - Background[c]));
    }
    e.holes += exactOff > 0.05 && drawnOff < 0.01 ? 1 : 0;
  }
  mapper->ReleaseGraphicsResources(stage.window);
  return e;
}

TEST(MapperFlyThrough, NoHolesAndTheReferenceImageAllTheWayThrough)
{
  auto grid = MakeTetrahedralBox(10); // [-1, 1]^3
  auto property = MakeProperty(-0.3, 1.3, 0.8);
  int vtkHoles = 0;
  // From outside (z = 2.5) through the box to beyond its far side.
  for (double eyeZ : { 2.5, 0.9, -0.4, -0.95 })
  {
    vtkNew<vtkDoubleArray> exact;
    double preIntegrated = 1;
    for (int shading : { Mapper::VTK_COMPATIBLE_SHADING, Mapper::PRE_INTEGRATED_SHADING })
    {
      vtkNew<Mapper> mapper;
      mapper->SetBackendToCPU();
      mapper->SetShadingMode(shading);
      const FrameError ours = Frame(mapper, grid, property, eyeZ, 0.01, exact);
      std::printf("eye z %5.2f %-14s: RMSE %.4f, worst %.3f, holes %d, cells cut by the near "
                  "plane %lld\n",
        eyeZ, mapper->GetShadingModeAsString(), ours.rmse, ours.worst, ours.holes,
        static_cast<long long>(mapper->GetNumberOfNearClippedCells()));
      EXPECT_EQ(ours.holes, 0) << eyeZ;
      if (eyeZ < 1.0 && eyeZ > -1.0)
      {
        EXPECT_GT(mapper->GetNumberOfNearClippedCells(), 0) << eyeZ;
      }
      // Pre-integrated shading is perspective-exact; VTK-compatible interpolates lengths
      // linearly in screen space, as VTK's PT does, which errs most in cells at the eye.
      // Measured: pre-integrated RMSE 0.0012-0.0019, worst 0.003-0.004; VTK-compatible up
      // to 0.037 and 0.071 (the eye inside the box).
      const bool exact = shading == Mapper::PRE_INTEGRATED_SHADING;
      EXPECT_LT(ours.rmse, exact ? 0.006 : 0.04) << eyeZ;
      EXPECT_LT(ours.worst, exact ? 0.02 : 0.12) << eyeZ;
      preIntegrated = exact ? ours.rmse : preIntegrated;
    }
    vtkNew<vtkProjectedTetrahedraMapper> pt;
    const FrameError theirs = Frame(pt, grid, property, eyeZ, 0.01, exact);
    std::printf(
      "eye z %5.2f VTK PT        : RMSE %.4f, holes %d\n", eyeZ, theirs.rmse, theirs.holes);
    vtkHoles += theirs.holes;
    // VTK's PT drops the cells the near plane cuts (what is fixed): inside the box its error
    // is several times ours. How many pixels that leaves empty depends on the blending order
    // of the cells around, which its depth sort's random pivots decide (0, or 1548 to 1799,
    // over the flight with the test's seed or others; RenderingTestUtilities.cxx): reported.
    // Measured over the orders and seeds tried: 0.024-0.036 at z 0.9, 0.060-0.164 at z -0.4,
    // 0.0097 at z -0.95, against ours pre-integrated 0.0012, 0.0016 and 0.0019.
    if (eyeZ < 1.0)
    {
      EXPECT_GT(theirs.rmse, 3 * preIntegrated) << eyeZ;
    }
  }
  std::printf("VTK PT holes over the flight: %d\n", vtkHoles);
}

} // namespace
