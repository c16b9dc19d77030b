// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_interactive: moving frames at the rate a window asks for, as a user dragging
// the view gets them. For every scene, window size, contender and asked rate: the window's
// desired update rate set as VTK's interactor sets it while the user drags, warm-up frames,
// then timed frames with the camera turning before each (7 degrees by default); the median
// moving frame against the time the renderer allots (1 / rate), and the images of the last 5
// moving frames against the still frames of the same views (the window then asks for VTK's
// still rate, 0.0001 frames a second), the median of their covered RMSEs. Contenders: MTPT
// with its defaults (cell level of detail and image sample distance adjusted together), MTPT
// adjusting the image sample distance alone (VTK's rule, AutoAdjustCellFraction off), and
// VTK's unstructured ray caster adjusting its image sample distance (its default). --plot
// draws moving-frame time against image error for every contender and rate (--plot-from
// draws it from a CSV that --csv wrote); --csv appends every figure. The peak resident
// memory of the process ends the output.
#include "Harness.h"
#include "Plot.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "mtpt/LevelOfDetail.h"

#include "vtkCamera.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridVolumeRayCastMapper.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  std::string meshes = "wavelet,comb";
  std::string sizes = "1024";
  std::string rates = "5,10,15,25";
  std::string contenders = "mtpt-cpu,mtpt-cpu-distance,raycast";
  int frames = 15, warmUp = 10;
  double step = 7;
  bool multisampling = true;
  int threads = 0;
  std::string dataFolder;
  std::string csv, plot;
};

/// Whether `name` is an MTPT contender that adjusts the image sample distance alone
/// ("mtpt-cpu-distance"), and its name without that suffix.
bool DistanceOnly(const std::string& name, std::string* base = nullptr)
{
  const std::string suffix = "-distance";
  const bool alone = name.size() > suffix.size() &&
    name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  if (base)
  {
    *base = alone ? name.substr(0, name.size() - suffix.size()) : name;
  }
  return alone;
}

/// The contenders of this benchmark, each as a user gets it with the rate asked for.
vtkSmartPointer<vtkUnstructuredGridVolumeMapper> MakeContender(
  const std::string& name, int threads)
{
  if (name == "raycast")
  {
    auto mapper = vtkSmartPointer<vtkUnstructuredGridVolumeRayCastMapper>::New();
    mapper->AutoAdjustSampleDistancesOn(); // its default
    return mapper;
  }
  std::string base;
  const bool distanceOnly = DistanceOnly(name, &base);
  if (base != "mtpt-cpu" && base != "mtpt-gl")
  {
    return nullptr;
  }
  auto mapper = vtkSmartPointer<Mapper>::New();
  mapper->SetBackend(base == "mtpt-cpu" ? Mapper::CPU_BACKEND : Mapper::OPENGL_BACKEND);
  mapper->SetNumberOfThreads(threads);
  mapper->SetAutoAdjustCellFraction(distanceOnly ? 0 : 1);
  return mapper;
}

/// A contender as the plot's legend names it.
std::string ContenderLabel(const std::string& name)
{
  if (name == "raycast")
  {
    return "VTK's ray caster";
  }
  const std::string backend = name.rfind("mtpt-gl", 0) == 0 ? " (OpenGL)" : "";
  return (DistanceOnly(name) ? "MTPT, image sample distance alone" : "MTPT") + backend;
}

/// RMSE over RGB of the pixels either image covers (differs from `background` by more
/// than 2/255 in a channel), in 255ths.
double CoveredRmse(vtkImageData* a, vtkImageData* b, const double background[3])
{
  auto* pa = vtkUnsignedCharArray::SafeDownCast(a->GetPointData()->GetScalars());
  auto* pb = vtkUnsignedCharArray::SafeDownCast(b->GetPointData()->GetScalars());
  if (!pa || !pb || pa->GetNumberOfValues() != pb->GetNumberOfValues())
  {
    return -1;
  }
  double sum = 0;
  vtkIdType count = 0;
  for (vtkIdType i = 0; i < pa->GetNumberOfTuples(); ++i)
  {
    bool covered = false;
    for (int c = 0; c < 3; ++c)
    {
      const double bg = 255 * background[c];
      covered = covered || std::fabs(pa->GetValue(3 * i + c) - bg) > 2 ||
        std::fabs(pb->GetValue(3 * i + c) - bg) > 2;
    }
    if (covered)
    {
      for (int c = 0; c < 3; ++c)
      {
        const double d = pa->GetValue(3 * i + c) - pb->GetValue(3 * i + c);
        sum += d * d;
      }
      count += 3;
    }
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

/// Moving frames whose images are compared with the still frames of their views.
constexpr int ComparedFrames = 5;

/// One contender at one rate.
struct Result
{
  double medianMs = 0, volumeMs = 0, rmse = 0;
  /// Of the median moving frame: MTPT's cell fraction, the image sample distance (MTPT's or
  /// the ray caster's).
  double fraction = 1, distance = 1;
};

Result Run(const Scene& scene, vtkVolumeProperty* property, const std::string& name, int width,
  int height, double rate, const Options& o)
{
  Result r;
  auto mapper = MakeContender(name, o.threads);
  StageOptions look;
  look.multisampling = o.multisampling;
  look.desiredUpdateRate = rate;
  Stage stage(scene, property, mapper, width, height, look);
  std::vector<double> ms, volumeMs, fractions, distances;
  stage.StartView();
  for (int i = 0; i < o.warmUp; ++i) // the first analyses the input; the rule then settles
  {
    stage.Turn(o.step);
    stage.Frame();
  }
  auto* ours = Mapper::SafeDownCast(mapper);
  auto* caster = vtkUnstructuredGridVolumeRayCastMapper::SafeDownCast(mapper);
  // The last frames' images and views, compared with still frames of the same views after
  // the timed frames (in between, a still frame would change what the rule learns).
  struct Kept
  {
    vtkSmartPointer<vtkImageData> image;
    vtkNew<vtkCamera> camera;
  };
  std::vector<std::unique_ptr<Kept>> kept;
  for (int i = 0; i < o.frames; ++i)
  {
    stage.Turn(o.step);
    ms.push_back(stage.Frame());
    if (i >= o.frames - ComparedFrames)
    {
      kept.push_back(std::make_unique<Kept>());
      kept.back()->image = stage.Image();
      kept.back()->camera->DeepCopy(stage.GetRenderer()->GetActiveCamera());
    }
    volumeMs.push_back(1e3 * mapper->GetTimeToDraw());
    fractions.push_back(ours ? mtpt::CellFractionLevel(ours->GetCellFraction(), 0.0) : 1.0);
    distances.push_back(ours ? ours->GetImageSampleDistance()
        : caster              ? caster->GetImageSampleDistance()
                              : 1.0);
  }
  const std::size_t median = MedianIndex(ms);
  r.medianMs = ms[median];
  r.volumeMs = volumeMs[median];
  r.fraction = fractions[median];
  r.distance = distances[median];
  // The user lets go: VTK's still rate, each kept view; the median of their errors.
  stage.GetWindow()->SetDesiredUpdateRate(0.0001);
  std::vector<double> errors;
  for (const auto& k : kept)
  {
    stage.GetRenderer()->GetActiveCamera()->DeepCopy(k->camera);
    stage.GetRenderer()->ResetCameraClippingRange();
    stage.Frame();
    errors.push_back(CoveredRmse(k->image, stage.Image(), look.background));
  }
  r.rmse = errors.empty() ? 0.0 : errors[MedianIndex(errors)];
  return r;
}

} // namespace

int main(int argc, char* argv[])
try
{
  Options o;
  CLI::App app{ "Moving frames at the rate the window asks for: time against the allotted "
                "time, and image error against the still frame of the same view." };
  app.add_option("--meshes", o.meshes, "scenes (Harness.h: wavelet, grid:N, bluntfin, comb, ...)");
  app.add_option("--sizes", o.sizes, "window sizes: 1024 (square) or 1920x1080, comma-separated");
  app.add_option("--rates", o.rates, "frames a second the window asks for, comma-separated");
  app.add_option("--contenders", o.contenders,
    "mtpt-cpu, mtpt-gl (MTPT's defaults), mtpt-cpu-distance, mtpt-gl-distance (the image "
    "sample distance adjusted alone), raycast (VTK's unstructured ray caster)");
  app.add_option("--frames", o.frames, "timed moving frames (median)")->check(CLI::PositiveNumber);
  app.add_option("--warm-up", o.warmUp, "untimed moving frames first")->check(CLI::PositiveNumber);
  app.add_option("--step", o.step, "degrees the camera turns before every frame");
  app.add_option("--threads", o.threads, "MTPT's threads (0: the default)");
  std::string multisampling = "on";
  app.add_option("--multisampling", multisampling, "on (VTK's default window) or off")
    ->check(CLI::IsMember({ "on", "off" }));
  app.add_option("--data", o.dataFolder, "folder of real meshes (default $MTPT_DATA_DIR)");
  app.add_option("--csv", o.csv, "append every figure to this CSV file");
  app.add_option("--plot", o.plot, "write moving-frame time against image error to this PNG");
  std::string fromCsv;
  app.add_option("--plot-from", fromCsv,
    "with --plot: draw the figures of this CSV (written by --csv) instead of measuring");
  CLI11_PARSE(app, argc, argv);
  o.multisampling = multisampling == "on";
  if (o.dataFolder.empty())
  {
    o.dataFolder = DefaultDataFolder();
  }
  std::vector<double> rates;
  for (const std::string& rate : SplitList(o.rates))
  {
    rates.push_back(std::stod(rate));
  }
  for (const std::string& name : SplitList(o.contenders))
  {
    if (!MakeContender(name, 0))
    {
      std::fprintf(stderr, "unknown contender '%s'\n", name.c_str());
      return 2;
    }
  }
  std::map<std::string, Series> series;
  if (!fromCsv.empty())
  {
    std::ifstream in(fromCsv);
    std::string line;
    while (std::getline(in, line))
    {
      // scene, cells, size, contender, rate, allotted ms, moving ms, volume ms, RMSE, ...
      const std::vector<std::string> f = SplitList(line);
      if (f.size() >= 9)
      {
        Series& s = series[f[0] + " " + f[3]];
        s.label = f[0] + ", " + ContenderLabel(f[3]);
        s.x.push_back(std::stod(f[6]));
        s.y.push_back(std::max(std::stod(f[8]), 0.1));
      }
    }
  }
  std::ofstream csv;
  if (!o.csv.empty())
  {
    csv.open(o.csv, std::ios::app);
  }
  const std::vector<std::string> meshes =
    fromCsv.empty() ? SplitList(o.meshes) : std::vector<std::string>{};
  for (const std::string& meshName : meshes)
  {
    Scene scene;
    std::string error;
    if (!LoadScene(meshName, o.dataFolder, scene, error))
    {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    auto property = MakeProperty(scene);
    for (const std::string& sizeText : SplitList(o.sizes))
    {
      int width = 0, height = 0;
      if (!ParseSize(sizeText, width, height))
      {
        std::fprintf(stderr, "bad size '%s'\n", sizeText.c_str());
        return 2;
      }
      std::printf("\n%s, %lld tetrahedra, %dx%d (%s), camera turning %.0f degrees per frame, "
                  "median of %d after %d\n\n",
        scene.name.c_str(), static_cast<long long>(scene.grid->GetNumberOfCells()), width, height,
        WindowName(o.multisampling), o.step, o.frames, o.warmUp);
      std::printf("| contender | asked (frames/s) | allotted ms | moving ms | moving / allotted "
                  "| of which the volume, ms | RMSE vs still (of 255) | cell fraction "
                  "| image sample distance |\n"
                  "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
      for (const std::string& name : SplitList(o.contenders))
      {
        for (double rate : rates)
        {
          const Result r = Run(scene, property, name, width, height, rate, o);
          const double allotted = 1e3 / rate;
          std::printf("| %s | %g | %.0f | %.1f | %.2f | %.1f | %.1f | %.3f | %.2f |\n",
            name.c_str(), rate, allotted, r.medianMs, r.medianMs / allotted, r.volumeMs, r.rmse,
            r.fraction, r.distance);
          std::fflush(stdout);
          if (csv)
          {
            csv << scene.name << ',' << scene.grid->GetNumberOfCells() << ',' << width << 'x'
                << height << ',' << name << ',' << rate << ',' << allotted << ',' << r.medianMs
                << ',' << r.volumeMs << ',' << r.rmse << ',' << r.fraction << ',' << r.distance
                << '\n';
          }
          Series& s = series[scene.name + " " + name];
          s.label = scene.name + ", " + ContenderLabel(name);
          s.x.push_back(r.medianMs);
          s.y.push_back(std::max(r.rmse, 0.1));
        }
      }
    }
  }
  if (fromCsv.empty())
  {
    std::printf("\npeak resident memory: %.0f MiB\n", StatusKiB("VmHWM") / 1024.0);
  }
  if (!o.plot.empty())
  {
    Chart chart;
    chart.title = "Moving frames: time against error, one point per rate asked (" + o.rates +
      " frames a second)";
    chart.xTitle = "median moving frame, ms";
    chart.yTitle = "covered RMSE against the still frame, of 255";
    chart.headroom = 4; // room for the legend above the points
    chart.legendRight = true;
    chart.lines = std::any_of(series.begin(), series.end(),
      [](const auto& entry) { return entry.second.x.size() > 1; }); // a line needs 2 points
    std::vector<Series> all;
    for (auto& entry : series)
    {
      all.push_back(entry.second);
    }
    std::string error;
    if (!WritePlot(o.plot, chart, all, error))
    {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    std::printf("plot: %s\n", o.plot.c_str());
  }
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_interactive", error);
}
