// SPDX-License-Identifier: BSD-3-Clause
// Soak: 1000 frames of one mapper in one window, the camera rotating, the backend switching
// between OpenGL and the CPU compositor every frame, and the transfer functions, the
// shading mode and the perspective changing now and then. Resident memory after the last
// frame must stay within a small bound of its value after a warm-up: no leak per frame,
// per backend switch or per transfer-function change (buffers grow to their largest size
// and are reused, FramePipeline.h).
#include "RenderingTestUtilities.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

constexpr int Frames = 1000;
constexpr int WarmUpFrames = 100;
constexpr double AllowedGrowthMiB = 4.0;

/// Resident set size of this process in MiB (/proc/self/statm, second field: pages).
double ResidentMiB()
{
  std::ifstream statm("/proc/self/statm");
  long total = 0, resident = 0;
  statm >> total >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
    (1024.0 * 1024.0);
}

/// A new transfer function for frame `f`: the colour ramp and the opacity peak move.
void ChangeTransferFunction(vtkVolumeProperty* property, int f, double low, double high)
{
  const double t = (f % 7) / 7.0;
  const double mid = low + (0.2 + 0.6 * t) * (high - low);
  vtkColorTransferFunction* color = property->GetRGBTransferFunction();
  color->RemoveAllPoints();
  color->AddRGBPoint(low, 0.1 + 0.5 * t, 0.3, 0.9 - 0.5 * t);
  color->AddRGBPoint(mid, 0.95, 0.9, 0.5);
  color->AddRGBPoint(high, 0.9, 0.2 + 0.4 * t, 0.1);
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity();
  opacity->RemoveAllPoints();
  opacity->AddPoint(low, f % 3 == 0 ? 0.0 : 0.05); // sometimes cells are opacity-culled
  opacity->AddPoint(mid, 0.8);
  opacity->AddPoint(high, 0.3 * t);
}

TEST(MapperSoak, ResidentMemoryStaysFlatOverAThousandFrames)
{
  auto grid = MakeTetrahedralBox(5); // 625 tetrahedra
  double range[2];
  grid->GetPointData()->GetScalars()->GetRange(range);
  auto property = MakeProperty(range[0], range[1], 0.5);

  vtkNew<Mapper> mapper;
  const Stage stage = MakeStage(grid, property, mapper, 64, 64);
  vtkRenderer* renderer = stage.renderer;
  vtkRenderWindow* window = stage.window;
  renderer->ResetCamera();
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->Elevation(20);
  camera->OrthogonalizeViewUp();

  double warmedUp = 0, peak = 0;
  int backendUsed[3] = { 0, 0, 0 };
  const auto start = std::chrono::steady_clock::now();
  auto measured = start;
  for (int f = 1; f <= Frames; ++f)
  {
    mapper->SetBackend(f % 2 ? Mapper::OPENGL_BACKEND : Mapper::CPU_BACKEND);
    if (f % 50 == 0)
    {
      ChangeTransferFunction(property, f, range[0], range[1]);
    }
    if (f % 200 == 0)
    {
      mapper->SetShadingMode(mapper->GetShadingMode() == Mapper::VTK_COMPATIBLE_SHADING
          ? Mapper::PRE_INTEGRATED_SHADING
          : Mapper::VTK_COMPATIBLE_SHADING);
    }
    if (f % 250 == 0)
    {
      camera->SetParallelProjection(!camera->GetParallelProjection());
    }
    camera->Azimuth(360.0 / 250.0); // a full turn every 250 frames
    renderer->ResetCameraClippingRange();
    window->Render();
    const int last = mapper->GetLastBackend();
    if (last >= 0 && last < 3)
    {
      ++backendUsed[last];
    }
    const double rss = ResidentMiB();
    peak = std::max(peak, rss);
    if (f == WarmUpFrames)
    {
      warmedUp = rss;
      peak = rss;
      measured = std::chrono::steady_clock::now();
    }
  }
  const auto end = std::chrono::steady_clock::now();
  const double settled = ResidentMiB();

  // The last frame drew something (the scene did not silently vanish).
  window->Render();
  auto image = Grab(window, false);
  const double covered = CoveredFraction(image, Background);
  mapper->ReleaseGraphicsResources(window);

  const double seconds = std::chrono::duration<double>(end - measured).count();
  std::printf("soak: %d frames at 64x64 (%lld tetrahedra), OpenGL %d, CPU %d; resident memory "
              "after frame %d: %.2f MiB, after frame %d: %.2f MiB (growth %+.2f MiB, peak "
              "%.2f MiB, bound %.1f MiB); frames %d-%d took %.2f s (%.2f ms per frame); "
              "mapper buffers %lld bytes; last frame covers %.0f%% of the window\n",
    Frames, static_cast<long long>(grid->GetNumberOfCells()), backendUsed[Mapper::OPENGL_BACKEND],
    backendUsed[Mapper::CPU_BACKEND], WarmUpFrames, warmedUp, Frames, settled, settled - warmedUp,
    peak, AllowedGrowthMiB, WarmUpFrames + 1, Frames, seconds,
    1000.0 * seconds / (Frames - WarmUpFrames), static_cast<long long>(mapper->GetMemoryBytes()),
    100.0 * covered);
  EXPECT_EQ(backendUsed[Mapper::OPENGL_BACKEND], Frames / 2);
  EXPECT_EQ(backendUsed[Mapper::CPU_BACKEND], Frames / 2);
  EXPECT_GT(covered, 0.05);
  EXPECT_LE(settled - warmedUp, AllowedGrowthMiB)
    << "resident memory grew from " << warmedUp << " MiB to " << settled << " MiB";
}

} // namespace
