// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_work: "model only what a scene needs" in figures. On a generated mesh (10M
// tetrahedra by default) and a real one, each with a transfer function that shows every
// cell and one that makes 90% of the cells fully transparent, it times frames of the mapper
// with and without culling, and the reuse cases (unchanged view, small rotation, colour-only
// and opacity changes), printing the CPU stages apart from the whole frame. Then it measures
// peak memory in child processes (batched, unbatched, VTK's PT). Windows as the benchmark
// harness makes them (Harness.h), of the first kind --multisampling names (VTK's default,
// multisampled, unless it says off): these figures compare MTPT with itself. The cases that keep
// the view unchanged measure reuse and are labelled so; every other case turns the camera before
// each frame. Run under a display (Testing/xvfb-launch.sh without one).
#include "Harness.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  long long tets = 10000000;
  std::string real = "kiefer";
  int size = 512;
  CommonOptions common; ///< repeat, data folder
  std::string child;    ///< memory child: mtpt, mtpt-unbatched, vtkpt
  std::string self;
};

/// The benchmark's window: of the first kind --multisampling names.
StageOptions Window(const Options& o)
{
  StageOptions look;
  look.multisampling = o.common.windows.front();
  return look;
}

/// "grid" (the generated grid of --tets) or a harness scene name.
bool LoadMesh(const Options& o, const std::string& name, Scene& scene)
{
  std::string error;
  const std::string what = name == "grid" ? "grid:" + std::to_string(o.tets) : name;
  if (!LoadScene(what, o.common.dataFolder, scene, error))
  {
    std::fprintf(stderr, "%s: %s\n", name.c_str(), error.c_str());
    return false;
  }
  scene.name = name;
  return true;
}

/// The point scalar below which `fraction` of the cells have all their points.
double CellQuantile(vtkUnstructuredGrid* grid, double fraction)
{
  vtkDataArray* scalars = grid->GetPointData()->GetScalars();
  std::vector<double> highs(static_cast<std::size_t>(grid->GetNumberOfCells()));
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, ids);
    double high = -1e300;
    for (const vtkIdType id : *ids)
    {
      high = std::max(high, scalars->GetTuple1(id));
    }
    highs[static_cast<std::size_t>(c)] = high;
  }
  const auto nth = highs.begin() + static_cast<std::ptrdiff_t>(fraction * (highs.size() - 1));
  std::nth_element(highs.begin(), nth, highs.end());
  return *nth;
}

/// The transfer functions of a scene, changed between frames by the cases.
struct TransferFunctions
{
  vtkNew<vtkColorTransferFunction> color;
  vtkNew<vtkPiecewiseFunction> opacity;
  vtkNew<vtkVolumeProperty> property;
  double range[2] = { 0, 1 };

  TransferFunctions(const Scene& scene, double hiddenBelow)
  {
    std::copy(scene.range, scene.range + 2, this->range);
    this->SetColors(false);
    this->SetOpacity(hiddenBelow);
    this->property->SetColor(this->color);
    this->property->SetScalarOpacity(this->opacity);
    this->property->SetScalarOpacityUnitDistance(scene.grid->GetLength() / 50);
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
};

/// One row: `change` runs before every frame.
template <typename Change>
void Case(const char* scene, const char* name, Stage& s, Mapper* m, int repeat, Change&& change)
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
  const int reuse = m->GetLastFrameReuse();
  std::printf("| %s | %s | %.1f | %.1f | %.1f | %.1f | %lld | %lld / %lld / %lld | %s%s |\n", scene,
    name, Median(frame), Median(cpu), Median(order), Median(decompose),
    static_cast<long long>(m->GetNumberOfTetrahedra()),
    static_cast<long long>(m->GetNumberOfOpacityCulledCells()),
    static_cast<long long>(m->GetNumberOfFrustumCulledCells()),
    static_cast<long long>(m->GetNumberOfPixelCulledCells()),
    (reuse & Mapper::REUSED_IMAGE)             ? "image reused"
      : (reuse & Mapper::REUSED_DECOMPOSITION) ? "decomposition reused"
      : (reuse & Mapper::REUSED_ORDER)         ? "order reused"
                                               : "-",
    fromPrevious ? " (sorted from previous order)" : "");
  std::fflush(stdout);
}

void Cases(const Options& o, const Scene& mesh)
{
  const double hidden90 = CellQuantile(mesh.grid, 0.9);
  for (bool hide : { false, true })
  {
    const std::string scene = mesh.name + " (" + std::to_string(mesh.grid->GetNumberOfCells()) +
      " tets, " + (hide ? "90% transparent" : "all visible") + ")";
    vtkNew<Mapper> mapper;
    TransferFunctions tf(mesh, hide ? hidden90 : -1e300);
    Stage s(mesh, tf.property, mapper, o.size, o.size, Window(o));
    s.Frame(); // warm-up
    const int repeat = o.common.timing.repeat;
    auto turn = [&](double degrees) { return [&, degrees](int) { s.Turn(degrees); }; };
    const double step = o.common.timing.step;
    mapper->CullInvisibleCellsOff();
    mapper->ReuseResultsOff();
    Case(scene.c_str(), "new view, no culling", s, mapper, repeat, turn(step));
    mapper->CullInvisibleCellsOn();
    Case(scene.c_str(), "new view, culling", s, mapper, repeat, turn(step));
    mapper->ReuseResultsOn();
    Case(scene.c_str(), "new view, culling + reuse", s, mapper, repeat, turn(step));
    Case(scene.c_str(), "unchanged view (reuse)", s, mapper, repeat, [](int) {});
    Case(scene.c_str(), "rotation by 0.05 deg", s, mapper, repeat, turn(0.05));
    Case(scene.c_str(), "colour change, unchanged view", s, mapper, repeat,
      [&](int i) { tf.SetColors(i % 2 == 0); });
    // Opacity: alternately hides 2% more of the cells, so the visible set changes.
    const double low = hide ? hidden90 : -1e300,
                 higher = CellQuantile(mesh.grid, hide ? 0.92 : 0.02);
    Case(scene.c_str(), "opacity change, unchanged view", s, mapper, repeat,
      [&](int i) { tf.SetOpacity(i % 2 ? low : higher); });
  }
}

/// Child process: one frame of one mapper; prints resident memory before and the peak.
int MemoryChild(const Options& o)
{
  Scene mesh;
  if (!LoadMesh(o, "grid", mesh))
  {
    return 1;
  }
  vtkSmartPointer<vtkUnstructuredGridVolumeMapper> mapper;
  vtkNew<Mapper> ours;
  if (o.child == "vtkpt")
  {
    mapper = MakeMapper("vtk-pt");
  }
  else
  {
    ours->SetBatchSize(o.child == "mtpt-unbatched" ? 0 : ours->GetBatchSize());
    mapper = ours.Get();
  }
  TransferFunctions tf(mesh, -1e300);
  Stage s(mesh, tf.property, mapper, o.size, o.size, Window(o));
  s.GetRenderer()->RemoveVolume(s.GetVolume());
  s.Frame(); // the context and the window's buffers: not the mapper's memory
  const long before = StatusKiB("VmRSS");
  ResetPeakMemory();
  s.GetRenderer()->AddVolume(s.GetVolume());
  const double ms = s.Frame();
  const long peak = StatusKiB("VmHWM");
  std::printf("MEMORY %s %lld %ld %ld %lld %.0f\n", o.child.c_str(),
    static_cast<long long>(mesh.grid->GetNumberOfCells()), before, peak,
    static_cast<long long>(o.child == "vtkpt" ? -1 : ours->GetMemoryBytes()), ms);
  return 0;
}

void Memory(const Options& o)
{
  std::printf("\n| mapper (%zu-tet grid, %dx%d) | extra peak resident memory | bytes per tet "
              "(peak) | mapper buffers | frame |\n|---|---|---|---|---|\n",
    static_cast<std::size_t>(o.tets), o.size, o.size);
  for (const char* kind : { "mtpt", "mtpt-unbatched", "vtkpt" })
  {
    const std::string command = o.self + " --child-memory " + kind + " --tets " +
      std::to_string(o.tets) + " --size " + std::to_string(o.size) + " --data '" +
      o.common.dataFolder + "' --multisampling " + (o.common.windows.front() ? "on" : "off");
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
try
{
  Options o;
  o.self = argv[0];
  o.common.timing.repeat = 3;
  bool memoryOnly = false, casesOnly = false;
  CLI::App app{ "Culling, reuse and batching in figures, and peak memory." };
  AddCommonOptions(app, o.common);
  app.add_option("--tets", o.tets, "tetrahedra of the generated grid")->check(CLI::PositiveNumber);
  app.add_option("--real", o.real, "a real mesh too (harness scene name), or none");
  app.add_option("--size", o.size, "window size (square)")->check(CLI::PositiveNumber);
  app.add_option("--child-memory", o.child, "internal: one memory measurement")
    ->check(CLI::IsMember({ "mtpt", "mtpt-unbatched", "vtkpt" }));
  app.add_flag("--memory-only", memoryOnly, "only the memory table");
  app.add_flag("--cases-only", casesOnly, "only the culling and reuse table");
  CLI11_PARSE(app, argc, argv);
  if (!o.child.empty())
  {
    return MemoryChild(o);
  }
  if (!memoryOnly)
  {
    std::printf("Frames at %dx%d, median of %d; times in ms; new views turn the camera by %.2f "
                "degrees. CPU stage = transform + cull + keys + order + decompose; sort = keys + "
                "order. Culled: transparent / outside the view / covering no pixel.\n\n| scene "
                "| case | frame | CPU stage | sort | decompose | sorted | culled | reuse |\n"
                "|---|---|---|---|---|---|---|---|---|\n",
      o.size, o.size, o.common.timing.repeat, o.common.timing.step);
    for (const std::string& name : { std::string("grid"), o.real })
    {
      Scene mesh;
      if (name != "none" && LoadMesh(o, name, mesh))
      {
        Cases(o, mesh);
      }
    }
  }
  if (!casesOnly)
  {
    Memory(o);
  }
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_work", error);
}
