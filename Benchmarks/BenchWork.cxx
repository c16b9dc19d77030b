// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_work: "model only what a scene needs" in figures. On a generated mesh (10M
// tetrahedra by default) and a real one, each with a transfer function that shows every
// cell and one that makes 90% of the cells fully transparent, it times frames of the mapper
// with and without culling, and the reuse cases (unchanged view, small rotation, colour-only
// and opacity changes), printing the CPU stages apart from the whole frame. Then it measures
// peak memory in child processes (batched, unbatched, VTK's PT). Run under a display
// (xvfb-run without one).
#include "MeshLoader.h"
#include "TetrahedralGrid.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkDataArray.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace
{
using mtpt::bench::TetMesh;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  std::size_t tets = 10000000;
  std::string real = "kiefer";
  std::string data = MTPT_SHARED_DATA_DIR;
  int size = 512;
  int repeat = 3;
  std::string child; // memory child: mtpt, mtpt-unbatched, vtkpt
  std::string self;
};

/// Kilobytes from a /proc/self/status line ("VmRSS", "VmHWM").
long StatusKiB(const char* field)
{
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(in, line))
  {
    if (line.compare(0, prefix.size(), prefix) == 0)
    {
      return std::atol(line.c_str() + prefix.size());
    }
  }
  return -1;
}

bool LoadMesh(const Options& o, const std::string& name, TetMesh& mesh)
{
  if (name == "grid")
  {
    mtpt::bench::GridOptions grid;
    grid.cells = mtpt::bench::GridCellsForTetrahedra(o.tets, mtpt::bench::HexSplit::Five);
    grid.jitter = 0.2;
    mesh = mtpt::bench::GenerateTetrahedralGrid(grid);
    return true;
  }
  for (const auto& entry : mtpt::bench::SharedDataSets())
  {
    if (name == entry.name)
    {
      std::string error;
      if (mtpt::bench::LoadTetMesh(
            o.data + "/" + entry.relativePath, entry.scalarName, mesh, error))
      {
        return true;
      }
      std::fprintf(stderr, "%s: %s\n", name.c_str(), error.c_str());
      return false;
    }
  }
  std::fprintf(stderr, "unknown mesh %s\n", name.c_str());
  return false;
}

/// The scalar below which `fraction` of the cells have all four point scalars.
double CellQuantile(const TetMesh& mesh, double fraction)
{
  std::vector<float> highs(mesh.offsets.size() - 1);
  for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
  {
    float high = -1e30f;
    for (auto k = mesh.offsets[c]; k < mesh.offsets[c + 1]; ++k)
    {
      high = std::max(high, mesh.scalars[mesh.connectivity[k]]);
    }
    highs[c] = high;
  }
  const auto nth = highs.begin() + static_cast<std::ptrdiff_t>(fraction * (highs.size() - 1));
  std::nth_element(highs.begin(), nth, highs.end());
  return *nth;
}

/// A scene in one window: the volume's property can be changed between frames.
struct Scene
{
  vtkNew<vtkColorTransferFunction> color;
  vtkNew<vtkPiecewiseFunction> opacity;
  vtkNew<vtkVolumeProperty> property;
  vtkNew<vtkVolume> volume;
  vtkNew<vtkRenderer> renderer;
  vtkNew<vtkRenderWindow> window;
  double range[2] = { 0, 1 };

  Scene(vtkUnstructuredGrid* grid, vtkUnstructuredGridVolumeMapper* mapper, int size,
    double hiddenBelow)
  {
    grid->GetPointData()->GetScalars()->GetRange(this->range);
    this->SetColors(false);
    this->SetOpacity(hiddenBelow);
    this->property->SetColor(this->color);
    this->property->SetScalarOpacity(this->opacity);
    this->property->SetScalarOpacityUnitDistance(grid->GetLength() / 50);
    mapper->SetInputData(grid);
    this->volume->SetMapper(mapper);
    this->volume->SetProperty(this->property);
    this->renderer->SetBackground(1, 1, 1);
    this->renderer->AddVolume(this->volume);
    this->window->SetOffScreenRendering(1);
    this->window->SetMultiSamples(0);
    this->window->SetSize(size, size);
    this->window->AddRenderer(this->renderer);
    this->renderer->ResetCamera();
    this->renderer->GetActiveCamera()->Azimuth(30);
    this->renderer->GetActiveCamera()->Elevation(20);
    this->renderer->GetActiveCamera()->OrthogonalizeViewUp();
    this->renderer->ResetCameraClippingRange();
  }
  void SetColors(bool alternate)
  {
    this->color->RemoveAllPoints();
    this->color->AddRGBPoint(this->range[0], 0.23, 0.30, 0.75);
    this->color->AddRGBPoint(0.5 * (this->range[0] + this->range[1]), alternate ? 0.3 : 0.87, 0.87,
      alternate ? 0.3 : 0.87);
    this->color->AddRGBPoint(this->range[1], 0.71, 0.02, 0.15);
  }
  /// Opacity 0 up to `hiddenBelow`, then a ramp to 1 at the top of the range.
  void SetOpacity(double hiddenBelow)
  {
    this->opacity->RemoveAllPoints();
    this->opacity->AddPoint(this->range[0], 0.0);
    if (hiddenBelow > this->range[0])
    {
      this->opacity->AddPoint(hiddenBelow, 0.0);
    }
    this->opacity->AddPoint(this->range[1], 1.0);
  }
  double Frame()
  {
    const auto start = std::chrono::steady_clock::now();
    this->window->Render();
    this->window->WaitForCompletion();
    return 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

/// One row: `change` runs before every frame.
template <typename Change>
void Case(const char* scene, const char* name, Scene& s, Mapper* m, int repeat, Change&& change)
{
  std::vector<double> frame, cpu, order, decompose;
  int fromPrevious = 0;
  for (int i = 0; i < repeat; ++i)
  {
    change(i);
    frame.push_back(s.Frame());
    cpu.push_back(1e3 * m->GetCPUStageSeconds());
    order.push_back(1e3 * (m->GetDepthKeySeconds() + m->GetOrderSeconds()));
    decompose.push_back(1e3 * m->GetDecomposeSeconds());
    fromPrevious += (m->GetLastFrameReuse() & Mapper::ORDER_FROM_PREVIOUS) ? 1 : 0;
  }
  std::printf("| %s | %s | %.1f | %.1f | %.1f | %.1f | %lld | %lld / %lld / %lld | %s%s |\n", scene,
    name, Median(frame), Median(cpu), Median(order), Median(decompose),
    static_cast<long long>(m->GetNumberOfTetrahedra()),
    static_cast<long long>(m->GetNumberOfOpacityCulledCells()),
    static_cast<long long>(m->GetNumberOfFrustumCulledCells()),
    static_cast<long long>(m->GetNumberOfPixelCulledCells()),
    (m->GetLastFrameReuse() & Mapper::REUSED_DECOMPOSITION) ? "decomposition reused"
      : (m->GetLastFrameReuse() & Mapper::REUSED_ORDER)     ? "order reused"
                                                            : "-",
    fromPrevious ? " (sorted from previous order)" : "");
  std::fflush(stdout);
}

void Cases(const Options& o, const std::string& meshName, const TetMesh& mesh)
{
  auto grid = mtpt::bench::ToUnstructuredGrid(mesh);
  const double hidden90 = CellQuantile(mesh, 0.9);
  for (bool hide : { false, true })
  {
    const std::string scene = meshName + " (" + std::to_string(mesh.offsets.size() - 1) +
      " tets, " + (hide ? "90% transparent" : "all visible") + ")";
    vtkNew<Mapper> mapper;
    Scene s(grid, mapper, o.size, hide ? hidden90 : -1e300);
    vtkCamera* camera = s.renderer->GetActiveCamera();
    s.Frame(); // warm-up
    auto rotate = [&](double degrees) { return [&, degrees](int) { camera->Azimuth(degrees); }; };
    mapper->CullInvisibleCellsOff();
    mapper->ReuseResultsOff();
    Case(scene.c_str(), "new view, no culling", s, mapper, o.repeat, rotate(1.0));
    mapper->CullInvisibleCellsOn();
    Case(scene.c_str(), "new view, culling", s, mapper, o.repeat, rotate(1.0));
    mapper->ReuseResultsOn();
    Case(scene.c_str(), "new view, culling + reuse", s, mapper, o.repeat, rotate(1.0));
    Case(scene.c_str(), "unchanged view", s, mapper, o.repeat, [](int) {});
    Case(scene.c_str(), "rotation by 0.05 deg", s, mapper, o.repeat, rotate(0.05));
    Case(
      scene.c_str(), "colour change", s, mapper, o.repeat, [&](int i) { s.SetColors(i % 2 == 0); });
    // Opacity: alternately hides 2% more of the cells, so the visible set changes.
    const double low = hide ? hidden90 : -1e300, higher = CellQuantile(mesh, hide ? 0.92 : 0.02);
    Case(scene.c_str(), "opacity change", s, mapper, o.repeat,
      [&](int i) { s.SetOpacity(i % 2 ? low : higher); });
    mapper->ReleaseGraphicsResources(s.window);
  }
}

/// Child process: one frame of one mapper; prints resident memory before and the peak.
int MemoryChild(const Options& o)
{
  TetMesh mesh;
  if (!LoadMesh(o, "grid", mesh))
  {
    return 1;
  }
  auto grid = mtpt::bench::ToUnstructuredGrid(mesh);
  vtkSmartPointer<vtkUnstructuredGridVolumeMapper> mapper;
  vtkNew<Mapper> ours;
  if (o.child == "vtkpt")
  {
    mapper = vtkSmartPointer<vtkProjectedTetrahedraMapper>::New();
  }
  else
  {
    ours->SetBatchSize(o.child == "mtpt-unbatched" ? 0 : ours->GetBatchSize());
    mapper = ours.Get();
  }
  Scene s(grid, mapper, o.size, -1e300);
  s.renderer->RemoveVolume(s.volume);
  s.window->Render(); // the context and the window's buffers: not the mapper's memory
  const long before = StatusKiB("VmRSS");
  std::ofstream("/proc/self/clear_refs") << "5"; // reset the peak (VmHWM) to the current RSS
  s.renderer->AddVolume(s.volume);
  const double ms = s.Frame();
  const long peak = StatusKiB("VmHWM");
  std::printf("MEMORY %s %zu %ld %ld %lld %.0f\n", o.child.c_str(), mesh.offsets.size() - 1, before,
    peak, static_cast<long long>(o.child == "vtkpt" ? -1 : ours->GetMemoryBytes()), ms);
  mapper->ReleaseGraphicsResources(s.window);
  return 0;
}

void Memory(const Options& o)
{
  std::printf("\n| mapper (%zu-tet grid, %dx%d) | extra peak resident memory | bytes per tet "
              "(peak) | mapper buffers | frame |\n|---|---|---|---|---|\n",
    o.tets, o.size, o.size);
  for (const char* kind : { "mtpt", "mtpt-unbatched", "vtkpt" })
  {
    const std::string command = o.self + " --child-memory " + kind + " --tets " +
      std::to_string(o.tets) + " --size " + std::to_string(o.size);
    FILE* pipe = popen(command.c_str(), "r");
    char line[512];
    bool found = false;
    while (pipe && std::fgets(line, sizeof(line), pipe))
    {
      char name[64];
      std::size_t tets;
      long before, peak;
      long long buffers;
      double ms;
      if (std::sscanf(line, "MEMORY %63s %zu %ld %ld %lld %lf", name, &tets, &before, &peak,
            &buffers, &ms) == 6)
      {
        const double extra = (peak - before) * 1024.0;
        std::printf("| %s | %.0f MiB | %.1f | %s | %.0f ms |\n", name, extra / (1 << 20),
          extra / tets,
          buffers < 0 ? "-"
                      : (std::to_string(buffers / (1 << 20)) + " MiB (" +
                          std::to_string(buffers / static_cast<long long>(tets)) + " B/tet)")
                          .c_str(),
          ms);
        found = true;
      }
    }
    if (pipe)
    {
      pclose(pipe);
    }
    if (!found)
    {
      std::printf("| %s | failed | | | |\n", kind);
    }
    std::fflush(stdout);
  }
}

} // namespace

int main(int argc, char** argv)
{
  Options o;
  o.self = argv[0];
  bool memoryOnly = false, casesOnly = false;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--tets")
      o.tets = std::strtoull(next().c_str(), nullptr, 10);
    else if (a == "--real")
      o.real = next();
    else if (a == "--data")
      o.data = next();
    else if (a == "--size")
      o.size = std::max(1, std::atoi(next().c_str()));
    else if (a == "--repeat")
      o.repeat = std::max(1, std::atoi(next().c_str()));
    else if (a == "--child-memory")
      o.child = next();
    else if (a == "--memory-only")
      memoryOnly = true;
    else if (a == "--cases-only")
      casesOnly = true;
    else
    {
      std::printf("usage: mtpt_bench_work [--tets N] [--real NAME|none] [--data DIR] [--size S]\n"
                  "  [--repeat R] [--memory-only | --cases-only]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (!o.child.empty())
  {
    return MemoryChild(o);
  }
  if (!memoryOnly)
  {
    std::printf("Frames at %dx%d, median of %d; times in ms. CPU stage = transform + cull + keys + "
                "order + decompose; sort = keys + order. Culled: transparent / outside the view / "
                "covering no pixel.\n\n| scene | case | frame | CPU stage | sort | decompose | "
                "sorted | culled | reuse |\n|---|---|---|---|---|---|---|---|---|\n",
      o.size, o.size, o.repeat);
    for (const std::string& name : { std::string("grid"), o.real })
    {
      if (name == "none")
      {
        continue;
      }
      TetMesh mesh;
      if (LoadMesh(o, name, mesh))
      {
        Cases(o, name, mesh);
      }
    }
  }
  if (!casesOnly)
  {
    Memory(o);
  }
  return 0;
}
