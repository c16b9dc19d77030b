// SPDX-License-Identifier: BSD-3-Clause
// Bad input gets a clear VTK error or warning and no crash, and the next valid frame
// renders as if nothing happened; window resizes, several renderers and several windows.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "mtpt/Threads.h"

#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnsignedIntArray.h"
#include "vtkVersionMacros.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

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
  /// One frame of the valid box by a fresh mapper, read back without rendering again.
  vtkSmartPointer<vtkImageData> FreshFrame(int backend)
  {
    vtkNew<Mapper> fresh;
    fresh->SetBackend(backend);
    const Stage stage = RenderStage(SceneOf(this->Box), fresh, 1);
    auto image = Grab(stage.window, false);
    fresh->ReleaseGraphicsResources(stage.window);
    return image;
  }
  /// The camera inside the box, looking at its centre from a tenth of its width and a fifth
  /// of its depth away, turned by `azimuth` degrees: the near plane cuts cells.
  void LookFromInsideTheBox(vtkCamera* camera, double azimuth) const
  {
    double bounds[6];
    this->Box->GetBounds(bounds);
    const double centre[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
      0.5 * (bounds[4] + bounds[5]) };
    camera->SetFocalPoint(centre);
    camera->SetPosition(centre[0] + 0.1 * (bounds[1] - bounds[0]), centre[1],
      centre[2] + 0.2 * (bounds[5] - bounds[4]));
    camera->SetViewUp(0, 1, 0);
    camera->Azimuth(azimuth);
    camera->SetClippingRange(0.01 * (bounds[1] - bounds[0]), 10 * (bounds[1] - bounds[0]));
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

TEST_F(MapperRobustness, UnknownBlendModeIsReportedOnce)
{
  // A blend mode beyond vtkVolumeMapper's 0 to 4 is an error, reported once; the volume is
  // drawn composited, the image of a mapper without it.
  const auto plain = FreshBoxImage();
  this->MapperUnderTest->SetBlendMode(7);
  auto image = Render(SceneOf(this->Box), this->MapperUnderTest, 3);
  auto count = [&](const std::vector<std::string>& messages, const char* text)
  {
    return std::count_if(messages.begin(), messages.end(),
      [text](const std::string& w) { return w.find(text) != std::string::npos; });
  };
  EXPECT_EQ(count(this->Observer->errors, "blend mode 7 is none of 0 (composite) to 4"), 1);
  EXPECT_EQ(Compare(image, plain).worst, 0.0);
}

TEST_F(MapperRobustness, NonTetrahedralCellsAreSplitNotRejected)
{
  // A hexahedron on eight collinear points (no volume) among the tetrahedra: the grid is
  // split into tetrahedra (see TestMapperCellTypes.cxx) and draws as the box alone.
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  const vtkIdType hexahedron[8] = { 0, 1, 2, 3, 4, 5, 6, 7 };
  grid->InsertNextCell(VTK_HEXAHEDRON, 8, hexahedron);
  auto image = Render(SceneOf(grid), this->MapperUnderTest);
  EXPECT_TRUE(this->Observer->errors.empty());
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfTetrahedralizations(), 1);
  const ImageDifference d = Compare(image, FreshBoxImage());
  std::cout << "box plus a flat hexahedron against the box: RMSE " << d.rmse << "\n";
  EXPECT_LT(d.rmse, 1e-3);
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
  Render(SceneOf(this->Box), this->MapperUnderTest, 2);
  EXPECT_EQ(this->Observer->errors.size(), 1u) << "once, not per frame";
  EXPECT_TRUE(AnyContains(this->Observer->errors, "no scalars"));
  EXPECT_TRUE(AnyContains(this->Observer->errors, "point array named 'no-such-array'"));
  // Another wrong name, or a wrong index into the cell arrays, is reported too.
  this->MapperUnderTest->SelectScalarArray("nor-this-one");
  Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->errors, "'nor-this-one'"));
  this->MapperUnderTest->SetScalarModeToUseCellFieldData();
  this->MapperUnderTest->SelectScalarArray(7);
  Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->errors, "cell array number 7"));
  EXPECT_EQ(this->Observer->errors.size(), 3u);
  this->MapperUnderTest->SetScalarModeToUsePointFieldData();
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

TEST_F(MapperRobustness, AMeshOverTheMemoryLimitIsReportedAndNotDrawn)
{
  // A limit below what the box's buffers need (mtpt::FramePipeline::BytesNeeded): every
  // frame is refused before a buffer is allocated, with an error saying what it needs and
  // what to change, and the background shows. A limit the frame fits, or the default (the
  // memory available), draws the box as a fresh mapper does. The frames draw a fraction of
  // the cells, so that the level of detail's importance order would be built too.
  this->MapperUnderTest->SetMemoryLimit(1024);
  this->MapperUnderTest->AutoAdjustCellFractionOff();
  this->MapperUnderTest->SetCellFraction(0.5f);
  const auto image = Render(SceneOf(this->Box), this->MapperUnderTest, 2);
  // Two frames and the render of the read-back: an error for each.
  ASSERT_EQ(this->Observer->errors.size(), 3u);
  // A limit under 1 MiB is given in bytes, and so is the need beside it.
  for (const std::string& error : this->Observer->errors)
  {
    const std::string needs = "needs up to ";
    const std::size_t at = error.find(needs);
    ASSERT_NE(at, std::string::npos) << error;
    std::size_t digits = 0;
    const unsigned long long bytes = std::stoull(error.substr(at + needs.size()), &digits);
    EXPECT_GT(bytes, 1024u) << error;
    // VTK's error macro ends the message with its own line breaks.
    const std::string rest = " bytes of buffers, over the memory limit of 1024 bytes "
                             "(SetMemoryLimit); nothing was drawn. A smaller batch size "
                             "(SetBatchSize, now 1048576), a larger limit or fewer cells may fit";
    EXPECT_EQ(error.compare(at + needs.size() + digits, rest.size(), rest), 0) << error;
  }
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  EXPECT_EQ(this->MapperUnderTest->GetMemoryBytes(), 0);
  this->MapperUnderTest->SetCellFraction(1.0f);
  this->MapperUnderTest->AutoAdjustCellFractionOn();
  this->Observer->Clear();
  this->MapperUnderTest->SetMemoryLimit(-5);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "keeping 1024"));
  this->MapperUnderTest->SetMemoryLimit(64 << 20);
  this->ExpectRecovers();
  this->MapperUnderTest->SetMemoryLimit(0);
  this->ExpectRecovers();
  EXPECT_TRUE(this->Observer->errors.empty());
  EXPECT_GT(this->MapperUnderTest->GetMemoryBytes(), 0);
}

TEST_F(MapperRobustness, TheMemoryBoundHoldsTheNearPlanesPieces)
{
  // From inside the box the near plane cuts cells into pieces, which the frame allocates
  // beside the mesh's buffers. The bound the frame is checked against includes them (known
  // once the cells are cut), so it holds what the buffers take; a limit between the bound
  // without them and the bound with them refuses the frame, with the error, and frees the
  // buffers. From outside, no pieces: the smaller bound.
  for (const int backend : Backends)
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackend(backend);
    mapper->AddObserver(vtkCommand::ErrorEvent, this->Observer);
    mapper->AddObserver(vtkCommand::WarningEvent, this->Observer);
    const Stage stage = MakeStage(this->Box, this->Property, mapper, 200, 200);
    const auto inside = [&](const Stage& on)
    {
      this->LookFromInsideTheBox(on.renderer->GetActiveCamera(), 0);
      on.window->Render();
    };
    stage.window->Render(); // from outside
    const vtkIdType outside = mapper->GetMemoryBytesBound();
    EXPECT_GT(outside, 0);
    EXPECT_LE(mapper->GetMemoryBytes(), outside);
    inside(stage);
    const vtkIdType cut = mapper->GetMemoryBytesBound();
    EXPECT_GT(mapper->GetNumberOfNearClippedCells(), 0) << BackendName(backend);
    EXPECT_GT(cut, outside) << BackendName(backend);
    EXPECT_LE(mapper->GetMemoryBytes(), cut) << BackendName(backend);
    ASSERT_TRUE(this->Observer->errors.empty());

    vtkNew<Mapper> limited;
    limited->SetBackend(backend);
    limited->SetMemoryLimit((outside + cut) / 2);
    limited->AddObserver(vtkCommand::ErrorEvent, this->Observer);
    limited->AddObserver(vtkCommand::WarningEvent, this->Observer);
    const Stage limitedStage = MakeStage(this->Box, this->Property, limited, 200, 200);
    inside(limitedStage);
    ASSERT_EQ(this->Observer->errors.size(), 1u) << BackendName(backend);
    EXPECT_TRUE(AnyContains(this->Observer->errors, "over the memory limit"));
    EXPECT_EQ(limited->GetMemoryBytes(), 0) << BackendName(backend);
    EXPECT_EQ(limited->GetMemoryBytesBound(), cut) << BackendName(backend);
    this->Observer->Clear();
    mapper->ReleaseGraphicsResources(stage.window);
    limited->ReleaseGraphicsResources(limitedStage.window);
  }
}

/**
 * An allocation that fails partway through a frame (MTPT_TESTING_FAULT=allocation:SITE, at
 * each site of mtpt/Faults.h, with each backend that reaches it): reported once, nothing
 * drawn, no buffer kept, and the next frame, from the view the frame before drew, is a fresh
 * mapper's. The failing frame turns the view and comes after the data were modified, so
 * that every stage computes anew, and fails with some stages done and the rest not; the
 * near-plane site's frames look from inside the box, so that the near plane cuts cells; the
 * level of detail's draw half of the cells.
 */
class MapperAllocationFaults
  : public MapperRobustness
  , public ::testing::WithParamInterface<std::tuple<std::string, int>>
{
protected:
  void SetUpMapper(Mapper* mapper) const
  {
    const auto& [site, backend] = this->GetParam();
    mapper->SetBackend(backend);
    if (site == "level-of-detail")
    {
      mapper->AutoAdjustCellFractionOff();
      mapper->SetCellFraction(0.5f);
    }
  }
  /// From outside the box at `azimuth` degrees, or from inside it for the near plane.
  void Look(vtkRenderer* renderer, double azimuth) const
  {
    // From one view each time: Azimuth and Elevation turn the camera from where it is.
    vtkCamera* camera = renderer->GetActiveCamera();
    camera->SetFocalPoint(0, 0, 0);
    camera->SetPosition(0, 0, 1);
    camera->SetViewUp(0, 1, 0);
    renderer->ResetCamera();
    camera->Azimuth(azimuth);
    camera->Elevation(20);
    if (std::get<0>(this->GetParam()) == "near-plane")
    {
      this->LookFromInsideTheBox(camera, azimuth);
    }
  }
  vtkSmartPointer<vtkImageData> Frame(const Stage& stage, double azimuth) const
  {
    this->Look(stage.renderer, azimuth);
    stage.window->Render();
    return Grab(stage.window, false);
  }
};

TEST_P(MapperAllocationFaults, AreReportedAndTheNextFrameIsWhole)
{
  const std::string site = std::get<0>(this->GetParam());
  this->SetUpMapper(this->MapperUnderTest);
  const Stage stage = MakeStage(this->Box, this->Property, this->MapperUnderTest, 200, 200);
  this->Frame(stage, 30);
  ASSERT_TRUE(this->Observer->errors.empty());
  this->Box->Modified();
  setenv("MTPT_TESTING_FAULT", ("allocation:" + site).c_str(), 1);
  const auto failed = this->Frame(stage, 75);
  unsetenv("MTPT_TESTING_FAULT");
  ASSERT_EQ(this->Observer->errors.size(), 1u) << "the fault at " << site << " reported once";
  EXPECT_TRUE(AnyContains(this->Observer->errors,
    "ran out of memory drawing 2560 tetrahedra; "
    "nothing was drawn and the buffers were freed"))
    << this->Observer->errors[0];
  EXPECT_LT(CoveredFraction(failed, Background), 0.001);
  EXPECT_EQ(this->MapperUnderTest->GetMemoryBytes(), 0);
  const auto again = this->Frame(stage, 30);
  this->MapperUnderTest->ReleaseGraphicsResources(stage.window);
  vtkNew<Mapper> fresh;
  this->SetUpMapper(fresh);
  const Stage freshStage = MakeStage(this->Box, this->Property, fresh, 200, 200);
  const auto expected = this->Frame(freshStage, 30);
  fresh->ReleaseGraphicsResources(freshStage.window);
  EXPECT_GT(CoveredFraction(expected, Background), 0.05);
  EXPECT_EQ(Compare(again, expected).worst, 0.0) << "after a fault at " << site;
  EXPECT_EQ(this->Observer->errors.size(), 1u);
}

std::string SiteName(const ::testing::TestParamInfo<std::tuple<std::string, int>>& info)
{
  std::string name = std::get<0>(info.param) + "_" + ShortBackendName(std::get<1>(info.param));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

INSTANTIATE_TEST_SUITE_P(EverySite, MapperAllocationFaults,
  ::testing::Combine(::testing::Values("transform", "culling", "level-of-detail", "depth-keys",
                       "near-plane", "order", "decomposition"),
    ::testing::Values(Mapper::CPU_BACKEND, Mapper::OPENGL_BACKEND)),
  SiteName);
INSTANTIATE_TEST_SUITE_P(CPUCompositor, MapperAllocationFaults,
  ::testing::Values(std::make_tuple(std::string("tiles"), static_cast<int>(Mapper::CPU_BACKEND))),
  SiteName);

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

TEST_F(MapperRobustness, InfiniteScalarsAreReportedAndTheirCellsSkipped)
{
  for (const float bad :
    { std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity() })
  {
    this->Observer->Clear();
    vtkNew<vtkUnstructuredGrid> grid;
    grid->DeepCopy(this->Box);
    auto* field = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetScalars());
    for (vtkIdType i = 0; i < field->GetNumberOfTuples(); i += 37)
    {
      field->SetValue(i, bad);
    }
    auto image = Render(SceneOf(grid), this->MapperUnderTest, 2);
    EXPECT_EQ(this->Observer->warnings.size(), 1u) << "once, not per frame";
    EXPECT_TRUE(AnyContains(this->Observer->warnings, "NaN or infinite"));
    // The finite range sets the transfer-function table: the rest of the box looks as usual.
    EXPECT_GT(CoveredFraction(image, Background), 0.15);
    EXPECT_LT(Compare(image, FreshBoxImage()).rmse, 0.1);
    this->ExpectRecovers();
  }
}

TEST_F(MapperRobustness, NonFiniteCellScalarsAreReported)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  auto* cellField = vtkFloatArray::SafeDownCast(grid->GetCellData()->GetArray("cellField"));
  cellField->SetValue(3, std::numeric_limits<float>::quiet_NaN());
  cellField->SetValue(50, std::numeric_limits<float>::infinity());
  this->MapperUnderTest->SetScalarModeToUseCellFieldData();
  this->MapperUnderTest->SelectScalarArray("cellField");
  auto image = Render(SceneOf(grid), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "2 scalar values are NaN or infinite"));
  EXPECT_GT(CoveredFraction(image, Background), 0.15);
  this->MapperUnderTest->SetScalarModeToDefault();
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, NonFinitePointsAreReportedAndTheRestDrawn)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  vtkPoints* points = grid->GetPoints();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  vtkIdType bad = 0;
  for (vtkIdType i = 5; i < points->GetNumberOfPoints(); i += 41, ++bad)
  {
    double p[3];
    points->GetPoint(i, p);
    p[bad % 3] = (bad % 2) ? inf : ((bad % 4 == 2) ? -inf : nan);
    points->SetPoint(i, p);
  }
  // The volume's bounds (and so the camera and its clipping range) ignore those points.
  vtkNew<vtkVolume> volume;
  this->MapperUnderTest->SetInputData(grid);
  volume->SetMapper(this->MapperUnderTest);
  const double* bounds = volume->GetBounds();
  for (int b = 0; b < 6; ++b)
  {
    EXPECT_DOUBLE_EQ(bounds[b], b % 2 ? 1.0 : -1.0) << "bound " << b;
  }
  auto image = Render(SceneOf(grid), this->MapperUnderTest, 2);
  EXPECT_EQ(this->Observer->warnings.size(), 1u);
  EXPECT_TRUE(AnyContains(this->Observer->warnings,
    std::to_string(bad) + " of " + std::to_string(points->GetNumberOfPoints()) +
      " points have NaN or infinite coordinates"));
  EXPECT_TRUE(this->Observer->errors.empty());
  EXPECT_GT(CoveredFraction(image, Background), 0.15);
  EXPECT_LT(Compare(image, FreshBoxImage()).rmse, 0.1);
  this->ExpectRecovers();

  // Every point non-finite: nothing drawn, no crash.
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i)
  {
    points->SetPoint(i, nan, nan, nan);
  }
  points->Modified();
  image = Render(SceneOf(grid), this->MapperUnderTest);
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, OutOfRangeConnectivityIsReportedAndTheRestDrawn)
{
  vtkNew<vtkUnstructuredGrid> grid;
  grid->DeepCopy(this->Box);
  const vtkIdType points = grid->GetNumberOfPoints();
  const vtkIdType beyond[4] = { 0, 1, 2, points + 1000 }, negative[4] = { -7, 1, 2, 3 };
  grid->InsertNextCell(VTK_TETRA, 4, beyond);
  grid->InsertNextCell(VTK_TETRA, 4, negative);
  auto image = Render(SceneOf(grid), this->MapperUnderTest, 2);
  EXPECT_EQ(this->Observer->warnings.size(), 1u);
  EXPECT_TRUE(AnyContains(this->Observer->warnings,
    "2 connectivity entries name points outside [0, " + std::to_string(points) + ")"));
  EXPECT_TRUE(this->Observer->errors.empty());
  const ImageDifference d = Compare(image, FreshBoxImage());
  EXPECT_LT(d.rmse, 1e-3) << "the valid cells draw as the box";
  this->ExpectRecovers();
}

/// The same grid with its cells in another of vtkCellArray's storages.
vtkSmartPointer<vtkUnstructuredGrid> WithCellStorage(
  vtkUnstructuredGrid* grid, const std::string& kind)
{
  auto copy = vtkSmartPointer<vtkUnstructuredGrid>::New();
  copy->ShallowCopy(grid);
  vtkNew<vtkCellArray> cells;
  cells->DeepCopy(grid->GetCells());
  if (kind == "32-bit")
  {
    cells->ConvertTo32BitStorage();
  }
  else if (kind == "64-bit")
  {
    cells->ConvertTo64BitStorage();
  }
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
  else if (kind == "fixed-size 32-bit")
  {
    cells->ConvertToFixedSize32BitStorage();
  }
  else if (kind == "fixed-size 64-bit")
  {
    cells->ConvertToFixedSize64BitStorage();
  }
  else if (kind == "generic")
  {
    // Ids in arrays of a type no specialized storage has: VTK keeps them as they are.
    vtkNew<vtkUnsignedIntArray> offsets, connectivity;
    offsets->DeepCopy(grid->GetCells()->GetOffsetsArray());
    connectivity->DeepCopy(grid->GetCells()->GetConnectivityArray());
    cells->SetData(offsets, connectivity);
  }
#endif
  copy->SetCells(VTK_TETRA, cells);
  return copy;
}

/// The cell storages this VTK has: 32- and 64-bit always; fixed-size and generic from 9.6.
std::vector<std::string> CellStorages()
{
  std::vector<std::string> kinds = { "32-bit", "64-bit" };
#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 6, 0)
  kinds.insert(kinds.end(), { "fixed-size 32-bit", "fixed-size 64-bit", "generic" });
#endif
  return kinds;
}

TEST_F(MapperRobustness, EveryCellStorageDrawsTheSameImage)
{
  // Read in place where the storage has the core's layout; copied, with one warning that
  // says so, where it has not (VTK 9.6's generic storage). The image is the same.
  const auto reference = this->FreshBoxImage();
  for (const std::string& kind : CellStorages())
  {
    SCOPED_TRACE(kind);
    auto grid = WithCellStorage(this->Box, kind);
    this->Observer->Clear();
    vtkNew<Mapper> mapper;
    mapper->AddObserver(vtkCommand::WarningEvent, this->Observer);
    mapper->AddObserver(vtkCommand::ErrorEvent, this->Observer);
    Scene s = SceneOf(grid);
    auto image = Render(s, mapper, 2);
    EXPECT_EQ(Compare(image, reference).worst, 0.0);
    EXPECT_TRUE(this->Observer->errors.empty());
    const bool copied = kind == "generic";
    EXPECT_EQ(this->Observer->warnings.size(), copied ? 1u : 0u) << "once, not per frame";
    EXPECT_EQ(AnyContains(this->Observer->warnings, "cannot read in place"), copied);
    EXPECT_GT(CoveredFraction(image, Background), 0.1);
  }
}

TEST_F(MapperRobustness, GridsWithoutPointsAreReported)
{
  // No points and no cells at all.
  vtkNew<vtkUnstructuredGrid> bare;
  auto image = Render(SceneOf(bare), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "no cells"));
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  this->ExpectRecovers();

  // Cells but no points.
  this->Observer->Clear();
  vtkNew<vtkUnstructuredGrid> pointless;
  const vtkIdType tetrahedron[4] = { 0, 1, 2, 3 };
  pointless->InsertNextCell(VTK_TETRA, 4, tetrahedron);
  image = Render(SceneOf(pointless), this->MapperUnderTest);
  EXPECT_TRUE(AnyContains(this->Observer->errors, "no points"));
  EXPECT_LT(CoveredFraction(image, Background), 0.001);
  this->ExpectRecovers();
}

TEST_F(MapperRobustness, TinyAndEmptyViewportsAndWindows)
{
  for (const int backend : { Mapper::CPU_BACKEND, Mapper::OPENGL_BACKEND })
  {
    this->MapperUnderTest->SetBackend(backend);
    // A 1x1 window: one pixel. Valid, so drawn without a message.
    Scene one = SceneOf(this->Box);
    one.size = 1;
    auto image = Render(one, this->MapperUnderTest, 2);
    int dims[3];
    image->GetDimensions(dims);
    EXPECT_EQ(dims[0] * dims[1], 1);
    EXPECT_GT(this->MapperUnderTest->GetNumberOfTetrahedra(), 0);
    // A renderer with a zero-area viewport: nothing to draw, no work, no message.
    Scene empty = SceneOf(this->Box);
    empty.customize = [](vtkVolume*, vtkRenderer* renderer)
    { renderer->SetViewport(0.5, 0.5, 0.5, 0.5); };
    Render(empty, this->MapperUnderTest, 2);
    EXPECT_EQ(this->MapperUnderTest->GetNumberOfTetrahedra(), 0) << "no work for no pixels";
    // A zero-size window (VTK's X11 window keeps a usable size for SetSize(0, 0); this
    // checks that asking for it breaks nothing).
    Scene zero = SceneOf(this->Box);
    zero.size = 0;
    Render(zero, this->MapperUnderTest);
    EXPECT_TRUE(this->Observer->errors.empty()) << "backend " << backend;
    EXPECT_TRUE(this->Observer->warnings.empty()) << "backend " << backend;
    vtkNew<Mapper> fresh;
    fresh->SetBackend(backend);
    const ImageDifference d =
      Compare(Render(SceneOf(this->Box), this->MapperUnderTest), Render(SceneOf(this->Box), fresh));
    EXPECT_EQ(d.worst, 0.0) << "backend " << backend;
  }
}

TEST_F(MapperRobustness, ZeroAndLargeThreadCountsDrawTheSameImage)
{
  this->MapperUnderTest->SetNumberOfThreads(1);
  const auto single = Render(SceneOf(this->Box), this->MapperUnderTest);
  for (const int threads : { 0, 64 })
  {
    vtkNew<Mapper> mapper;
    mapper->SetNumberOfThreads(threads);
    EXPECT_EQ(mapper->GetNumberOfThreads(), threads);
    EXPECT_EQ(Compare(Render(SceneOf(this->Box), mapper), single).worst, 0.0)
      << threads << " threads";
  }
  EXPECT_TRUE(this->Observer->warnings.empty());
}

TEST_F(MapperRobustness, NegativeThreadCountsAreRejected)
{
  this->MapperUnderTest->SetNumberOfThreads(3);
  this->MapperUnderTest->SetNumberOfThreads(-2);
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfThreads(), 3);
  EXPECT_TRUE(AnyContains(this->Observer->warnings, "thread count"));
  this->MapperUnderTest->SetNumberOfThreads(-1);
  EXPECT_EQ(this->MapperUnderTest->GetNumberOfThreads(), 3);
  EXPECT_EQ(this->Observer->warnings.size(), 2u);
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
  EXPECT_NE(print.str().find("NumberOfThreads: 0 (default: " +
              std::to_string(this->MapperUnderTest->GetEffectiveNumberOfThreads()) + " in use)"),
    std::string::npos)
    << print.str();
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

/// Records the mapper's progress; optionally aborts the render when a value is reached.
class ProgressRecorder : public vtkCommand
{
public:
  static ProgressRecorder* New() { return new ProgressRecorder; }
  void Execute(vtkObject*, unsigned long, void* data) override
  {
    const double value = *static_cast<double*>(data);
    this->values.push_back(value);
    if (this->window && value >= this->abortAt)
    {
      this->window->SetAbortRender(1); // what an application's AbortCheckEvent handler does
    }
  }
  std::vector<double> values;
  vtkRenderWindow* window = nullptr;
  double abortAt = 2;
};

TEST_F(MapperRobustness, ProgressIsReportedThroughTheStagesAndBatches)
{
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    vtkNew<Mapper> mapper;
    mapper->SetBackend(backend);
    mapper->SetBatchSize(700); // 2560 tetrahedra: 4 batches
    mapper->CullInvisibleCellsOff();
    vtkNew<ProgressRecorder> progress;
    mapper->AddObserver(vtkCommand::ProgressEvent, progress);
    const Stage stage = RenderStage(SceneOf(this->Box), mapper, 1);
    const auto image = Grab(stage.window, false);
    mapper->ReleaseGraphicsResources(stage.window);
    ASSERT_EQ(mapper->GetNumberOfBatches(), 4);
    // 0, after the transform, culling, keys and order, after each batch but the last, 1.
    const std::vector<double> expected = { 0.0, 0.1, 0.15, 0.25, 0.35, 0.35 + 0.65 * 700 / 2560.0,
      0.35 + 0.65 * 1400 / 2560.0, 0.35 + 0.65 * 2100 / 2560.0, 1.0 };
    // Before them, VTK's pipeline reports 0 and 1 for the mapper's own Update (first frame).
    ASSERT_GE(progress->values.size(), expected.size());
    const std::size_t first = progress->values.size() - expected.size();
    for (std::size_t i = 0; i < expected.size(); ++i)
    {
      EXPECT_NEAR(progress->values[first + i], expected[i], 1e-12) << "event " << i;
    }
    EXPECT_FALSE(mapper->GetLastFrameStopped());
    // The same image: a frame in batches is the one-batch frame exactly with either backend
    // (OpenGL blends them back to front, the CPU compositor front to back).
    EXPECT_EQ(Compare(image, this->FreshFrame(backend)).worst, 0.0)
      << "observed frames draw the same";
  }
}

TEST_F(MapperRobustness, AnAbortStopsTheFrameAndTheNextFrameIsWhole)
{
  for (const int backend : { Mapper::OPENGL_BACKEND, Mapper::CPU_BACKEND })
  {
    for (const double abortAt : { 0.1, 0.4 }) // after the transform; after the first batch
    {
      vtkNew<Mapper> mapper;
      mapper->SetBackend(backend);
      mapper->SetBatchSize(700);
      mapper->CullInvisibleCellsOff();
      vtkNew<ProgressRecorder> progress;
      mapper->AddObserver(vtkCommand::ProgressEvent, progress);
      const Stage stage = RenderStage(SceneOf(this->Box), mapper, 0);
      progress->window = stage.window;
      progress->abortAt = abortAt;
      stage.window->Render();
      const auto stopped = Grab(stage.window, false);
      EXPECT_TRUE(mapper->GetLastFrameStopped());
      const double covered = CoveredFraction(stopped, Background);
      if (abortAt < 0.35)
      {
        EXPECT_EQ(mapper->GetNumberOfTetrahedra(), 0) << "nothing sorted";
        EXPECT_LT(covered, 0.001) << "nothing drawn";
      }
      else
      {
        EXPECT_EQ(mapper->GetNumberOfBatches(), 1) << "stopped after the first batch";
        EXPECT_GT(covered, 0.01) << "the first batch was drawn";
        EXPECT_GT(Compare(stopped, this->FreshFrame(backend)).worst, 0.05) << "but not the rest";
      }
      // The next frame, not aborted, is whole.
      progress->window = nullptr;
      stage.window->Render();
      EXPECT_FALSE(mapper->GetLastFrameStopped());
      EXPECT_EQ(Compare(Grab(stage.window, false), this->FreshFrame(backend)).worst, 0.0)
        << "backend " << backend << ", abort at " << abortAt;
      mapper->ReleaseGraphicsResources(stage.window);
    }
  }
}

TEST_F(MapperRobustness, AFailedReadBackIsReportedOnceAndDrawnWithOpenGL)
{
  // MTPT_TESTING_FAULT=cpu-read-back makes the CPU backend's read-back fail with a real
  // OpenGL error (GL_INVALID_ENUM): the first frame already must be drawn by the OpenGL
  // backend, exactly as it draws it, and the second too, with one error message for both.
  // (VTK's state cache checks for and clears OpenGL errors when it changes a setting: an
  // error raised before the read-back's own calls would go unseen.)
  // Both windows are read as they are, without the render a grab would add.
  vtkNew<Mapper> reference;
  reference->SetBackendToOpenGL();
  const Stage referenceStage = RenderStage(SceneOf(this->Box), reference);
  const auto expected = Grab(referenceStage.window, false);
  reference->ReleaseGraphicsResources(referenceStage.window);
  this->MapperUnderTest->SetBackendToCPU();
  setenv("MTPT_TESTING_FAULT", "cpu-read-back", 1);
  const Stage stage = RenderStage(SceneOf(this->Box), this->MapperUnderTest);
  ASSERT_EQ(this->Observer->errors.size(), 1u);
  EXPECT_EQ(this->MapperUnderTest->GetLastBackend(), Mapper::OPENGL_BACKEND);
  EXPECT_EQ(Compare(Grab(stage.window, false), expected).worst, 0.0);
  stage.window->Render();
  const auto image = Grab(stage.window, false);
  unsetenv("MTPT_TESTING_FAULT");
  this->MapperUnderTest->ReleaseGraphicsResources(stage.window);
  ASSERT_EQ(this->Observer->errors.size(), 1u);
  EXPECT_TRUE(AnyContains(this->Observer->errors,
    "the CPU backend failed: reading the window's colour and depth back failed "
    "(GL_INVALID_ENUM); drawing with OpenGL instead"))
    << this->Observer->errors[0];
  EXPECT_EQ(this->MapperUnderTest->GetLastBackend(), Mapper::OPENGL_BACKEND);
  EXPECT_EQ(Compare(image, expected).worst, 0.0);
  this->Observer->Clear();
  this->ExpectRecovers(); // and the CPU backend works again once OpenGL does
  EXPECT_EQ(this->MapperUnderTest->GetLastBackend(), Mapper::CPU_BACKEND);
  EXPECT_TRUE(this->Observer->errors.empty());
}

TEST_F(MapperRobustness, AVectorComponentOutOfRangeIsWarnedAbout)
{
  // A three-component point array coloured by its component 5: one warning, drawn with the
  // last component (2), as with component 2 asked for.
  vtkNew<vtkUnstructuredGrid> grid;
  grid->ShallowCopy(this->Box);
  vtkNew<vtkFloatArray> vectors;
  vectors->SetName("vectors");
  vectors->SetNumberOfComponents(3);
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i)
  {
    const double* p = grid->GetPoint(i);
    vectors->InsertNextTuple3(p[0], p[1], 0.5 * (p[2] + 1.0));
  }
  grid->GetPointData()->SetScalars(vectors);
  auto componentProperty = [&](int component)
  {
    auto property = MakeProperty(0.0, 1.0, 0.5);
    property->GetRGBTransferFunction()->SetVectorModeToComponent();
    property->GetRGBTransferFunction()->SetVectorComponent(component);
    return property;
  };
  Scene scene = SceneOf(grid);
  scene.property = componentProperty(5);
  const auto image = Render(scene, this->MapperUnderTest, 2);
  ASSERT_EQ(this->Observer->warnings.size(), 1u) << "once, not per frame";
  EXPECT_TRUE(AnyContains(this->Observer->warnings,
    "the colour transfer function selects component 5 of the array 'vectors', which has "
    "components 0 to 2; using component 2"))
    << this->Observer->warnings[0];
  vtkNew<Mapper> fresh;
  scene.property = componentProperty(2);
  EXPECT_EQ(Compare(image, Render(scene, fresh)).worst, 0.0);
  EXPECT_GT(CoveredFraction(image, Background), 0.1);
}

TEST_F(MapperRobustness, ANonPositiveUnitDistanceIsWarnedAbout)
{
  auto property = MakeProperty(-0.3, 1.3, 0.0);
  Scene scene = SceneOf(this->Box);
  scene.property = property;
  const auto image = Render(scene, this->MapperUnderTest, 2);
  ASSERT_EQ(this->Observer->warnings.size(), 1u) << "once, not per frame";
  EXPECT_TRUE(AnyContains(this->Observer->warnings,
    "the volume property's ScalarOpacityUnitDistance is 0; it must be positive, using 1"));
  scene.property = MakeProperty(-0.3, 1.3, 1.0);
  vtkNew<Mapper> fresh;
  EXPECT_EQ(Compare(image, Render(scene, fresh)).worst, 0.0) << "drawn with 1";
  property->SetScalarOpacityUnitDistance(-2.0);
  Render(SceneOf(this->Box), this->MapperUnderTest);
  EXPECT_EQ(this->Observer->warnings.size(), 1u) << "the fixture's property is fine";
  scene.property = property;
  Render(scene, this->MapperUnderTest);
  EXPECT_EQ(this->Observer->warnings.size(), 2u) << "a changed value is reported again";
}

TEST_F(MapperRobustness, TheDefaultThreadCountIsTheLibrarys)
{
  vtkNew<Mapper> mapper;
  EXPECT_EQ(mapper->GetEffectiveNumberOfThreads(), mtpt::DefaultThreadCount());
  mapper->SetNumberOfThreads(3);
  EXPECT_EQ(mapper->GetEffectiveNumberOfThreads(), 3);
}

} // namespace
