// SPDX-License-Identifier: BSD-3-Clause
// Bad input gets a clear VTK error or warning and no crash, and the next valid frame
// renders as if nothing happened; window resizes, several renderers and several windows.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

bool AnyContains(const std::vector<std::string>& messages, const std::string& text)
{
  for (const auto& m : messages)
  {
    if (m.find(text) != std::string::npos)
    {
      return true;
    }
  }
  return false;
}

class MapperRobustness : public ::testing::Test
{
protected:
  void SetUp() override
  {
    this->Box = MakeTetrahedralBox(8);
    this->Property = MakeProperty(-0.3, 1.3, 0.5);
    this->Observer = vtkSmartPointer<MessageObserver>::New();
    this->MapperUnderTest = vtkSmartPointer<Mapper>::New();
    this->MapperUnderTest->AddObserver(vtkCommand::ErrorEvent, this->Observer);
    this->MapperUnderTest->AddObserver(vtkCommand::WarningEvent, this->Observer);
  }
  Scene SceneOf(vtkUnstructuredGrid* grid)
  {
    Scene s;
    s.grid = grid;
    s.property = this->Property;
    return s;
  }
  /// The reference: a fresh mapper rendering the valid box.
  vtkSmartPointer<vtkImageData> FreshBoxImage(int size = 200)
  {
    vtkNew<Mapper> fresh;
    Scene s = SceneOf(this->Box);
    s.size = size;
    return Render(s, fresh);
  }
  /// After bad input, the same mapper must render the valid box exactly as a fresh one.
  void ExpectRecovers()
  {
    const ImageDifference d =
      Compare(Render(SceneOf(this->Box), this->MapperUnderTest), FreshBoxImage());
    EXPECT_EQ(d.worst, 0.0);
  }
  vtkSmartPointer<vtkUnstructuredGrid> Box;
  vtkSmartPointer<vtkVolumeProperty> Property;
  vtkSmartPointer<MessageObserver> Observer;
  vtkSmartPointer<Mapper> MapperUnderTest;
};

TEST_F(MapperRobustness, NonTetrahedralCellsAreReportedAndNothingIsDrawn)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  const vtkIdType hexahedron[8] = { 0, 1, 2, 3, 4, 5, 6, 7 };
  grid->InsertNextCell(VTK_HEXAHEDRON, 8, hexahedron);
  auto image = Render(SceneOf(grid), this->MapperUnderTest);
  ASSERT_TRUE(AnyContains(this->Observer->errors, "not tetrahedra"));
  EXPECT_TRUE(AnyContains(this->Observer->errors, "vtkDataSetTriangleFilter"));
  EXPECT_LT(CoveredFraction(image, Background), 0.001); // no garbage image
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, MissingScalarsAreReported)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->ShallowCopy(this->Box);
  grid->GetPointData()->SetScalars(nullptr);
  grid->GetPointData()->RemoveArray("field");
  auto image = Render(SceneOf(grid), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->errors, "no scalars"));
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, MisnamedArrayIsReported)
{
  this->MapperUnderTest->SetScalarModeToUsePointFieldData();
  this->MapperUnderTest->SelectScalarArray("no-such-array");
  Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->errors, "no scalars"));
  // Selecting the right array by name renders the same image as the active scalars.
  this->MapperUnderTest->SelectScalarArray("field");
  const ImageDifference d =
    Compare(Render(SceneOf(this->Box), this->MapperUnderTest), FreshBoxImage());
  EXPECT_EQ(d.worst, 0.0);
}

TEST_F(MapperRobustness, EmptyGridIsReported)
{
  vtkNew<vtkUnstructuredGrid> empty;
  vtkNew<vtkPoints> points;
  empty->SetPoints(points);
  empty->Allocate(1);
  auto image = Render(SceneOf(empty), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "no cells"));
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, NaNScalarsAreReportedAndTheirCellsSkipped)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  auto* field = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
  for (vtkIdType i = 0; i < field->GetNumberOfTuples(); i += 37)
  {
    field->SetValue(i, std::numeric_limits<float>::quiet_NaN());
  }
  auto image = Render(SceneOf(grid), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "NaN"));
  // The rest still renders: most of the box is there, and no pixel is garbage (the image
  // stays close to the valid one away from the skipped cells).
  EXPECT_GT(CoveredFraction(image, Background), 0.15);
  EXPECT_LT(Compare(image, FreshBoxImage()).rmse, 0.1);
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, NegativeThreadCountsAreRejected)
{
  this->MapperUnderTest->SetNumberOfThreads(3);
  this->MapperUnderTest->SetNumberOfThreads(-2);
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfThreads(), 3);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "thread count"));
  this->MapperUnderTest->SetNumberOfThreads(0);
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfThreads(), 0);
}

TEST_F(MapperRobustness, StageTimersAndCountsAfterARender)
{
  this->MapperUnderTest->SynchronizedTimingOn();
  Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfTetrahedra(), this->Box->GetNumberOfCells());
  EXPECT_GT(this->MapperUnderTest->GetCPUStageSeconds(), 0.0);
  EXPECT_GT(this->MapperUnderTest->GetDrawSeconds(), 0.0);
  EXPECT_GE(this->MapperUnderTest->GetUploadSeconds(), 0.0);
  EXPECT_NEAR(this->MapperUnderTest->GetCPUStageSeconds(),
    this->MapperUnderTest->GetTransformSeconds() + this->MapperUnderTest->GetDepthKeySeconds() +
      this->MapperUnderTest->GetOrderSeconds() + this->MapperUnderTest->GetDecomposeSeconds(),
    1e-12);
  std::ostringstream print;
  this->MapperUnderTest->Print(print);
  EXPECT_NE(print.str().find("OrderMethod: RadixSort"), std::string::npos);
  EXPECT_NE(print.str().find("NumberOfThreads: 0 (all cores)"), std::string::npos);
  EXPECT_TRUE(this->Observer->errors.empty());
}

TEST_F(MapperRobustness, SurvivesResizesAndRepeatedFrames)
{
  Scene s = SceneOf(this->Box);
  s.size = 300;
  // Two frames, the second with everything cached, at a size different from before.
  Render(SceneOf(this->Box), this->MapperUnderTest);
  const ImageDifference d = Compare(Render(s, this->MapperUnderTest, 2), FreshBoxImage(300));
  EXPECT_EQ(d.worst, 0.0);
}

/// The pixels of columns [x0, x0 + width) of an RGB image.
std::vector<unsigned char> Columns(vtkImageData* image, int x0, int width)
{
  int dims[3];
  image->GetDimensions(dims);
  auto* p = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  std::vector<unsigned char> out;
  for (int y = 0; y < dims[1]; ++y)
  {
    for (int x = x0; x < x0 + width; ++x)
    {
      for (int c = 0; c < 3; ++c)
      {
        out.push_back(p->GetValue((y * dims[0] + x) * 3 + c));
      }
    }
  }
  return out;
}

TEST_F(MapperRobustness, SeveralRenderersInOneWindowAndOneMapperInTwoWindows)
{
  // Two renderers side by side, each with its own mapper: each half must equal a
  // single-renderer image (the float framebuffer copy honours the viewport origin).
  const auto expected = FreshBoxImage(200);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->SetSize(400, 200);
  vtkNew<Mapper> left, right;
  for (int side = 0; side < 2; ++side)
  {
    vtkNew<vtkVolume> volume;
    Mapper* mapper = side == 0 ? left.Get() : right.Get();
    mapper->SetInputData(this->Box);
    volume->SetMapper(mapper);
    volume->SetProperty(this->Property);
    vtkNew<vtkRenderer> renderer;
    renderer->SetViewport(0.5 * side, 0, 0.5 * side + 0.5, 1);
    renderer->SetBackground(Background[0], Background[1], Background[2]);
    renderer->AddVolume(volume);
    window->AddRenderer(renderer);
    renderer->ResetCamera();
    renderer->GetActiveCamera()->Azimuth(30);
    renderer->GetActiveCamera()->Elevation(20);
    renderer->GetActiveCamera()->OrthogonalizeViewUp();
    renderer->ResetCameraClippingRange();
  }
  window->Render();
  const auto image = Grab(window);
  const auto reference = Columns(expected, 0, 200);
  EXPECT_EQ(Columns(image, 0, 200), reference) << "left renderer";
  EXPECT_EQ(Columns(image, 200, 200), reference) << "right renderer";
  left->ReleaseGraphicsResources(window);
  right->ReleaseGraphicsResources(window);

  // One mapper drawn in two windows in turn: resources move with it.
  const auto first = Render(SceneOf(this->Box), this->MapperUnderTest);
  const auto second = Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_EQ(Compare(first, expected).worst, 0.0);
  EXPECT_EQ(Compare(second, expected).worst, 0.0);
  EXPECT_TRUE(this->Observer->errors.empty());
}

} // namespace
