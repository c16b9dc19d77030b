// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_scaling: frame time against mesh size (generated jittered grids of 10 to 10M
// tetrahedra, one window size) or against window size (one scene, 16x16 to 1920x1080),
// for MTPT's backends and VTK's mappers, the camera turning before every timed frame
// (Harness.h states the rules), each in VTK's default window (multisampled) and
// single-sampled (--multisampling). Prints a Markdown table with VTK's PT over MTPT's CPU
// backend each in its faster window, writes a CSV and a log-log plot with one series per
// contender and window (PNG, VTK's charts) to --out. Run under a display (Testing/xvfb-launch.sh
// without one).
#include "Harness.h"
#include "Plot.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkUnstructuredGrid.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;

struct Options
{
  CommonOptions common;
  std::string vary = "mesh";
  std::string meshes = "grid:10,grid:100,grid:1000,grid:10000,grid:100000,grid:1000000,"
                       "grid:10000000";
  std::string size = "512";
  std::string scene = "wavelet";
  std::string sizes = "16,64,256,512,1024,1920x1080";
  std::string contenders = "mtpt-cpu,mtpt-gl,vtk-pt";
  std::string out = ".";
};

/// One measured point: a scene in a window, per contender.
struct Point
{
  std::string scene;
  long long tetrahedra = 0;
  int width = 0, height = 0;
  std::map<std::string, WindowMeasurements> results;
};

/// "vtk-pt (single-sampled)": a contender in one kind of window, as a column and a series.
std::string Label(const std::string& name, bool multisampling)
{
  return name + " (" + WindowName(multisampling) + ")";
}

/// VTK PT over MTPT CPU, each at its faster window, and in each window; empty without both.
std::string Ratios(const Point& p)
{
  const auto pt = p.results.find("vtk-pt"), cpu = p.results.find("mtpt-cpu");
  if (pt == p.results.end() || cpu == p.results.end())
  {
    return " |";
  }
  char text[64];
  std::snprintf(text, sizeof(text), " %.2fx |",
    pt->second.Fastest().moving.median / cpu->second.Fastest().moving.median);
  std::string ratios = text;
  for (std::size_t w = 0; w < cpu->second.windows.size(); ++w)
  {
    const Measurement* same = pt->second.In(cpu->second.windows[w]);
    std::snprintf(text, sizeof(text), " %.2fx |",
      same ? same->moving.median / cpu->second.measurements[w].moving.median : 0.0);
    ratios += text;
  }
  return ratios;
}

} // namespace

int main(int argc, char* argv[])
try
{
  Options o;
  CLI::App app{ "Frame time against mesh size or window size, for MTPT and VTK's mappers, "
                "the camera turning before every timed frame." };
  AddCommonOptions(app, o.common);
  app
    .add_option("--vary", o.vary,
      "what changes: the mesh (--meshes, one --size) or the "
      "window (--sizes, one --scene)")
    ->check(CLI::IsMember({ "mesh", "window" }));
  app.add_option("--meshes", o.meshes, "--vary mesh: the scenes, smallest first (Harness.h)");
  app.add_option("--size", o.size, "--vary mesh: the window, 512 or 1920x1080");
  app.add_option("--scene", o.scene, "--vary window: the scene");
  app.add_option("--sizes", o.sizes, "--vary window: the windows, comma-separated");
  app.add_option("--contenders", o.contenders, "mtpt-cpu, mtpt-gl, vtk-pt, raycast, zsweep");
  app.add_option("--out", o.out, "folder for scaling_<vary>.csv and scaling_<vary>.png");
  CLI11_PARSE(app, argc, argv);

  const bool byMesh = o.vary == "mesh";
  std::vector<std::string> scenes = byMesh ? SplitList(o.meshes) : SplitList(o.scene);
  std::vector<std::pair<int, int>> windows;
  for (const std::string& text : SplitList(byMesh ? o.size : o.sizes))
  {
    int w = 0, h = 0;
    if (!ParseSize(text, w, h))
    {
      std::fprintf(stderr, "mtpt_bench_scaling: not a window size: '%s'\n", text.c_str());
      return 2;
    }
    windows.emplace_back(w, h);
  }
  if (scenes.empty() || windows.empty() || (byMesh && windows.size() != 1) ||
    (!byMesh && scenes.size() != 1))
  {
    std::fprintf(stderr,
      "mtpt_bench_scaling: --vary mesh takes one --size and several "
      "--meshes; --vary window one --scene and several --sizes\n");
    return 2;
  }
  const std::vector<std::string> names = SplitList(o.contenders);
  for (const std::string& name : names)
  {
    if (!MakeMapper(name))
    {
      std::fprintf(stderr, "mtpt_bench_scaling: unknown contender '%s'\n", name.c_str());
      return 2;
    }
  }

  std::vector<Point> points;
  for (const std::string& sceneName : scenes)
  {
    Scene scene;
    std::string error;
    if (!LoadScene(sceneName, o.common.dataFolder, scene, error))
    {
      std::fprintf(stderr, "mtpt_bench_scaling: %s\n", error.c_str());
      return 1;
    }
    auto property = MakeProperty(scene);
    for (const auto& window : windows)
    {
      Point p;
      p.scene = scene.name;
      p.tetrahedra = static_cast<long long>(scene.grid->GetNumberOfCells());
      p.width = window.first;
      p.height = window.second;
      p.results = MeasureContenders(scene, property, names, p.width, p.height, o.common);
      std::fprintf(stderr, "measured %s at %dx%d\n", p.scene.c_str(), p.width, p.height);
      points.push_back(std::move(p));
    }
  }

  // The table, the CSV and the plot.
  std::printf("Frame time (ms, median of %d, camera turning %.2f degrees per frame; * one "
              "frame slower than %.0f s), MTPT shading %s\n\n",
    o.common.timing.repeat, o.common.timing.step, o.common.timing.slowLimit,
    o.common.mapper.shading.c_str());
  const std::vector<bool>& kinds = o.common.windows;
  std::printf("| scene | tetrahedra | window |");
  for (const std::string& name : names)
  {
    for (bool multisampling : kinds)
    {
      std::printf(" %s |", Label(name, multisampling).c_str());
    }
  }
  std::printf(" VTK PT / MTPT CPU, each in its faster window |");
  for (bool multisampling : kinds)
  {
    std::printf(" VTK PT / MTPT CPU, %s |", WindowName(multisampling));
  }
  std::printf("\n|---|---:|---|");
  for (std::size_t i = 0; i < names.size() * kinds.size() + 1 + kinds.size(); ++i)
  {
    std::printf("---:|");
  }
  std::printf("\n");
  const std::string stem = o.out + "/scaling_" + o.vary;
  std::ofstream csv(stem + ".csv");
  csv << "scene,tetrahedra,width,height,contender,multisampling,shading,ms,slow,cpu_stages_ms,"
         "composite_ms,fragments,threads\n";
  vtkNew<vtkMultiThreadedProjectedTetrahedraMapper> probe;
  const int threads = probe->GetEffectiveNumberOfThreads();
  std::vector<Series> series;
  for (const std::string& name : names)
  {
    for (bool multisampling : kinds)
    {
      series.push_back(Series{ Label(name, multisampling), {}, {} });
    }
  }
  for (const Point& p : points)
  {
    std::printf("| %s | %lld | %dx%d |", p.scene.c_str(), p.tetrahedra, p.width, p.height);
    for (std::size_t k = 0; k < names.size(); ++k)
    {
      const WindowMeasurements& all = p.results.at(names[k]);
      for (std::size_t w = 0; w < kinds.size(); ++w)
      {
        const Measurement& m = all.measurements[w];
        std::printf(" %s |", FormatMs(m.moving).c_str());
        csv << p.scene << ',' << p.tetrahedra << ',' << p.width << ',' << p.height << ','
            << names[k] << ',' << (kinds[w] ? "on" : "off") << ',' << o.common.mapper.shading << ','
            << m.moving.median << ',' << (m.moving.slow ? 1 : 0) << ',' << m.mtpt.cpuStages << ','
            << m.mtpt.composite << ',' << m.mtpt.fragments << ',' << threads << '\n';
        Series& s = series[k * kinds.size() + w];
        s.x.push_back(
          byMesh ? static_cast<double>(p.tetrahedra) : static_cast<double>(p.width) * p.height);
        s.y.push_back(m.moving.median);
      }
    }
    std::printf("%s\n", Ratios(p).c_str());
  }
  Chart chart;
  chart.title = byMesh
    ? "Frame time against mesh size (" + o.size + " window, " + std::to_string(threads) +
      " threads)"
    : "Frame time against window size (" + o.scene + ", " + std::to_string(threads) + " threads)";
  chart.xTitle = byMesh ? "tetrahedra" : "pixels in the window";
  chart.yTitle = "ms per frame (camera moving)";
  std::string error;
  if (!WritePlot(stem + ".png", chart, series, error))
  {
    std::fprintf(stderr, "mtpt_bench_scaling: %s\n", error.c_str());
    return 1;
  }
  std::printf("\nWritten: %s.csv, %s.png\n", stem.c_str(), stem.c_str());
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_scaling", error);
}
