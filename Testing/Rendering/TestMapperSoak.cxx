// SPDX-License-Identifier: BSD-3-Clause
// Soak: 1000 frames of one mapper in one window, the camera rotating, the backend switching
// between OpenGL and the CPU compositor every frame, and the transfer functions, the
// shading mode and the perspective changing now and then. The schedule repeats every 250
// frames, so after the first 250 every state has been seen once and every cache holds its
// largest buffers (FramePipeline.h); the three repeats after it must not grow the heap.
//
// What is measured is the heap in use, not resident memory. Resident memory follows the
// allocator's fragmentation: under a competing load the threads of OpenMP and llvmpipe
// interleave their allocations differently, glibc's main arena keeps more free space that
// it cannot return, and resident memory grew by up to 5.4 MiB over 900 frames while the
// bytes in use stayed within 1 KiB of their start (Documentation/testing.md, "The soak
// test"). The bytes in use are counted twice: every C++ allocation of the process (this
// program replaces the global operator new and delete, which VTK, the mapper and the core
// all call), counted exactly and independently of timing; and everything malloc hands out
// (glibc's mallinfo2, which also sees OpenGL's driver), with a looser bound.
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

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <new>

// --- Every C++ allocation of the process, counted in usable bytes ----------------------
namespace
{
std::atomic<long long> LiveCxxBytes{ 0 };

void* Allocate(std::size_t size, std::size_t alignment)
{
  void* p = nullptr;
  if (alignment <= alignof(std::max_align_t))
  {
    p = std::malloc(size ? size : 1);
  }
  else if (posix_memalign(&p, alignment, size ? size : 1) != 0)
  {
    p = nullptr;
  }
  if (p)
  {
    LiveCxxBytes.fetch_add(static_cast<long long>(malloc_usable_size(p)), std::memory_order_relaxed);
  }
  return p;
}

void Release(void* p) noexcept
{
  if (p)
  {
    LiveCxxBytes.fetch_sub(static_cast<long long>(malloc_usable_size(p)), std::memory_order_relaxed);
    std::free(p);
  }
}

void* AllocateOrThrow(std::size_t size, std::size_t alignment)
{
  if (void* p = Allocate(size, alignment))
  {
    return p;
  }
  throw std::bad_alloc();
}
} // namespace

void* operator new(std::size_t n)
{
  return AllocateOrThrow(n, 0);
}
void* operator new[](std::size_t n)
{
  return AllocateOrThrow(n, 0);
}
void* operator new(std::size_t n, std::align_val_t a)
{
  return AllocateOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a)
{
  return AllocateOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept
{
  return Allocate(n, 0);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept
{
  return Allocate(n, 0);
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
  return Allocate(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
  return Allocate(n, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept
{
  Release(p);
}
void operator delete[](void* p) noexcept
{
  Release(p);
}
void operator delete(void* p, std::size_t) noexcept
{
  Release(p);
}
void operator delete[](void* p, std::size_t) noexcept
{
  Release(p);
}
void operator delete(void* p, std::align_val_t) noexcept
{
  Release(p);
}
void operator delete[](void* p, std::align_val_t) noexcept
{
  Release(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept
{
  Release(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept
{
  Release(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept
{
  Release(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept
{
  Release(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept
{
  Release(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept
{
  Release(p);
}

namespace
{
using namespace mtpt::rendering_test;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

constexpr int Frames = 1000;
constexpr int Period = 250;         // the schedule repeats every Period frames
constexpr int WarmUpFrames = Period; // every state seen once
/// C++ bytes in use may differ by this much after three repeats of the schedule. Measured:
/// 0, loaded or not; a leak of 8 bytes a frame in the mapper gives +19 KiB.
constexpr long long AllowedCxxGrowth = 4096;
/// Bytes malloc has handed out (the driver's included), measured once OpenGL has finished
/// the frame: within 150 bytes, loaded or not; a leak of 96 bytes a frame gives +82 KiB.
constexpr long long AllowedMallocGrowth = 64 * 1024;

struct Memory
{
  long long cxx = 0;     ///< C++ bytes in use (operator new minus operator delete)
  long long malloced = 0; ///< bytes malloc has handed out, mmapped blocks included
  long long arena = 0;   ///< bytes malloc holds from the system (in use or free)
  double residentMiB = 0;
};

Memory Measure()
{
  Memory m;
  m.cxx = LiveCxxBytes.load();
  const struct mallinfo2 info = mallinfo2();
  m.malloced = static_cast<long long>(info.uordblks + info.hblkhd);
  m.arena = static_cast<long long>(info.arena + info.hblkhd);
  std::ifstream statm("/proc/self/statm");
  long total = 0, resident = 0;
  statm >> total >> resident;
  m.residentMiB = static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
    (1024.0 * 1024.0);
  return m;
}

/// The transfer functions of variant `v` (0-4): the colour ramp and the opacity peak move.
void SetTransferFunction(vtkVolumeProperty* property, int v, double low, double high)
{
  const double t = v / 5.0;
  const double mid = low + (0.2 + 0.6 * t) * (high - low);
  vtkColorTransferFunction* color = property->GetRGBTransferFunction();
  color->RemoveAllPoints();
  color->AddRGBPoint(low, 0.1 + 0.5 * t, 0.3, 0.9 - 0.5 * t);
  color->AddRGBPoint(mid, 0.95, 0.9, 0.5);
  color->AddRGBPoint(high, 0.9, 0.2 + 0.4 * t, 0.1);
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity();
  opacity->RemoveAllPoints();
  opacity->AddPoint(low, v % 2 == 0 ? 0.0 : 0.05); // sometimes cells are opacity-culled
  opacity->AddPoint(mid, 0.8);
  opacity->AddPoint(high, 0.3 * t);
}

TEST(MapperSoak, HeapInUseStaysFlatOverAThousandFrames)
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

  Memory warmedUp, peak;
  int backendUsed[3] = { 0, 0, 0 };
  auto measured = std::chrono::steady_clock::now();
  for (int f = 1; f <= Frames; ++f)
  {
    // Each change below happens at the same place in every period of the schedule.
    const int phase = f % Period;
    mapper->SetBackend(f % 2 ? Mapper::OPENGL_BACKEND : Mapper::CPU_BACKEND);
    if (phase % 50 == 0)
    {
      SetTransferFunction(property, phase / 50, range[0], range[1]);
    }
    if (phase == 0 || phase == 125)
    {
      mapper->SetShadingMode(mapper->GetShadingMode() == Mapper::VTK_COMPATIBLE_SHADING
          ? Mapper::PRE_INTEGRATED_SHADING
          : Mapper::VTK_COMPATIBLE_SHADING);
    }
    if (phase == 60 || phase == 190)
    {
      camera->SetParallelProjection(!camera->GetParallelProjection());
    }
    camera->Azimuth(360.0 / Period); // a full turn every period
    renderer->ResetCameraClippingRange();
    window->Render();
    window->WaitForCompletion(); // OpenGL's driver has freed what the frame needed
    const int last = mapper->GetLastBackend();
    if (last >= 0 && last < 3)
    {
      ++backendUsed[last];
    }
    const Memory now = Measure();
    if (f == WarmUpFrames)
    {
      warmedUp = peak = now;
      measured = std::chrono::steady_clock::now();
    }
    peak.residentMiB = std::max(peak.residentMiB, now.residentMiB);
  }
  const auto end = std::chrono::steady_clock::now();
  const Memory settled = Measure();

  // The last frame drew something (the scene did not silently vanish).
  window->Render();
  auto image = Grab(window, false);
  const double covered = CoveredFraction(image, Background);
  mapper->ReleaseGraphicsResources(window);

  const double seconds = std::chrono::duration<double>(end - measured).count();
  std::printf("soak: %d frames at 64x64 (%lld tetrahedra), OpenGL %d, CPU %d; from frame %d "
              "to %d: C++ heap in use %+lld bytes (bound %lld), malloc in use %+lld bytes "
              "(bound %lld), malloc's arenas %+.2f MiB, resident memory %.2f -> %.2f MiB "
              "(peak %.2f MiB, not asserted); %.2f ms per frame; mapper buffers %lld bytes; "
              "last frame covers %.0f%% of the window\n",
    Frames, static_cast<long long>(grid->GetNumberOfCells()), backendUsed[Mapper::OPENGL_BACKEND],
    backendUsed[Mapper::CPU_BACKEND], WarmUpFrames, Frames, settled.cxx - warmedUp.cxx,
    AllowedCxxGrowth, settled.malloced - warmedUp.malloced, AllowedMallocGrowth,
    static_cast<double>(settled.arena - warmedUp.arena) / (1024.0 * 1024.0),
    warmedUp.residentMiB, settled.residentMiB, peak.residentMiB,
    1000.0 * seconds / (Frames - WarmUpFrames), static_cast<long long>(mapper->GetMemoryBytes()),
    100.0 * covered);
  EXPECT_EQ(backendUsed[Mapper::OPENGL_BACKEND], Frames / 2);
  EXPECT_EQ(backendUsed[Mapper::CPU_BACKEND], Frames / 2);
  EXPECT_GT(covered, 0.05);
  EXPECT_LE(settled.cxx - warmedUp.cxx, AllowedCxxGrowth)
    << "C++ heap in use grew from " << warmedUp.cxx << " to " << settled.cxx << " bytes";
  EXPECT_LE(settled.malloced - warmedUp.malloced, AllowedMallocGrowth)
    << "malloc's bytes in use grew from " << warmedUp.malloced << " to " << settled.malloced;
}

} // namespace
