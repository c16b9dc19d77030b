// SPDX-License-Identifier: BSD-3-Clause
// Numerical hard cases through the whole mapper (the core's own are in
// Testing/Core/TestHardCases.cxx): a mesh 1e7 from the origin renders as at the origin, and
// a 120-degree view and a nearly opaque volume match the exact reference.
#include "RenderingTestUtilities.h"

#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkDoubleArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPoints.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// The box with double-precision points moved by `offset`.
vtkSmartPointer<vtkUnstructuredGrid> ShiftedBox(const double offset[3])
{
  auto box = MakeTetrahedralBox(10);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(box->GetNumberOfPoints());
  for (vtkIdType i = 0; i < box->GetNumberOfPoints(); ++i)
  {
    const double* p = box->GetPoint(i);
    points->SetPoint(i, p[0] + offset[0], p[1] + offset[1], p[2] + offset[2]);
  }
  box->SetPoints(points);
  return box;
}

/// The image of `grid` seen from `offset` + (1.8, 1.3, 3.2) looking at `offset`.
vtkSmartPointer<vtkImageData> RenderAt(
  vtkUnstructuredGridVolumeMapper* mapper, vtkUnstructuredGrid* grid, const double offset[3])
{
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  const Stage stage = MakeStage(grid, property, mapper, 120, 120);
  vtkCamera* camera = stage.renderer->GetActiveCamera();
  camera->SetFocalPoint(offset);
  camera->SetPosition(offset[0] + 1.8, offset[1] + 1.3, offset[2] + 3.2);
  camera->SetViewUp(0, 1, 0);
  camera->SetClippingRange(1.0, 8.0);
  stage.window->Render();
  auto image = Grab(stage.window);
  mapper->ReleaseGraphicsResources(stage.window);
  return image;
}

TEST(MapperHardCases, FarFromTheOriginAsAtTheOrigin)
{
  const double origin[3] = { 0, 0, 0 };
  for (int shading : { Mapper::VTK_COMPATIBLE_SHADING, Mapper::PRE_INTEGRATED_SHADING })
  {
    vtkNew<Mapper> plain;
    plain->SetBackendToCPU();
    plain->SetShadingMode(shading);
    auto expected = RenderAt(plain, ShiftedBox(origin), origin);
    for (double distance : { 1e6, 1e7 })
    {
      const double offset[3] = { distance, -0.6 * distance, 0.3 * distance };
      vtkNew<Mapper> mapper;
      mapper->SetBackendToCPU();
      mapper->SetShadingMode(shading);
      const ImageDifference d = Compare(RenderAt(mapper, ShiftedBox(offset), offset), expected);
      std::printf("%s, mesh and camera %.0e from the origin: RMSE %.5f, worst %.4f\n",
        mapper->GetShadingModeAsString(), distance, d.rmse, d.worst);
      EXPECT_LT(d.rmse, 1e-4) << distance;
      EXPECT_LE(d.worst, 1.0 / 255) << distance;
    }
  }
  // VTK's PT on the same scenes, for comparison (not asserted).
  vtkNew<vtkProjectedTetrahedraMapper> pt;
  auto expected = RenderAt(pt, ShiftedBox(origin), origin);
  const double offset[3] = { 1e7, -0.6e7, 0.3e7 };
  vtkNew<vtkProjectedTetrahedraMapper> far;
  const ImageDifference d = Compare(RenderAt(far, ShiftedBox(offset), offset), expected);
  std::printf("VTK PT, 1e+07 from the origin: RMSE %.5f, worst %.4f\n", d.rmse, d.worst);
}

/// `mapper` on the box against the exact reference with the given camera and opacity.
double ErrorAgainstReference(
  vtkUnstructuredGridVolumeMapper* mapper, double viewAngle, double distance, double opacityScale)
{
  auto grid = MakeTetrahedralBox(10);
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity();
  opacity->RemoveAllPoints();
  opacity->AddPoint(-0.3, 0.05 * opacityScale);
  opacity->AddPoint(1.3, 0.9 * opacityScale);
  const Stage stage = MakeStage(grid, property, mapper, 120, 120);
  vtkCamera* camera = stage.renderer->GetActiveCamera();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(0.55 * distance, 0.4 * distance, distance);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(viewAngle);
  stage.renderer->ResetCameraClippingRange();
  stage.window->Render();
  vtkNew<vtkMTPTReferenceRenderer> reference;
  double result[3] = { 1, 0, 1 };
  EXPECT_TRUE(reference->Render(stage.renderer, stage.volume));
  EXPECT_TRUE(reference->CompareWithRenderer(stage.renderer, result));
  mapper->ReleaseGraphicsResources(stage.window);
  return result[0];
}

TEST(MapperHardCases, WideViewAndOpaqueVolumeAgainstTheReference)
{
  struct Case
  {
    const char* name;
    double viewAngle, distance, opacityScale, limit;
  };
  // Limits: measured with margin; the window's 8-bit rounding alone gives about 0.001.
  const Case cases[] = { { "120-degree view", 120, 1.9, 1, 0.004 },
    { "nearly opaque (attenuation x1000)", 30, 5, 1000, 0.005 } };
  for (const Case& c : cases)
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackendToCPU();
    mapper->SetShadingModeToPreIntegrated();
    const double ours = ErrorAgainstReference(mapper, c.viewAngle, c.distance, c.opacityScale);
    vtkNew<vtkProjectedTetrahedraMapper> pt;
    const double theirs = ErrorAgainstReference(pt, c.viewAngle, c.distance, c.opacityScale);
    std::printf("%s: MTPT pre-integrated RMSE %.5f, VTK PT %.5f\n", c.name, ours, theirs);
    EXPECT_LT(ours, c.limit) << c.name;
  }
}

TEST(MapperNearPlane, PiecesReachingFarOffScreenDrawAlikeOnBothBackends)
{
  // The camera inside a mesh of few, large cells with its near plane 1e-6 from the eye: the
  // pieces of the cells the near plane cuts have corners on that plane, which project up
  // to 10^8 pixels off screen, beyond the CPU rasterizer's fixed-point range. They must be
  // clipped as OpenGL clips them, not dropped.
  auto box = MakeTetrahedralBox(3);
  auto property = MakeProperty(-0.3, 1.3, 0.3);
  std::vector<vtkSmartPointer<vtkImageData>> images;
  std::vector<vtkIdType> pieces;
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackend(backend);
    const Stage stage = MakeStage(box, property, mapper, 160, 160);
    vtkCamera* camera = stage.renderer->GetActiveCamera();
    camera->SetPosition(0.1, 0.05, 0.2);
    camera->SetFocalPoint(1.0, 0.4, -0.5);
    camera->SetViewUp(0, 1, 0);
    camera->SetViewAngle(60);
    camera->SetClippingRange(1e-6, 10.0);
    stage.window->Render();
    images.push_back(Grab(stage.window, false));
    pieces.push_back(mapper->GetNumberOfNearClipPieces());
    mapper->ReleaseGraphicsResources(stage.window);
  }
  EXPECT_GT(pieces[1], 0) << "the near plane cuts cells";
  EXPECT_EQ(pieces[0], pieces[1]);
  // Measured RMSE 0.0003, worst 0.004 (the backends' rounding).
  ExpectClose(images[1], images[0], { 0.001, 0.02, 0 }, "CPU vs OpenGL, camera inside", 0.9);
}

} // namespace
