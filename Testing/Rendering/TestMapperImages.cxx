// SPDX-License-Identifier: BSD-3-Clause
// Image tests of vtkMultiThreadedProjectedTetrahedraMapper: against VTK's own
// vtkProjectedTetrahedraMapper rendering the same scene in the same process, and against
// stored baselines of the mapper's own output.
//
// Metric (RenderingTestUtilities.h): RMSE over RGB in [0, 1] over the pixels the volume
// covers, the largest channel difference (worst pixel), and the fraction of covered pixels
// differing by more than 0.1 in some channel. Every scene is drawn from three directions
// (Views: from +z, from -z, obliquely from above) with its cells stored in a random order,
// so that neither storage order nor a reversed order can pass for the visibility order;
// `scripts/ci/mutation-check.sh` runs these tests with the order reversed and with no sort
// (MTPT_TESTING_ORDER=reversed, storage),
// and both must fail. Thresholds come from measurement (values in the comments, Mesa
// llvmpipe, 200x200) and sit between the correct order's figures and the mutations'.
// The two mappers are expected to differ a little, and where they do VTK's PT is the less
// accurate one: it quantizes colours to 8 bits before interpolating, interpolates the
// opacity at a quadrilateral's crossing with alpha on both edges, reads thicknesses from a
// 2048-entry square-root table, and sorts perspective views along the view direction.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkActor.h"
#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkMatrix4x4.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace
{
using namespace mtpt::rendering_test;

using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

class MapperImages : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    Box = ShuffleCells(MakeTetrahedralBox(12), 1); // 8640 tetrahedra
    BluntFin = ShuffleCells(LoadBluntFin(), 2);
  }
  static void TearDownTestSuite()
  {
    Box = nullptr;
    BluntFin = nullptr;
  }
  Scene BoxScene(bool perspective)
  {
    return MakeScene(Box, MakeProperty(-0.3, 1.3, 0.5), perspective);
  }
  Scene BluntFinScene(bool perspective)
  {
    return MakeScene(BluntFin, MakeBluntFinProperty(), perspective);
  }
  /// The orthographic box with an opaque sphere inside the volume (depth test).
  Scene SphereScene()
  {
    Scene s = BoxScene(false);
    s.customize = [](vtkVolume*, vtkRenderer* renderer)
    {
      vtkNew<vtkSphereSource> sphere;
      sphere->SetCenter(0.3, 0.2, 0.4);
      sphere->SetRadius(0.6);
      sphere->SetThetaResolution(32);
      sphere->SetPhiResolution(32);
      vtkNew<vtkPolyDataMapper> mapper;
      mapper->SetInputConnection(sphere->GetOutputPort());
      vtkNew<vtkActor> actor;
      actor->SetMapper(mapper);
      actor->GetProperty()->SetColor(0.2, 0.9, 0.3);
      renderer->AddActor(actor);
    };
    return s;
  }
  /// The box with a transfer function that is transparent except for a narrow opacity
  /// peak at scalar 0.5 (width 0.02, about a fifth of the scalar step between vertices).
  Scene NarrowPeakBoxScene(bool perspective)
  {
    return MakeScene(Box, MakeNarrowPeakProperty(0.5), perspective);
  }
  static vtkSmartPointer<vtkUnstructuredGrid> Box, BluntFin;
};
vtkSmartPointer<vtkUnstructuredGrid> MapperImages::Box;
vtkSmartPointer<vtkUnstructuredGrid> MapperImages::BluntFin;

// Limits: { RMSE over covered pixels, worst pixel, fraction of covered pixels over 0.1 }.
// Measured with the correct order (Mesa llvmpipe, 200x200, three views): box scenes RMSE
// 0.0013-0.0027, worst 0.004-0.020, no pixel over 0.1; with the order reversed or left in
// storage order RMSE 0.006-0.022 and worst 0.035-0.12 (scripts/ci/mutation-check.sh).
const Limits BoxLimits{ 0.004, 0.03, 0.001 };

TEST_F(MapperImages, SyntheticOrthographicMatchesVTK)
{
  ExpectCloseToVTK(BoxScene(false), "box-ortho", BoxLimits);
}

TEST_F(MapperImages, SyntheticPerspectiveMatchesVTK)
{
  ExpectCloseToVTK(BoxScene(true), "box-persp", BoxLimits);
}

TEST_F(MapperImages, SyntheticCellScalarsMatchVTK)
{
  Scene s = BoxScene(true);
  vtkNew<vtkUnstructuredGrid> cellOnly;
  cellOnly->ShallowCopy(Box);
  cellOnly->GetPointData()->SetScalars(nullptr);
  cellOnly->GetCellData()->SetScalars(cellOnly->GetCellData()->GetArray("cellField"));
  s.grid = cellOnly;
  ExpectCloseToVTK(s, "box-cells", BoxLimits);
}

TEST_F(MapperImages, RealMeshOrthographicMatchesVTK)
{
  // Measured RMSE 0.0020-0.0021, worst 0.008-0.016; storage order 0.004-0.009 and 0.055-0.11.
  ExpectCloseToVTK(BluntFinScene(false), "bluntfin-ortho", { 0.003, 0.03, 0.001 });
}

TEST_F(MapperImages, RealMeshPerspectiveMatchesVTK)
{
  // VTK's PT sorts perspective views along the view direction, where this mapper sorts by
  // distance from the eye: in the bright core near the fin tip, where small cells meet a
  // steep transfer function, the two orders differ (measured RMSE 0.013-0.015, worst
  // 0.13-0.29, 0.15-0.5% of covered pixels over 0.1). Which of the two is right the next
  // test says: the exact reference.
  ExpectCloseToVTK(BluntFinScene(true), "bluntfin-persp", { 0.02, 0.35, 0.01 });
}

TEST_F(MapperImages, RealMeshPerspectiveMatchesTheReference)
{
  // Measured RMSE 0.0015-0.0018, worst 0.004-0.020 (both shadings); with the order
  // reversed or in storage order 0.004-0.018 and 0.059-0.17.
  const Limits limits{ 0.0025, 0.03, 0.001 };
  ExpectCloseToReference(
    BluntFinScene(true), "bluntfin-persp", limits, Mapper::VTK_COMPATIBLE_SHADING);
  ExpectCloseToReference(
    BluntFinScene(true), "bluntfin-persp", limits, Mapper::PRE_INTEGRATED_SHADING);
}

TEST_F(MapperImages, SyntheticPerspectiveMatchesTheReference)
{
  // Measured: VTK-compatible RMSE 0.0026-0.0027, worst 0.016-0.020; pre-integrated 0.0016-0.0017
  // and 0.004; mutations 0.009-0.022 and 0.059-0.12.
  ExpectCloseToReference(BoxScene(true), "box-persp", BoxLimits, Mapper::VTK_COMPATIBLE_SHADING);
  ExpectCloseToReference(
    BoxScene(true), "box-persp", { 0.003, 0.015, 0.001 }, Mapper::PRE_INTEGRATED_SHADING);
}

TEST_F(MapperImages, TransformedVolumeMatchesVTK)
{
  Scene s = BoxScene(true);
  s.customize = [](vtkVolume* volume, vtkRenderer*)
  {
    volume->SetPosition(0.5, -0.2, 0.1);
    volume->SetOrientation(20, 35, -10);
    volume->SetScale(1.5, 0.7, 1.0);
    vtkNew<vtkMatrix4x4> user;
    user->SetElement(0, 1, 0.2); // a shear, through the user matrix
    volume->SetUserMatrix(user);
  };
  ExpectCloseToVTK(s, "box-transformed", BoxLimits);
}

TEST_F(MapperImages, OpaqueGeometryOccludesTheVolume)
{
  // Both in VTK's default window. Measured RMSE 0.0065-0.021, worst 0.10-0.41, up to 1.4% of
  // covered pixels over 0.1: VTK's speckles, and where a tetrahedron meets the sphere the two
  // mappers test different depths (this mapper the front of the ray segment). A black or
  // missing volume, or a volume drawn over the sphere, is far beyond these.
  ExpectCloseToVTK(SphereScene(), "box-sphere", { 0.03, 0.5, 0.02 }, TheirWindow::Same);
}

TEST_F(MapperImages, IdenticalForEveryThreadCountAndOrderMethod)
{
  const Scene s = BluntFinScene(true);
  for (int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    auto reference = MakeMapper(backend);
    reference->SetNumberOfThreads(1);
    reference->SetOrderMethodToPartitionSort();
    auto expected = Render(s, reference);
    for (int threads : { 2, 3, 8 })
    {
      for (bool radix : { false, true })
      {
        auto mapper = MakeMapper(backend);
        mapper->SetNumberOfThreads(threads);
        mapper->SetOrderMethod(radix ? Mapper::RADIX_SORT : Mapper::PARTITION_SORT);
        const ImageDifference d = Compare(Render(s, mapper), expected);
        EXPECT_EQ(d.worst, 0.0) << ShortBackendName(backend) << ", " << threads
                                << " threads, radix " << radix;
      }
    }
  }
}

/// The CPU compositor and the OpenGL path draw the same triangles with the same math:
/// they may differ only where the rasterizers' coverage rules and interpolation rounding
/// differ (pixels on triangle edges, Mesa's 8-bit texture filter weights), and, in VTK's
/// multisampled window, on the silhouette of opaque geometry: OpenGL tests the volume's
/// depth per sample, the CPU compositor per pixel against the resolved depth, so a pixel the
/// silhouette crosses may differ by the volume's colour times the samples' coverage.
TEST_F(MapperImages, CPUCompositorMatchesTheOpenGLPath)
{
  struct Case
  {
    const char* name;
    Scene scene;
    double worst;
  };
  // Measured RMSE 0.00015-0.00040 over covered pixels; worst 0.004-0.008 without opaque
  // geometry; with the sphere 0.008 (Mesa 22.3), 0.027 (Mesa 26.2: one silhouette pixel;
  // Documentation/testing.md, "Today's stack").
  const Case cases[] = { { "box-ortho", BoxScene(false), 0.02 },
    { "box-persp", BoxScene(true), 0.02 }, { "bluntfin-persp", BluntFinScene(true), 0.02 },
    { "bluntfin-ortho", BluntFinScene(false), 0.02 }, { "box-sphere", SphereScene(), 0.04 } };
  for (const Case& c : cases)
  {
    auto gl = MakeMapper(Mapper::OPENGL_BACKEND);
    auto cpu = MakeMapper(Mapper::CPU_BACKEND);
    ExpectClose(Render(c.scene, cpu), Render(c.scene, gl), { 0.001, c.worst, 0 },
      std::string(c.name) + " CPU vs GL");
  }
}

/// Pre-integrated shading evaluates the same formulas in the fragment shader and in the
/// CPU compositor (mtpt::PreIntegrationTable::Segment).
TEST_F(MapperImages, PreIntegratedShadingMatchesAcrossBackends)
{
  struct Case
  {
    const char* name;
    Scene scene;
  };
  const Case cases[] = { { "box-persp", BoxScene(true) },
    { "bluntfin-ortho", BluntFinScene(false) }, { "narrow-peak-persp", NarrowPeakBoxScene(true) } };
  for (const Case& c : cases)
  {
    auto gl = MakeMapper(Mapper::OPENGL_BACKEND);
    auto cpu = MakeMapper(Mapper::CPU_BACKEND);
    gl->SetShadingModeToPreIntegrated();
    cpu->SetShadingModeToPreIntegrated();
    auto glImage = Render(c.scene, gl);
    Save(glImage, std::string("MTPT_PreIntegrated_") + c.name);
    ExpectClose(Render(c.scene, cpu), glImage, { 0.001, 0.02, 0 },
      std::string("pre-integrated ") + c.name + " CPU vs GL");
  }
}

/// A narrow opacity peak between the vertex values of a linear field: vertex
/// classification (VTK's PT, the VTK-compatible mode) sees none of it, pre-integration
/// draws the whole iso-layer with the same optical depth on every pixel.
TEST_F(MapperImages, PreIntegratedShadingCapturesNarrowFeatures)
{
  // The box with the scalar (x + 1) / 2: vertex values k / 12; the peak sits half-way
  // between two vertex planes, at (5.5 / 12), with half-width 0.01.
  vtkNew<vtkUnstructuredGrid> ramp;
  ramp->ShallowCopy(Box);
  vtkNew<vtkFloatArray> field;
  field->SetName("ramp");
  for (vtkIdType i = 0; i < ramp->GetNumberOfPoints(); ++i)
  {
    field->InsertNextValue(static_cast<float>(0.5 * (ramp->GetPoint(i)[0] + 1.0)));
  }
  ramp->GetPointData()->SetScalars(field);
  const double peak = 5.5 / 12;
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(0.0, 0.9, 0.6, 0.1);
  color->AddRGBPoint(1.0, 0.9, 0.6, 0.1);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(peak - 0.01, 0.0);
  opacity->AddPoint(peak, 2.0);
  opacity->AddPoint(peak + 0.01, 0.0);
  opacity->AddPoint(1.0, 0.0);
  Scene s;
  s.grid = ramp;
  s.property = vtkSmartPointer<vtkVolumeProperty>::New();
  s.property->SetColor(color);
  s.property->SetScalarOpacity(opacity);
  s.property->SetScalarOpacityUnitDistance(0.1);
  s.perspective = false;

  auto preIntegrated = MakeMapper(Mapper::CPU_BACKEND);
  preIntegrated->SetShadingModeToPreIntegrated();
  auto compatible = MakeMapper(Mapper::CPU_BACKEND);
  vtkNew<vtkProjectedTetrahedraMapper> vtkPT;
  auto image = Render(s, preIntegrated);
  Save(image, "MTPT_PreIntegrated_narrow_peak");
  const double covered = CoveredFraction(image, Background);
  const double coveredCompatible = CoveredFraction(Render(s, compatible), Background);
  const double coveredVTK = CoveredFraction(Render(s, vtkPT), Background);
  // Every ray through the layer's middle crosses the whole peak: optical depth =
  // (integral of opacity over the scalar) / unit distance / (d scalar / d length), with
  // d scalar / d length = |view direction x| / 2 (camera: azimuth 30, elevation 20).
  const double pi = 3.14159265358979;
  const double dx = std::sin(30 * pi / 180) * std::cos(20 * pi / 180);
  const double alpha = 1.0 - std::exp(-(0.02 / 0.1) / (0.5 * dx));
  const double expected[3] = { 0.9 * alpha + (1 - alpha) * Background[0],
    0.6 * alpha + (1 - alpha) * Background[1], 0.1 * alpha + (1 - alpha) * Background[2] };
  std::size_t layer = 0, matching = 0;
  const auto* rgb = static_cast<const unsigned char*>(image->GetScalarPointer());
  for (vtkIdType p = 0; p < image->GetNumberOfPoints(); ++p)
  {
    bool background = true, match = true;
    for (int c = 0; c < 3; ++c)
    {
      background = background && std::fabs(rgb[3 * p + c] / 255.0 - Background[c]) <= 2.0 / 255;
      match = match && std::fabs(rgb[3 * p + c] / 255.0 - expected[c]) <= 2.0 / 255;
    }
    layer += background ? 0 : 1;
    matching += match ? 1 : 0;
  }
  std::printf("narrow peak: covered fraction pre-integrated %.3f (%.1f%% of it within 2/255 of "
              "the exact colour), VTK-compatible %.4f, VTK PT %.4f\n",
    covered, 100.0 * matching / std::max<std::size_t>(layer, 1), coveredCompatible, coveredVTK);
  EXPECT_GT(covered, 0.1);
  // Only rays near the box's faces cross part of the layer.
  EXPECT_GT(matching, 0.85 * layer);
  EXPECT_LT(coveredVTK, 0.001);

  // Smooth transfer functions: both modes agree closely (the vertices resolve them).
  const Scene smooth = BluntFinScene(true);
  auto smoothCompatible = MakeMapper(Mapper::CPU_BACKEND);
  auto smoothPreIntegrated = MakeMapper(Mapper::CPU_BACKEND);
  smoothPreIntegrated->SetShadingModeToPreIntegrated();
  const ImageDifference d =
    Compare(Render(smooth, smoothPreIntegrated), Render(smooth, smoothCompatible));
  std::printf(
    "smooth bluntfin: pre-integrated vs VTK-compatible RMSE %.5f, worst %.3f\n", d.rmse, d.worst);
  EXPECT_LT(d.worst, 0.05);
  EXPECT_LT(d.rmse, 0.02);
}

TEST_F(MapperImages, AutomaticBackendPicksTheCPUCompositorOnSoftwareOpenGL)
{
  EXPECT_TRUE(Mapper::IsSoftwareRenderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_TRUE(Mapper::IsSoftwareRenderer("Gallium 0.4 on softpipe"));
  EXPECT_FALSE(Mapper::IsSoftwareRenderer("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
  EXPECT_FALSE(Mapper::IsSoftwareRenderer(nullptr));
  // Ask this machine's OpenGL which renderer it is, and check the automatic choice.
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->Render();
  const std::string capabilities = window->ReportCapabilities();
  const std::string key = "OpenGL renderer string:";
  const auto at = capabilities.find(key);
  ASSERT_NE(at, std::string::npos);
  const std::string renderer =
    capabilities.substr(at + key.size(), capabilities.find('\n', at) - at - key.size());
  auto mapper = MakeMapper(Mapper::AUTOMATIC_BACKEND);
  Render(BoxScene(true), mapper);
  if (Mapper::IsSoftwareRenderer(renderer.c_str()))
  {
    EXPECT_EQ(mapper->GetLastBackend(), Mapper::CPU_BACKEND) << renderer;
    EXPECT_GT(mapper->GetCompositeSeconds(), 0.0);
  }
  else
  {
    EXPECT_EQ(mapper->GetLastBackend(), Mapper::OPENGL_BACKEND) << renderer;
  }
}

/// The mapper's own output against its stored baseline: same renderer, same build, so
/// identical up to driver rounding.
void ExpectMatchesBaseline(const Scene& scene, const std::string& name)
{
  for (int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    const std::string label = name + (backend == Mapper::CPU_BACKEND ? "_CPU" : "");
    auto mapper = MakeMapper(backend);
    const ImageDifference d = CompareWithBaseline(Render(scene, mapper), label);
    std::printf("baseline %s: RMSE %.5f worst %.3f\n", label.c_str(), d.rmse, d.worst);
    EXPECT_LT(d.coveredRmse, 0.005) << label;
    EXPECT_LT(d.worst, 0.05) << label;
  }
}

TEST_F(MapperImages, BaselineSyntheticPerspective)
{
  ExpectMatchesBaseline(BoxScene(true), "MTPT_BoxPerspective");
}

TEST_F(MapperImages, BaselineRealMeshOrthographic)
{
  ExpectMatchesBaseline(BluntFinScene(false), "MTPT_BluntFinOrthographic");
}

} // namespace
