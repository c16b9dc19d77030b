// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_frames: whole frames of vtkMultiThreadedProjectedTetrahedraMapper (CPU
// compositor and OpenGL backends) against VTK's projected tetrahedra, ray-cast and Z-sweep
// unstructured mappers, on the same scenes, measured in one run, with every time printed
// beside the image's difference from VTK's PT. Run under a display (xvfb-run on machines
// without one: there OpenGL is Mesa llvmpipe and its rasterization is CPU work too).
#include "MeshLoader.h"
#include "TetrahedralGrid.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridVolumeRayCastMapper.h"
#include "vtkUnstructuredGridVolumeZSweepMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace
{
using mtpt::bench::TetMesh;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  std::vector<int> sizes{ 16, 512, 1024 };
  std::size_t tets = 1200000;
  std::string data = MTPT_SHARED_DATA_DIR;
  std::vector<std::string> meshes; // empty: all
  int repeat = 3;
  double slowLimit = 30;
  bool quick = false;
};

std::vector<std::string> Split(const std::string& s)
{
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
  {
    out.push_back(item);
  }
  return out;
}

struct Result
{
  double ms = 0;
  bool slow = false; ///< one frame only: it took longer than the slow limit
  vtkSmartPointer<vtkImageData> image;
  double stages[8] = {}; // transform, keys, order, decompose, composite, upload, draw, cpu
};

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

Result Measure(vtkUnstructuredGrid* grid, vtkUnstructuredGridVolumeMapper* mapper, int size,
  const double range[2], const Options& o)
{
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(range[0], 0.23, 0.30, 0.75);
  color->AddRGBPoint(0.5 * (range[0] + range[1]), 0.87, 0.87, 0.87);
  color->AddRGBPoint(range[1], 0.71, 0.02, 0.15);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(range[0], 0.0);
  opacity->AddPoint(range[1], 1.0);
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(grid->GetLength() / 50);
  mapper->SetInputData(grid);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1, 1, 1);
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->SetSize(size, size);
  window->AddRenderer(renderer);
  renderer->ResetCamera();
  renderer->GetActiveCamera()->Azimuth(30);
  renderer->GetActiveCamera()->Elevation(20);
  renderer->GetActiveCamera()->OrthogonalizeViewUp();
  renderer->ResetCameraClippingRange();
  auto frame = [&]
  {
    const auto start = std::chrono::steady_clock::now();
    window->Render();
    window->WaitForCompletion();
    return 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  Result r;
  const double first = frame(); // warm-up: input analysis, shaders, buffers
  std::vector<double> times;
  std::vector<std::vector<double>> stages(8);
  if (first > 1e3 * o.slowLimit)
  {
    r.slow = true;
    times.push_back(first);
  }
  else
  {
    for (int i = 0; i < o.repeat; ++i)
    {
      times.push_back(frame());
      if (auto* m = Mapper::SafeDownCast(mapper))
      {
        const double s[8] = { m->GetTransformSeconds(), m->GetDepthKeySeconds(),
          m->GetOrderSeconds(), m->GetDecomposeSeconds(), m->GetCompositeSeconds(),
          m->GetUploadSeconds(), m->GetDrawSeconds(), m->GetCPUStageSeconds() };
        for (int k = 0; k < 8; ++k)
        {
          stages[k].push_back(1e3 * s[k]);
        }
      }
    }
  }
  r.ms = Median(times);
  for (int k = 0; k < 8; ++k)
  {
    r.stages[k] = stages[k].empty() ? 0 : Median(stages[k]);
  }
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  r.image = vtkSmartPointer<vtkImageData>::New();
  r.image->DeepCopy(grab->GetOutput());
  mapper->ReleaseGraphicsResources(window);
  return r;
}

double Rmse(vtkImageData* a, vtkImageData* b)
{
  auto* pa = vtkUnsignedCharArray::SafeDownCast(a->GetPointData()->GetScalars());
  auto* pb = vtkUnsignedCharArray::SafeDownCast(b->GetPointData()->GetScalars());
  double sum = 0;
  for (vtkIdType i = 0; i < pa->GetNumberOfValues(); ++i)
  {
    const double d = (pa->GetValue(i) - pb->GetValue(i)) / 255.0;
    sum += d * d;
  }
  return std::sqrt(sum / pa->GetNumberOfValues());
}

std::string Ms(const Result& r)
{
  char text[64];
  std::snprintf(text, sizeof(text), r.slow ? "%.0f*" : "%.1f", r.ms);
  return text;
}

} // namespace

int main(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--sizes")
    {
      o.sizes.clear();
      for (const auto& s : Split(next()))
      {
        o.sizes.push_back(std::atoi(s.c_str()));
      }
    }
    else if (a == "--tets")
      o.tets = std::strtoull(next().c_str(), nullptr, 10);
    else if (a == "--data")
      o.data = next();
    else if (a == "--meshes")
      o.meshes = Split(next());
    else if (a == "--repeat")
      o.repeat = std::max(1, std::atoi(next().c_str()));
    else if (a == "--slow-limit")
      o.slowLimit = std::atof(next().c_str());
    else if (a == "--quick")
      o.quick = true;
    else
    {
      std::printf("usage: mtpt_bench_frames [--sizes 16,512,1024] [--tets N] [--data DIR]\n"
                  "  [--meshes grid,bluntfin,...] [--repeat R] [--slow-limit S] [--quick]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (o.quick)
  {
    o.tets = 200000;
    o.meshes = { "grid", "bluntfin" };
    o.sizes = { 16, 512 };
  }
  auto wanted = [&](const std::string& name) {
    return o.meshes.empty() || std::find(o.meshes.begin(), o.meshes.end(), name) != o.meshes.end();
  };

  std::vector<TetMesh> meshes;
  if (wanted("grid"))
  {
    mtpt::bench::GridOptions grid;
    grid.cells = mtpt::bench::GridCellsForTetrahedra(o.tets, mtpt::bench::HexSplit::Five);
    grid.jitter = 0.2;
    meshes.push_back(mtpt::bench::GenerateTetrahedralGrid(grid));
    meshes.back().name = "grid";
  }
  for (const auto& entry : mtpt::bench::SharedDataSets())
  {
    if (!wanted(entry.name))
    {
      continue;
    }
    TetMesh mesh;
    std::string error;
    if (mtpt::bench::LoadTetMesh(o.data + "/" + entry.relativePath, entry.scalarName, mesh, error))
    {
      mesh.name = entry.name;
      meshes.push_back(std::move(mesh));
    }
    else
    {
      std::fprintf(stderr, "skipping %s: %s\n", entry.name, error.c_str());
    }
  }

  std::printf("# Frames: MTPT against VTK's unstructured-grid volume mappers\n\n");
  {
    vtkNew<vtkRenderWindow> probe;
    probe->SetOffScreenRendering(1);
    probe->Render();
    const std::string caps = probe->ReportCapabilities();
    const auto at = caps.find("OpenGL renderer string:");
    std::printf("OpenGL renderer: %s\n",
      at == std::string::npos ? "unknown"
                              : caps.substr(at + 24, caps.find('\n', at) - at - 24).c_str());
  }
  std::printf("Median of %d frames after one warm-up (ms, whole window->Render() with "
              "WaitForCompletion); * = one frame only, slower than %.0f s. RMSE: RGB in [0, 1] "
              "against VTK's PT image of the same scene.\n\n",
    o.repeat, o.slowLimit);
  std::printf("| mesh | tets | size | MTPT CPU | MTPT GL | VTK PT | ray cast | Z-sweep | PT / "
              "MTPT CPU | ray cast / MTPT CPU | Z-sweep / MTPT CPU | RMSE CPU | RMSE GL |\n"
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<std::string> stageRows;
  for (const TetMesh& mesh : meshes)
  {
    auto grid = mtpt::bench::ToUnstructuredGrid(mesh);
    double range[2];
    grid->GetPointData()->GetScalars()->GetRange(range);
    for (int size : o.sizes)
    {
      std::fprintf(stderr, "%s %d\n", mesh.name.c_str(), size);
      vtkNew<Mapper> cpu, gl;
      cpu->SetBackendToCPU();
      gl->SetBackendToOpenGL();
      cpu->SynchronizedTimingOn();
      gl->SynchronizedTimingOn();
      vtkNew<vtkProjectedTetrahedraMapper> pt;
      vtkNew<vtkUnstructuredGridVolumeRayCastMapper> rayCast;
      vtkNew<vtkUnstructuredGridVolumeZSweepMapper> zsweep;
      const Result rc = Measure(grid, cpu, size, range, o);
      const Result rg = Measure(grid, gl, size, range, o);
      const Result rp = Measure(grid, pt, size, range, o);
      const Result rr = Measure(grid, rayCast, size, range, o);
      const Result rz = Measure(grid, zsweep, size, range, o);
      std::printf(
        "| %s | %zu | %d | %s | %s | %s | %s | %s | %.1fx | %.1fx | %.1fx | %.4f | %.4f |\n",
        mesh.name.c_str(), mesh.CellCount(), size, Ms(rc).c_str(), Ms(rg).c_str(), Ms(rp).c_str(),
        Ms(rr).c_str(), Ms(rz).c_str(), rp.ms / rc.ms, rr.ms / rc.ms, rz.ms / rc.ms,
        Rmse(rc.image, rp.image), Rmse(rg.image, rp.image));
      std::fflush(stdout);
      for (const Result* r : { &rc, &rg })
      {
        char row[512];
        const double triangles = 4.0 * mesh.CellCount();
        std::snprintf(row, sizeof(row),
          "| %s | %d | %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.0f |\n",
          mesh.name.c_str(), size, r == &rc ? "CPU" : "GL", r->stages[0], r->stages[1],
          r->stages[2], r->stages[3], r->stages[4], r->stages[5], r->stages[6], r->stages[7],
          1e6 * (r == &rc ? r->stages[4] : r->stages[6]) / triangles);
        stageRows.push_back(row);
      }
    }
  }
  std::printf(
    "\n## MTPT stages (ms, medians)\n\n| mesh | size | backend | transform | depth keys "
    "| order | decompose | composite | upload | draw | CPU stages | ns per triangle "
    "(composite or draw) |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& row : stageRows)
  {
    std::printf("%s", row.c_str());
  }
  return 0;
}
