// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_threads: MTPT's CPU backend at several thread counts (default 1, 2, 4, 8, 16)
// on the same scenes, the camera turning before every timed frame (Harness.h states the
// rules): each stage's median time (the CPU stages one by one, binning and rasterization,
// the whole frame), its speed-up over the fewest threads measured and its parallel
// efficiency, speed-up / (threads / fewest threads). Prints a Markdown table per scene,
// writes threads.csv and one plot of efficiency against threads per scene (PNG, VTK's
// charts) to --out. Run under a display (Testing/xvfb-launch.sh without one).
#include "Harness.h"
#include "Plot.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkUnstructuredGrid.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

/// Stages faster than this at the fewest threads get no efficiency (timer resolution).
constexpr double kMeasurableMs = 0.05;

struct Options
{
  CommonOptions common;
  std::string meshes = "wavelet,grid:10000000";
  std::string size = "1024";
  std::vector<int> threads = { 1, 2, 4, 8, 16 };
  std::string out = ".";
};

/// The stages of a frame, as the mapper times them (StageFigures), and the frame itself.
struct StageColumn
{
  const char* name;
  double StageFigures::*figure; ///< null: the whole frame
};

const std::vector<StageColumn>& Stages()
{
  static const std::vector<StageColumn> stages = { { "transform", &StageFigures::transform },
    { "cull", &StageFigures::cull }, { "depth keys", &StageFigures::keys },
    { "visibility order", &StageFigures::order }, { "decompose", &StageFigures::decompose },
    { "CPU stages", &StageFigures::cpuStages }, { "bin", &StageFigures::bin },
    { "raster", &StageFigures::raster }, { "frame", nullptr } };
  return stages;
}

/// The median of each stage (Stages() order) over the timed frames of one thread count.
std::vector<double> MeasureStages(const Scene& scene, vtkVolumeProperty* property, int threads,
  int width, int height, const Options& o)
{
  MapperSettings settings = o.common.mapper;
  settings.threads = threads;
  auto mapper = MakeMapper("mtpt-cpu", settings);
  StageOptions look;
  look.multisampling = o.common.windows.front();
  Stage stage(scene, property, mapper, width, height, look);
  std::vector<std::vector<double>> samples(Stages().size());
  const FrameTiming timing = TimeFrames(stage, o.common.timing,
    [&](std::size_t)
    {
      const StageFigures f = FiguresOf(mapper);
      for (std::size_t s = 0; s + 1 < Stages().size(); ++s)
      {
        samples[s].push_back(f.*(Stages()[s].figure));
      }
    });
  samples.back() = timing.frames;
  std::vector<double> medians;
  for (const auto& values : samples)
  {
    medians.push_back(Median(values));
  }
  return medians;
}

/// Prints one scene's table (a row per stage: ms, and efficiency past the first thread
/// count), appends its rows to `csv`, and returns the efficiency of each measurable stage
/// against threads.
std::vector<Series> Report(const Scene& scene, const std::vector<std::vector<double>>& byThreads,
  int width, int height, const Options& o, std::ofstream& csv)
{
  const long long tetrahedra = static_cast<long long>(scene.grid->GetNumberOfCells());
  std::printf("\n%s, %lld tetrahedra: ms (parallel efficiency against %d thread%s)\n\n| stage |",
    scene.name.c_str(), tetrahedra, o.threads.front(), o.threads.front() == 1 ? "" : "s");
  for (int threads : o.threads)
  {
    std::printf(" %d |", threads);
  }
  std::printf("\n|---|");
  for (std::size_t t = 0; t < o.threads.size(); ++t)
  {
    std::printf("---:|");
  }
  std::printf("\n");
  std::vector<Series> series;
  for (std::size_t s = 0; s < Stages().size(); ++s)
  {
    Series line{ Stages()[s].name, {}, {} };
    std::printf("| %s |", Stages()[s].name);
    const double base = byThreads.front()[s];
    // A stage that takes no measurable time (culling with nothing to cull) has no
    // efficiency to speak of: its row shows the times alone and it stays off the plot.
    const bool measurable = base >= kMeasurableMs;
    for (std::size_t t = 0; t < o.threads.size(); ++t)
    {
      const double ms = byThreads[t][s];
      const double speedup = ms > 0 ? base / ms : 0;
      const double efficiency = speedup * o.threads.front() / static_cast<double>(o.threads[t]);
      if (t == 0 || !measurable)
      {
        std::printf(" %.2f |", ms);
      }
      else
      {
        std::printf(" %.2f (%.2f) |", ms, efficiency);
      }
      csv << scene.name << ',' << tetrahedra << ',' << width << ',' << height << ','
          << (o.common.windows.front() ? "on" : "off") << ',' << o.threads[t] << ','
          << Stages()[s].name << ',' << ms << ',' << speedup << ',' << efficiency << ','
          << Mapper::GetCompositorInstructionSet() << ',' << std::thread::hardware_concurrency()
          << '\n';
      line.x.push_back(o.threads[t]);
      line.y.push_back(efficiency);
    }
    std::printf("\n");
    if (measurable)
    {
      series.push_back(std::move(line));
    }
  }
  csv.flush();
  std::fflush(stdout);
  return series;
}

/// Writes threads_<scene>.png (the name's other characters than letters and digits as '_',
/// so "grid:10000000" gives threads_grid_10000000.png); false with a message on failure.
bool Plot(const Scene& scene, const std::vector<Series>& series, const Options& o)
{
  Chart chart;
  chart.title = "Parallel efficiency, " + scene.name + " (" +
    std::to_string(scene.grid->GetNumberOfCells()) + " tetrahedra, " + o.size + ")";
  chart.xTitle = "threads";
  chart.yTitle = "speed-up / threads";
  chart.logY = false;
  chart.headroom = 1.6;
  std::string stem = scene.name;
  std::replace_if(
    stem.begin(), stem.end(), [](unsigned char c) { return !std::isalnum(c); }, '_');
  const std::string path = o.out + "/threads_" + stem + ".png";
  std::string error;
  if (!WritePlot(path, chart, series, error))
  {
    std::fprintf(stderr, "mtpt_bench_threads: %s\n", error.c_str());
    return false;
  }
  std::printf("\nWritten: %s\n", path.c_str());
  return true;
}

} // namespace

int main(int argc, char* argv[])
try
{
  Options o;
  o.common.windows = { true };
  CLI::App app{ "MTPT's CPU backend at several thread counts: each stage's time, speed-up and "
                "parallel efficiency, the camera turning before every timed frame." };
  AddCommonOptions(app, o.common);
  app.add_option("--meshes", o.meshes, "scenes (Harness.h: wavelet, grid:N, bluntfin, ...)");
  app.add_option("--size", o.size, "the window: 1024 (square) or 1920x1080");
  app.add_option("--thread-counts", o.threads, "thread counts, comma-separated")
    ->delimiter(',')
    ->check(CLI::Range(1, 4096));
  app.add_option("--out", o.out, "folder for threads.csv and threads_<scene>.png");
  CLI11_PARSE(app, argc, argv);
  std::sort(o.threads.begin(), o.threads.end());
  o.threads.erase(std::unique(o.threads.begin(), o.threads.end()), o.threads.end());
  int width = 0, height = 0;
  if (!ParseSize(o.size, width, height) || o.common.windows.size() != 1)
  {
    std::fprintf(stderr,
      "mtpt_bench_threads: one window: --size 1024 or 1920x1080, and "
      "--multisampling on or off\n");
    return 2;
  }

  const std::string path = o.out + "/threads.csv";
  std::ofstream csv(path);
  csv << "mesh,tetrahedra,width,height,multisampling,threads,stage,ms,speedup,efficiency,"
         "instruction_set,hardware_threads\n";
  std::printf("MTPT's CPU backend, %dx%d, %s window, camera turning %.2f degrees per frame, "
              "median of %d; compositor %s, %u hardware threads\n",
    width, height, WindowName(o.common.windows.front()), o.common.timing.step,
    o.common.timing.repeat, Mapper::GetCompositorInstructionSet(),
    std::thread::hardware_concurrency());
  for (const std::string& meshName : SplitList(o.meshes))
  {
    Scene scene;
    std::string error;
    if (!LoadScene(meshName, o.common.dataFolder, scene, error))
    {
      std::fprintf(stderr, "mtpt_bench_threads: %s\n", error.c_str());
      return 1;
    }
    auto property = MakeProperty(scene);
    std::vector<std::vector<double>> byThreads; // [thread count][stage]
    for (int threads : o.threads)
    {
      byThreads.push_back(MeasureStages(scene, property, threads, width, height, o));
      std::fprintf(stderr, "measured %s at %d threads\n", scene.name.c_str(), threads);
    }

    const std::vector<Series> series = Report(scene, byThreads, width, height, o, csv);
    if (!Plot(scene, series, o))
    {
      return 1;
    }
  }
  std::printf("Written: %s\n", path.c_str());
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_threads", error);
}
