// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_large: large meshes on one machine. For each mesh, smallest first (generated
// jittered grids of 1M to 100M tetrahedra by default), MTPT's CPU backend and VTK's PT in
// one window (the first kind --multisampling names; single-sampled is the faster of the two
// for both on llvmpipe), the camera turning before every timed frame (Harness.h):
// - MTPT's full frame: its CPU stages (and their rate in tetrahedra a second), rasterization,
//   fragments and time per fragment and core;
// - MTPT's moving frame with the window asking for --rate frames a second, as VTK's
//   interactor asks while the user drags (the level of detail draws a subset of the cells at
//   a coarser image sample distance): its time, the fraction of the cells drawn and the
//   distance;
// - memory: the grid's own (vtkDataObject::GetActualMemorySize), MTPT's buffers after its
//   frames (GetMemoryBytes) and per tetrahedron, and the process's peak resident memory over
//   each contender's frames (VmHWM, reset before each);
// - VTK's PT where the mesh has at most --vtk-limit tetrahedra (its buffers grow with the
//   mesh: the run says how much it measured, so that a larger mesh is not tried on a machine
//   it cannot fit), and VTK's PT over MTPT.
// Prints a Markdown table, writes large_meshes.csv and large_meshes.png (frame time against
// tetrahedra) to --out. Run under a display (Testing/xvfb-launch.sh without one).
#include "Harness.h"
#include "Plot.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkUnstructuredGrid.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;

struct Options
{
  CommonOptions common;
  std::string meshes = "grid:1000000,grid:3000000,grid:10000000,grid:30000000,grid:100000000";
  std::string size = "1024";
  double rate = 10;
  long long vtkLimit = 40000000;
  std::string out = ".";
};

/// One contender's frames on one mesh, and the memory they took.
struct Run
{
  bool measured = false;
  Measurement m;
  double peakMiB = 0; ///< the process's peak resident memory over the frames
};

/// Times `name` on `scene` (Measure) with the peak resident memory reset before it.
Run Timed(const Scene& scene, vtkVolumeProperty* property, const std::string& name, int width,
  int height, const CommonOptions& options)
{
  ResetPeakMemory();
  Run r;
  r.m = Measure(scene, property, name, width, height, options);
  r.peakMiB = StatusKiB("VmHWM") / 1024.0;
  r.measured = true;
  return r;
}

/// `value` with `digits` decimals.
std::string Fixed(double value, int digits)
{
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

/// "7194" or "25120*" (one frame: slower than the slow limit), "-" when not measured.
std::string Ms(const Run& r)
{
  return r.measured ? FormatMs(r.m.moving) : "-";
}

} // namespace

int main(int argc, char* argv[])
try
{
  Options o;
  o.common.windows = { false };
  CLI::App app{ "Large meshes: MTPT's full and moving frames, CPU stages, rasterization and "
                "memory against mesh size, beside VTK's PT, the camera turning before every "
                "timed frame." };
  AddCommonOptions(app, o.common);
  app.add_option("--meshes", o.meshes, "the scenes, smallest first (Harness.h)");
  app.add_option("--size", o.size, "the window, 1024 or 1920x1080");
  app.add_option("--rate", o.rate, "the frames a second the window asks for while moving")
    ->check(CLI::PositiveNumber);
  app.add_option(
    "--vtk-limit", o.vtkLimit, "VTK's PT only on meshes of at most this many tetrahedra (0: none)");
  app.add_option("--out", o.out, "folder for large_meshes.csv and large_meshes.png");
  CLI11_PARSE(app, argc, argv);

  int width = 0, height = 0;
  if (!ParseSize(o.size, width, height))
  {
    std::fprintf(stderr, "mtpt_bench_large: not a window size: '%s'\n", o.size.c_str());
    return 2;
  }
  const bool multisampling = o.common.windows.front();
  o.common.windows = { multisampling };
  CommonOptions moving = o.common;
  moving.desiredUpdateRate = o.rate;
  moving.mapper.autoAdjust = true; // the mapper's defaults: the level of detail on
  moving.timing.warmUp = std::max(moving.timing.warmUp, 3); // the level of detail settles

  vtkNew<vtkMultiThreadedProjectedTetrahedraMapper> probe;
  const int threads = probe->GetEffectiveNumberOfThreads();
  const std::string stem = o.out + "/large_meshes";
  std::ofstream csv(stem + ".csv");
  const char* instructionSet =
    vtkMultiThreadedProjectedTetrahedraMapper::GetCompositorInstructionSet();
  csv << "scene,tetrahedra,width,height,multisampling,threads,instruction_set,grid_mib,mtpt_ms,"
         "mtpt_slow,cpu_stages_ms,composite_ms,raster_ms,fragments,mtpt_mib,mtpt_peak_mib,"
         "moving_rate,moving_ms,moving_cell_fraction,moving_sample_distance,vtk_pt_ms,"
         "vtk_pt_slow,vtk_pt_peak_mib,moving_mtpt_mib,moving_peak_mib,sorted,hidden\n";
  std::printf("%dx%d, %s, %d threads, camera turning %.2f degrees per frame, median of %d (* one "
              "frame, slower than %.0f s); MTPT shading %s, its CPU compositor %s\n\n",
    width, height, WindowName(multisampling), threads, o.common.timing.step, o.common.timing.repeat,
    o.common.timing.slowLimit, o.common.mapper.shading.c_str(), instructionSet);
  std::printf("| tetrahedra | MTPT frame ms | CPU stages ms | tetrahedra a second | "
              "rasterization ms | fragments | ns per fragment x core | sorted cells: fans, "
              "hidden | moving at %g fps asked: "
              "ms, cells, distance | grid MiB | MTPT MiB | MTPT bytes per tet | peak MiB, "
              "MTPT | moving: MTPT MiB, bytes per tet, peak MiB | VTK PT ms | peak MiB, VTK PT | "
              "VTK PT / MTPT |\n",
    o.rate);
  std::printf(
    "|---:|---:|---:|---:|---:|---:|---:|---|---|---:|---:|---:|---:|---|---:|---:|---:|\n");
  Series full{ "MTPT CPU, full frame", {}, {} }, atRate{ "", {}, {} }, pt{ "VTK PT", {}, {} },
    stages{ "MTPT CPU stages", {}, {} };
  atRate.label = "MTPT CPU, moving at " + Fixed(o.rate, 0) + " fps asked";
  for (const std::string& name : SplitList(o.meshes))
  {
    Scene scene;
    std::string error;
    if (!LoadScene(name, o.common.dataFolder, scene, error))
    {
      std::fprintf(stderr, "mtpt_bench_large: %s\n", error.c_str());
      return 1;
    }
    auto property = MakeProperty(scene);
    const long long tets = static_cast<long long>(scene.grid->GetNumberOfCells());
    const double gridMiB = scene.grid->GetActualMemorySize() / 1024.0;
    const Run ours = Timed(scene, property, "mtpt-cpu", width, height, o.common);
    const StageFigures& f = ours.m.mtpt;
    const double mtptMiB = static_cast<double>(f.memoryBytes) / (1 << 20);
    const Run lod = Timed(scene, property, "mtpt-cpu", width, height, moving);
    Run vtk;
    if (o.vtkLimit <= 0 || tets <= o.vtkLimit)
    {
      vtk = Timed(scene, property, "vtk-pt", width, height, o.common);
    }
    const double cellFraction = tets > 0 ? static_cast<double>(lod.m.mtpt.sorted) / tets : 0;
    const double rasterNs = NsPerFragmentCore(f, threads);
    const double movingMiB = static_cast<double>(lod.m.mtpt.memoryBytes) / (1 << 20);
    const double hiddenShare = f.sorted > 0 ? static_cast<double>(f.hidden) / f.sorted : 0;
    std::printf("| %lld | %s | %.0f | %.1fM | %.0f | %.0fM | %.1f | %.0f%%, %.0f%% | %s, %.0f%%, "
                "%.2f | %.0f | "
                "%.0f | %.1f | %.0f | %.0f, %.1f, %.0f | %s | %s | %s |\n",
      tets, Ms(ours).c_str(), f.cpuStages, f.cpuStages > 0 ? tets / f.cpuStages / 1e3 : 0.0,
      f.raster, f.fragments / 1e6, rasterNs, 100 * (1 - hiddenShare), 100 * hiddenShare,
      Ms(lod).c_str(), 100 * cellFraction, lod.m.mtpt.imageSampleDistance, gridMiB, mtptMiB,
      tets > 0 ? static_cast<double>(f.memoryBytes) / tets : 0.0, ours.peakMiB, movingMiB,
      tets > 0 ? static_cast<double>(lod.m.mtpt.memoryBytes) / tets : 0.0, lod.peakMiB,
      Ms(vtk).c_str(), vtk.measured ? Fixed(vtk.peakMiB, 0).c_str() : "-",
      vtk.measured ? (Fixed(vtk.m.moving.median / ours.m.moving.median, 2) + "x").c_str() : "-");
    std::fflush(stdout);
    csv << scene.name << ',' << tets << ',' << width << ',' << height << ','
        << (multisampling ? "on" : "off") << ',' << threads << ',' << instructionSet << ','
        << gridMiB << ',' << ours.m.moving.median << ',' << (ours.m.moving.slow ? 1 : 0) << ','
        << f.cpuStages << ',' << f.composite << ',' << f.raster << ',' << f.fragments << ','
        << mtptMiB << ',' << ours.peakMiB << ',' << o.rate << ',' << lod.m.moving.median << ','
        << cellFraction << ',' << lod.m.mtpt.imageSampleDistance << ','
        << (vtk.measured ? std::to_string(vtk.m.moving.median) : "") << ','
        << (vtk.measured ? (vtk.m.moving.slow ? "1" : "0") : "") << ','
        << (vtk.measured ? std::to_string(vtk.peakMiB) : "") << ',' << movingMiB << ','
        << lod.peakMiB << ',' << f.sorted << ',' << f.hidden << '\n';
    csv.flush();
    for (Series* s : { &full, &atRate, &stages })
    {
      s->x.push_back(static_cast<double>(tets));
    }
    full.y.push_back(ours.m.moving.median);
    atRate.y.push_back(lod.m.moving.median);
    stages.y.push_back(f.cpuStages);
    if (vtk.measured)
    {
      pt.x.push_back(static_cast<double>(tets));
      pt.y.push_back(vtk.m.moving.median);
    }
    std::fprintf(stderr, "measured %s\n", scene.name.c_str());
  }
  Chart chart;
  chart.title = "Frame time against mesh size (" + o.size + " window, " +
    WindowName(multisampling) + ", " + std::to_string(threads) + " threads)";
  chart.xTitle = "tetrahedra";
  chart.yTitle = "ms per frame (camera moving)";
  std::vector<Series> series;
  for (const Series* s : { &full, &stages, &atRate, &pt })
  {
    if (s->x.size() >= 2) // a line needs two points
    {
      series.push_back(*s);
    }
  }
  std::string error;
  if (!WritePlot(stem + ".png", chart, series, error))
  {
    std::fprintf(stderr, "mtpt_bench_large: %s\n", error.c_str());
    return 1;
  }
  std::printf("\nWritten: %s.csv, %s.png\n", stem.c_str(), stem.c_str());
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_large", error);
}
