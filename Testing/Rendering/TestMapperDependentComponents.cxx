// SPDX-License-Identifier: BSD-3-Clause
// Dependent components (the volume property's IndependentComponents off), mapped as VTK's
// PT maps them: four components are the colour and the opacity themselves (unsigned chars
// used as they are, other types as values in [0, 1]); two are a colour scalar (through the
// colour transfer function) and an opacity scalar (through the scalar opacity function).
// Each case, point and cell data, both backends, three directions with the cells shuffled,
// against VTK's PT in the same process and against the exact reference, which maps the
// same way; any other component count is VTK's warning and nothing drawn; pre-integrated
// shading falls back to VTK-compatible shading with one warning; switching between
// independent and dependent components, or changing the colour function of the
// two-component mapping, redraws exactly as a fresh mapper.
//
// Metric and thresholds as in TestMapperImages.cxx (RenderingTestUtilities.h): measured
// values are in the comments (Mesa llvmpipe, 200x200), bounds sit above them.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// A colour and an attenuation in [0, 1] at a point of the box [-1, 1]^3: smooth, with
/// every channel varying, transparent in one corner (so that culling has cells to cull).
void ColourAt(const double p[3], double rgba[4])
{
  const double x = p[0], y = p[1], z = p[2];
  rgba[0] = 0.5 + 0.5 * std::sin(2.5 * x + 0.5);
  rgba[1] = 0.5 + 0.5 * std::cos(2.0 * y - z);
  rgba[2] = 0.5 + 0.45 * std::sin(1.7 * z + x);
  rgba[3] = std::max(0.0, std::min(1.0, 0.55 + 0.45 * std::sin(1.3 * (x + y) + 0.8 * z)));
}

/// The scalars of the two-component mapping at a point: a colour scalar in about
/// [-0.3, 1.3] and an opacity scalar in [0, 1].
void ScalarsAt(const double p[3], double s[2])
{
  s[0] = 0.5 + 0.8 * std::sin(1.5 * p[0] + p[1]) * std::cos(p[2]);
  s[1] = 0.5 + 0.5 * std::sin(2.0 * p[1] - 1.2 * p[2] + 0.3 * p[0]);
}

/// The centre of cell `c`.
void CellCentre(vtkUnstructuredGrid* grid, vtkIdType c, double centre[3])
{
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  grid->GetCellPoints(c, n, ids);
  centre[0] = centre[1] = centre[2] = 0;
  for (vtkIdType k = 0; k < n; ++k)
  {
    double q[3];
    grid->GetPoint(ids[k], q);
    for (int d = 0; d < 3; ++d)
    {
      centre[d] += q[d] / static_cast<double>(n);
    }
  }
}

/// What a dependent array holds.
enum class Components
{
  UnsignedCharRGBA,
  FloatRGBA,
  ColourAndOpacity
};

/// A copy of `box` whose active point (or cell) scalars are the dependent array `kind`.
vtkSmartPointer<vtkUnstructuredGrid> WithComponents(
  vtkUnstructuredGrid* box, Components kind, bool cellData)
{
  vtkSmartPointer<vtkDataArray> array;
  if (kind == Components::UnsignedCharRGBA)
  {
    array = vtkSmartPointer<vtkUnsignedCharArray>::New();
  }
  else
  {
    array = vtkSmartPointer<vtkFloatArray>::New();
  }
  const int components = kind == Components::ColourAndOpacity ? 2 : 4;
  array->SetNumberOfComponents(components);
  array->SetName("dependent");
  const vtkIdType tuples = cellData ? box->GetNumberOfCells() : box->GetNumberOfPoints();
  array->SetNumberOfTuples(tuples);
  for (vtkIdType t = 0; t < tuples; ++t)
  {
    double p[3];
    if (cellData)
    {
      CellCentre(box, t, p);
    }
    else
    {
      box->GetPoint(t, p);
    }
    double values[4];
    if (kind == Components::ColourAndOpacity)
    {
      ScalarsAt(p, values);
    }
    else
    {
      ColourAt(p, values);
    }
    for (int c = 0; c < components; ++c)
    {
      // Unsigned chars are colours in 0-255, as VTK's PT reads them.
      array->SetComponent(t, c,
        kind == Components::UnsignedCharRGBA ? std::floor(values[c] * 255.0 + 0.5) : values[c]);
    }
  }
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(box);
  grid->GetPointData()->Initialize();
  grid->GetCellData()->Initialize();
  if (cellData)
  {
    grid->GetCellData()->SetScalars(array);
  }
  else
  {
    grid->GetPointData()->SetScalars(array);
  }
  return grid;
}

/// Dependent components; for two components a colour ramp over the colour scalar and an
/// opacity rising over the opacity scalar (the functions four components do not read).
vtkSmartPointer<vtkVolumeProperty> DependentProperty()
{
  auto property = MakeProperty(-0.3, 1.3, 0.5);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(0.3, 0.1);
  opacity->AddPoint(1.0, 0.9);
  property->SetScalarOpacity(opacity);
  property->IndependentComponentsOff();
  return property;
}

class MapperDependentComponents : public ::testing::Test
{
protected:
  static void SetUpTestSuite() { Box = ShuffleCells(MakeTetrahedralBox(12), 4); }
  static void TearDownTestSuite() { Box = nullptr; }
  Scene ComponentScene(Components kind, bool cellData, bool perspective = true)
  {
    Grids.push_back(WithComponents(Box, kind, cellData));
    return MakeScene(Grids.back(), DependentProperty(), perspective);
  }
  static vtkSmartPointer<vtkUnstructuredGrid> Box;
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> Grids; ///< kept alive for the scenes
};
vtkSmartPointer<vtkUnstructuredGrid> MapperDependentComponents::Box;

// Limits: { RMSE over covered pixels, worst pixel, fraction of covered pixels over 0.1 }.
const Limits AgainstVTK{ 0.004, 0.03, 0.001 };
// Four components: measured against VTK's PT RMSE 0.0016-0.0020, worst 0.004-0.016 (cell
// data 0.0004-0.0005); against the reference 0.0013-0.0016, worst 0.004.
const Limits AgainstReference{ 0.003, 0.015, 0.001 };
// Two components: classified at the vertices (VTK's model, as VTK-compatible shading of one
// scalar), so the kinks of both transfer functions between vertex values are smoothed over:
// measured against VTK's PT 0.0018-0.0031, worst 0.004-0.024; against the reference
// 0.0027-0.0049, worst 0.024-0.047.
const Limits TwoAgainstReference{ 0.007, 0.07, 0.001 };

TEST_F(MapperDependentComponents, FourUnsignedCharComponentsMatchVTK)
{
  ExpectCloseToVTK(ComponentScene(Components::UnsignedCharRGBA, false), "rgba8", AgainstVTK);
}

TEST_F(MapperDependentComponents, FourFloatComponentsMatchVTK)
{
  ExpectCloseToVTK(ComponentScene(Components::FloatRGBA, false, false), "rgbaf", AgainstVTK);
}

TEST_F(MapperDependentComponents, TwoComponentsMatchVTK)
{
  ExpectCloseToVTK(ComponentScene(Components::ColourAndOpacity, false), "two", AgainstVTK);
}

TEST_F(MapperDependentComponents, CellDataMatchesVTK)
{
  ExpectCloseToVTK(ComponentScene(Components::UnsignedCharRGBA, true), "rgba8-cells", AgainstVTK);
  ExpectCloseToVTK(ComponentScene(Components::ColourAndOpacity, true), "two-cells", AgainstVTK);
}

TEST_F(MapperDependentComponents, EveryCaseMatchesTheReference)
{
  ExpectCloseToReference(ComponentScene(Components::UnsignedCharRGBA, false), "rgba8",
    AgainstReference, Mapper::VTK_COMPATIBLE_SHADING);
  ExpectCloseToReference(ComponentScene(Components::FloatRGBA, true), "rgbaf-cells",
    AgainstReference, Mapper::VTK_COMPATIBLE_SHADING);
  ExpectCloseToReference(ComponentScene(Components::ColourAndOpacity, false), "two",
    TwoAgainstReference, Mapper::VTK_COMPATIBLE_SHADING);
}

TEST_F(MapperDependentComponents, OtherComponentCountsWarnAndDrawNothing)
{
  auto grid = WithComponents(Box, Components::FloatRGBA, false);
  vtkNew<vtkFloatArray> three;
  three->SetName("three");
  three->SetNumberOfComponents(3);
  three->SetNumberOfTuples(grid->GetNumberOfPoints());
  three->Fill(0.5);
  grid->GetPointData()->SetScalars(three);
  for (int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    auto mapper = MakeMapper(backend);
    vtkNew<MessageObserver> messages;
    mapper->AddObserver(vtkCommand::ErrorEvent, messages);
    mapper->AddObserver(vtkCommand::WarningEvent, messages);
    Scene scene = MakeScene(grid, DependentProperty(), true);
    auto image = Render(scene, mapper, 2);
    EXPECT_EQ(CoveredFraction(image, Background), 0.0) << "nothing is drawn";
    EXPECT_TRUE(messages->errors.empty());
    ASSERT_EQ(messages->warnings.size(), 1u) << "one warning for two frames";
    EXPECT_NE(messages->warnings[0].find("'three' has 3"), std::string::npos)
      << messages->warnings[0];
  }
}

TEST_F(MapperDependentComponents, PreIntegratedShadingFallsBackWithOneWarning)
{
  const Scene scene = ComponentScene(Components::ColourAndOpacity, false);
  for (int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    auto compatible = MakeMapper(backend);
    auto preIntegrated = MakeMapper(backend);
    preIntegrated->SetShadingModeToPreIntegrated();
    vtkNew<MessageObserver> messages;
    preIntegrated->AddObserver(vtkCommand::WarningEvent, messages);
    auto expected = Render(scene, compatible);
    auto image = Render(scene, preIntegrated, 2);
    EXPECT_EQ(Compare(image, expected).worst, 0.0) << ShortBackendName(backend);
    ASSERT_EQ(messages->warnings.size(), 1u);
    EXPECT_NE(messages->warnings[0].find("VTK-compatible"), std::string::npos);
  }
}

TEST_F(MapperDependentComponents, ChangesBetweenFramesRedrawAsAFreshMapper)
{
  // Independent -> dependent -> a new colour function, each frame against a fresh mapper.
  Scene scene = ComponentScene(Components::ColourAndOpacity, false);
  for (int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    auto property = DependentProperty();
    property->IndependentComponentsOn();
    scene.property = property;
    auto mapper = MakeMapper(backend);
    const Stage stage = RenderStage(scene, mapper);
    auto check = [&](const std::string& step)
    {
      stage.window->Render();
      auto image = Grab(stage.window, false);
      auto freshMapper = MakeMapper(backend);
      const Stage fresh = RenderStage(scene, freshMapper);
      EXPECT_EQ(Compare(image, Grab(fresh.window, false)).worst, 0.0)
        << ShortBackendName(backend) << ": " << step;
      freshMapper->ReleaseGraphicsResources(fresh.window);
      return image;
    };
    auto independent = check("independent components");
    property->IndependentComponentsOff();
    auto dependent = check("dependent components");
    EXPECT_GT(Compare(independent, dependent).coveredRmse, 0.01) << "the mapping changed";
    property->GetRGBTransferFunction(0)->AddRGBPoint(0.5, 0.0, 1.0, 0.0);
    auto recoloured = check("a new colour function");
    EXPECT_GT(Compare(dependent, recoloured).coveredRmse, 0.01) << "the colours changed";
    mapper->ReleaseGraphicsResources(stage.window);
  }
}

} // namespace
