// SPDX-License-Identifier: BSD-3-Clause
// Level of detail for moving frames, on both backends, in windows as VTK makes them:
// - on a simulated clock (no test reads a clock), every frame takes the detail the budget
//   rule (mtpt::ChooseDetail, mtpt::VolumeBudget) gives for the last frame's simulated
//   costs, moving frames converge to the time the window allots while the camera turns,
//   the window's own work included, and the still frame after them is the image of a
//   fresh mapper, pixel for pixel;
// - a fixed fraction draws that fraction of the visible cells, with the opacity of the
//   cells left out compensated: the image stays within a stated bound of the full frame and
//   its mean brightness within a smaller one (without compensation it is far brighter);
//   the two backends draw the same subset and agree as closely as on full frames;
// - the defaults and the ranges of the settings.
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "mtpt/LevelOfDetail.h"

#include "vtkCamera.h"
#include "vtkImageData.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// A mapper whose frames take a simulated time, whatever the machine: `fixed` seconds of
/// work that follows the viewport alone, plus
/// per-cell stages of `cells` seconds at every cell, plus `samples` seconds at every cell
/// and every pixel of the window, both scaled by the fraction of cells drawn and the
/// latter by the pixels composited; the window's own work adds `window` seconds to each
/// frame, which the mapper sees only in the interval between frames.
class SimulatedMapper : public vtkMultiThreadedProjectedTetrahedraMapper
{
public:
  static SimulatedMapper* New();
  vtkTypeMacro(SimulatedMapper, vtkMultiThreadedProjectedTetrahedraMapper);
  double fixed = 0.004, cells = 0.1, samples = 0.5, window = 0.01;
  int windowPixels = 1;

  mtpt::Detail LastDetail() const { return this->Last; }
  double Seconds(const mtpt::Detail& d, const int size[2]) const
  {
    return this->fixed +
      d.cellFraction * (this->cells + this->samples * size[0] * size[1] / this->windowPixels);
  }
  double CellSeconds(const mtpt::Detail& d) const { return d.cellFraction * this->cells; }

  /// What the last frame drew (call after each Render).
  void Drawn()
  {
    this->Last = { mtpt::CellFractionLevel(this->GetCellFraction(), 0.0),
      this->GetImageSampleDistance() };
    const int* size = this->GetImageInUseSize();
    this->LastSize[0] = size[0];
    this->LastSize[1] = size[1];
    this->Timed = true;
  }
  double LastSeconds() const { return this->Timed ? this->Seconds(this->Last, this->LastSize) : 0; }

protected:
  SimulatedMapper() = default;
  ~SimulatedMapper() override = default;
  double RetrieveRenderTime(vtkRenderer*, vtkVolume*) override { return this->LastSeconds(); }
  void RetrieveFrameCosts(
    double& cellSeconds, double& sampleSeconds, double& viewportSeconds) override
  {
    cellSeconds = this->Timed ? this->CellSeconds(this->Last) : 0;
    sampleSeconds = this->Timed ? this->LastSeconds() - this->fixed - cellSeconds : -1;
    viewportSeconds = this->Timed ? this->fixed : 0;
  }
  double RetrieveFrameInterval() override
  {
    return this->Timed ? this->LastSeconds() + this->window : 0;
  }

private:
  SimulatedMapper(const SimulatedMapper&) = delete;
  void operator=(const SimulatedMapper&) = delete;
  mtpt::Detail Last;
  int LastSize[2] = { 0, 0 };
  bool Timed = false;
};
vtkStandardNewMacro(SimulatedMapper);

class MapperLevelOfDetail : public ::testing::Test
{
protected:
  static void SetUpTestSuite() { BluntFin = ShuffleCells(LoadBluntFin(), 9); }
  static void TearDownTestSuite() { BluntFin = nullptr; }
  static vtkSmartPointer<vtkUnstructuredGrid> BluntFin;

  static Stage FinStage(Mapper* mapper, int width, int height)
  {
    Stage stage = MakeStage(BluntFin, MakeBluntFinProperty(), mapper, width, height);
    SetView(stage.renderer, Views[2], true);
    return stage;
  }

  /// The window's image drawn by a fresh mapper (full frame) on `backend`.
  static vtkSmartPointer<vtkImageData> FreshImage(const Stage& stage, Mapper* under, int backend)
  {
    return FreshMapperImage(stage, under, [backend](Mapper* fresh) { fresh->SetBackend(backend); });
  }
};
vtkSmartPointer<vtkUnstructuredGrid> MapperLevelOfDetail::BluntFin;

TEST_F(MapperLevelOfDetail, DefaultsAndRanges)
{
  vtkNew<Mapper> mapper;
  EXPECT_EQ(mapper->GetCellFraction(), 1.0f);
  EXPECT_EQ(mapper->GetMinimumCellFraction(), 0.05f);
  EXPECT_EQ(mapper->GetAutoAdjustCellFraction(), 1);
  mapper->SetCellFraction(0.0f);
  EXPECT_EQ(mapper->GetCellFraction(), 0.001f);
  mapper->SetCellFraction(3.0f);
  EXPECT_EQ(mapper->GetCellFraction(), 1.0f);
  mapper->SetMinimumCellFraction(-1.0f);
  EXPECT_EQ(mapper->GetMinimumCellFraction(), 0.001f);
}

TEST_F(MapperLevelOfDetail, MovingFramesKeepTheBudgetAndTheStillFrameIsFresh)
{
  for (const int backend : Backends)
  {
    for (const double rate : { 10.0, 25.0 })
    {
      const std::string label = std::string(BackendName(backend)) + " at " +
        std::to_string(static_cast<int>(rate)) + " frames a second";
      vtkNew<SimulatedMapper> mapper;
      mapper->SetBackend(backend);
      mapper->windowPixels = 400 * 300;
      Stage stage = FinStage(mapper, 400, 300);
      stage.window->Render(); // a still frame first, as an application shows its first
      mapper->Drawn();
      EXPECT_EQ(mapper->GetNumberOfCellsLeftOut(), 0) << label;
      const vtkIdType all = mapper->GetNumberOfTetrahedra();
      stage.window->SetDesiredUpdateRate(rate); // the user drags
      mtpt::DetailLimits limits;
      for (int frame = 0; frame < 10; ++frame)
      {
        const mtpt::Detail last = mapper->LastDetail();
        const bool timed = mapper->LastSeconds() > 0;
        const double cells = timed ? mapper->CellSeconds(last) : 0;
        const mtpt::MeasuredFrame measured{ last, mapper->LastSeconds(), cells,
          timed ? mapper->LastSeconds() - mapper->fixed - cells : -1, timed ? mapper->fixed : 0 };
        const double interval = measured.seconds + mapper->window;
        stage.renderer->GetActiveCamera()->Azimuth(7);
        stage.window->Render();
        mapper->Drawn();
        const double allotted = stage.volume->GetAllocatedRenderTime();
        ASSERT_NEAR(allotted, 1.0 / rate, 1e-9) << label;
        const mtpt::Detail expected = mtpt::ChooseDetail(measured,
          mtpt::VolumeBudget(allotted, interval, measured.seconds), limits, last);
        EXPECT_EQ(mapper->GetCellFraction(), static_cast<float>(expected.cellFraction))
          << label << ", frame " << frame;
        EXPECT_EQ(mapper->GetImageSampleDistance(), static_cast<float>(expected.sampleDistance))
          << label << ", frame " << frame;
        if (frame >= 3) // the whole frame, the window's work included
        {
          const double seconds = mapper->LastSeconds() + mapper->window;
          EXPECT_LE(seconds, 1.1 * allotted) << label << ", frame " << frame;
          EXPECT_GE(seconds, 0.75 * allotted) << label << ", frame " << frame;
        }
      }
      EXPECT_LT(mapper->GetCellFraction(), 1.0f) << label;
      EXPECT_GT(mapper->GetNumberOfCellsLeftOut(), 0) << label;
      EXPECT_LT(mapper->GetNumberOfTetrahedra(), all) << label;

      // The user lets go: VTK's still rate, and a fresh mapper's image.
      stage.window->SetDesiredUpdateRate(0.0001);
      stage.window->Render();
      EXPECT_EQ(mapper->GetCellFraction(), 1.0f) << label;
      EXPECT_EQ(mapper->GetImageSampleDistance(), 1.0f) << label;
      EXPECT_EQ(mapper->GetNumberOfCellsLeftOut(), 0) << label;
      const auto still = Grab(stage.window, false);
      EXPECT_EQ(Compare(still, FreshImage(stage, mapper, backend)).worst, 0.0) << label;
      mapper->ReleaseGraphicsResources(stage.window);
    }
  }
}

TEST_F(MapperLevelOfDetail, VolumesDrawnTogetherShareTheirTime)
{
  // Two volumes of one renderer drawn together: the first volume's mapper draws both in the
  // time the renderer allots the two, not in its own share of it.
  vtkNew<SimulatedMapper> mapper;
  mapper->SetBackend(Mapper::CPU_BACKEND);
  mapper->windowPixels = 400 * 300;
  Stage stage = FinStage(mapper, 400, 300);
  vtkNew<Mapper> other;
  other->SetInputData(BluntFin);
  vtkNew<vtkVolume> second;
  second->SetMapper(other);
  auto property = MakeBluntFinProperty(); // another property object: still drawn together
  second->SetProperty(property);
  stage.renderer->AddVolume(second);
  stage.window->Render();
  mapper->Drawn();
  EXPECT_EQ(other->GetNumberOfTetrahedra(), 0);
  stage.window->SetDesiredUpdateRate(10);
  mtpt::DetailLimits limits;
  for (int frame = 0; frame < 4; ++frame)
  {
    const mtpt::Detail last = mapper->LastDetail();
    const double cells = mapper->CellSeconds(last);
    const mtpt::MeasuredFrame measured{ last, mapper->LastSeconds(), cells,
      mapper->LastSeconds() - mapper->fixed - cells, mapper->fixed };
    stage.renderer->GetActiveCamera()->Azimuth(7);
    stage.window->Render();
    mapper->Drawn();
    const double own = stage.volume->GetAllocatedRenderTime();
    const double both = own + second->GetAllocatedRenderTime();
    ASSERT_NEAR(both, 0.1, 1e-9);
    ASSERT_LT(own, both);
    const mtpt::Detail expected = mtpt::ChooseDetail(measured,
      mtpt::VolumeBudget(both, measured.seconds + mapper->window, measured.seconds), limits, last);
    EXPECT_EQ(mapper->GetCellFraction(), static_cast<float>(expected.cellFraction))
      << "frame " << frame;
    EXPECT_EQ(mapper->GetImageSampleDistance(), static_cast<float>(expected.sampleDistance))
      << "frame " << frame;
    EXPECT_EQ(other->GetNumberOfTetrahedra(), 0);
  }
  other->ReleaseGraphicsResources(stage.window);
  mapper->ReleaseGraphicsResources(stage.window);
}

/// Mean of the RGB channels over the pixels that differ from the background in `full`.
double CoveredMean(vtkImageData* image, vtkImageData* full)
{
  auto* a = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  auto* f = vtkUnsignedCharArray::SafeDownCast(full->GetPointData()->GetScalars());
  const vtkIdType n = a->GetNumberOfTuples();
  double background[3];
  for (int c = 0; c < 3; ++c)
  {
    background[c] = f->GetValue(c); // the corner pixel: the background
  }
  double sum = 0;
  vtkIdType count = 0;
  for (vtkIdType i = 0; i < n; ++i)
  {
    bool covered = false;
    for (int c = 0; c < 3; ++c)
    {
      covered = covered || std::abs(f->GetValue(3 * i + c) - background[c]) > 2;
    }
    if (covered)
    {
      sum += a->GetValue(3 * i) + a->GetValue(3 * i + 1) + a->GetValue(3 * i + 2);
      count += 3;
    }
  }
  return count > 0 ? sum / count / 255.0 : 0.0;
}

TEST_F(MapperLevelOfDetail, AFixedFractionKeepsTheLookOfTheVolume)
{
  vtkSmartPointer<vtkImageData> images[2];
  for (const int backend : Backends)
  {
    const std::string label = BackendName(backend);
    vtkNew<Mapper> mapper;
    mapper->SetBackend(backend);
    mapper->AutoAdjustCellFractionOff();
    Stage stage = FinStage(mapper, 400, 300);
    stage.window->Render();
    const auto full = Grab(stage.window, false);
    const vtkIdType all = mapper->GetNumberOfTetrahedra();
    mapper->SetCellFraction(0.25f);
    stage.window->Render();
    const auto quarter = Grab(stage.window, false);
    // A quarter of the visible cells (evenly spread: the count is within 1% of it).
    const vtkIdType visible = mapper->GetNumberOfTetrahedra() + mapper->GetNumberOfCellsLeftOut() +
      mapper->GetNumberOfPixelCulledCells() + mapper->GetNumberOfFrustumCulledCells();
    const vtkIdType drawn = visible - mapper->GetNumberOfCellsLeftOut();
    EXPECT_NEAR(static_cast<double>(drawn), 0.25 * visible, 0.01 * visible) << label;
    EXPECT_LT(mapper->GetNumberOfTetrahedra(), all / 3) << label;
    const ImageDifference d = Compare(quarter, full);
    EXPECT_GT(d.worst, 0.0) << label << ": the subset is drawn";
    EXPECT_LT(d.coveredRmse, 18.0 / 255) << label;
    // Compensated: the covered mean (brightness and opacity together) stays. Without the
    // compensation it is 43/255 off, and the covered RMSE is 47/255.
    EXPECT_NEAR(CoveredMean(quarter, full), CoveredMean(full, full), 4.0 / 255) << label;
    images[backend == Mapper::CPU_BACKEND ? 0 : 1] = quarter;
    mapper->ReleaseGraphicsResources(stage.window);
  }
  // The same subset and compensation on both backends.
  EXPECT_LT(Compare(images[0], images[1]).coveredRmse, 2.0 / 255);
}

} // namespace
