// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_frames: whole frames of vtkMultiThreadedProjectedTetrahedraMapper (CPU and
// OpenGL backends) against VTK's projected tetrahedra, ray-cast and Z-sweep unstructured
// mappers, on the same scenes in one run, with the camera turning before every timed frame
// (Harness.h states the rules). Per measurement: the median frame, for MTPT its stages and
// the CPU compositor's work (fragments, nanoseconds per fragment and core, binning against
// fragment work), and each image's difference from VTK's PT at the same final view. Every
// contender is timed in VTK's default window (multisampled) and single-sampled
// (--multisampling), and the ratios between VTK's mappers and MTPT take each at its faster
// window; --rounds repeats everything with the contenders alternating.
// --unchanged also times frames whose view does not change, as a separate column.
// --csv writes every figure; run under a display (Testing/xvfb-launch.sh without one).
// "gpu-raycast" (VTK's GPU ray caster) draws the scenes that have image data (the wavelet)
// and is left out of the others. --opengl-info prints OpenGL's vendor, renderer and version
// and exits; every run prints them first.
#include "Harness.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkImageData.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridVolumeMapper.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  CommonOptions common;
  std::string meshes = "wavelet,bluntfin";
  std::string sizes = "16,512,1024";
  std::string contenders = "mtpt-cpu,mtpt-gl,vtk-pt,raycast,zsweep";
  bool unchanged = false;
  bool openglInfo = false;
  std::string csv;
};

/// The image of VTK's PT that others are compared with: single-sampled when measured (VTK's
/// PT speckles along cell edges in a multisampled window), else its first window's.
const Measurement* ReferenceImage(const std::map<std::string, WindowMeasurements>& results)
{
  const auto pt = results.find("vtk-pt");
  if (pt == results.end())
  {
    return nullptr;
  }
  const Measurement* single = pt->second.In(false);
  return single ? single : &pt->second.measurements.front();
}

void PrintHeader(const Scene& scene, int width, int height, const Options& o)
{
  std::printf("\n%s, %lld tetrahedra, %dx%d, camera turning %.2f degrees per frame, median of %d "
              "(* one frame, slower than %.0f s)",
    scene.name.c_str(), static_cast<long long>(scene.grid->GetNumberOfCells()), width, height,
    o.common.timing.step, o.common.timing.repeat, o.common.timing.slowLimit);
  if (o.common.rounds > 1)
  {
    std::printf("; median round of %d, contenders and windows alternating", o.common.rounds);
  }
  std::printf("\n");
  if (o.common.desiredUpdateRate > 0)
  {
    std::printf("Windows ask for %g frames a second; MTPT adjusts its image sample distance "
                "(%d warm-up frames)\n",
      o.common.desiredUpdateRate, o.common.timing.warmUp);
  }
  else if (o.common.mapper.imageSampleDistance != 1.0f)
  {
    std::printf("MTPT's image sample distance: %g\n", o.common.mapper.imageSampleDistance);
  }
  std::printf("| contender | window | ms (moving) |%s VTK PT / this, same window | RMSE vs VTK "
              "PT | MTPT: CPU stages | composite (bin + raster) | upload + draw | fragments | ns "
              "per fragment x core |\n",
    o.unchanged ? " ms (unchanged view) |" : "");
  std::printf("|---|---|---:|%s---:|---:|---:|---:|---:|---:|---:|\n", o.unchanged ? "---:|" : "");
}

/// One row of the table (and of the CSV): `name` in window `w` of `m`.
void PrintRow(const Scene& scene, int width, int height, const std::string& name,
  const WindowMeasurements& m, std::size_t w, const std::map<std::string, WindowMeasurements>& all,
  const Options& o, int threads, std::ofstream& csv)
{
  const Measurement& r = m.measurements[w];
  const auto pt = all.find("vtk-pt");
  const Measurement* ptSame = pt != all.end() ? pt->second.In(m.windows[w]) : nullptr;
  const Measurement* reference = ReferenceImage(all);
  const double ratio = ptSame ? ptSame->moving.median / r.moving.median : 0;
  const double fastest =
    pt != all.end() ? pt->second.Fastest().moving.median / m.Fastest().moving.median : 0;
  const ImageError e = reference ? CompareImages(r.image, reference->image) : ImageError{};
  const StageFigures& f = r.mtpt;
  const double nsPerFragment = NsPerFragmentCore(f, threads);
  std::printf(
    "| %s | %s | %s |%s %.2fx | %.4f | %.1f | %.1f (%.1f + %.1f) | %.1f | %.0f | %.1f |\n",
    name.c_str(), WindowName(m.windows[w]), FormatMs(r.moving).c_str(),
    o.unchanged ? (" " + FormatMs(r.unchanged) + " |").c_str() : "", ratio, e.rmse, f.cpuStages,
    f.composite, f.bin, f.raster, f.upload + f.draw, f.fragments, nsPerFragment);
  if (csv)
  {
    csv << scene.name << ',' << scene.grid->GetNumberOfCells() << ',' << width << ',' << height
        << ',' << name << ',' << (m.windows[w] ? "on" : "off") << ',' << o.common.mapper.shading
        << ',' << r.moving.median << ',' << (r.moving.slow ? 1 : 0) << ',' << r.unchanged.median
        << ',' << ratio << ',' << fastest << ',' << e.rmse << ',' << e.worst << ',' << f.cpuStages
        << ',' << f.composite << ',' << f.bin << ',' << f.raster << ',' << f.upload << ',' << f.draw
        << ',' << f.fragments << ',' << nsPerFragment << ',' << f.sorted << ',' << f.pixelCulled
        << ',' << threads << '\n';
  }
}

/// The headline ratios: every VTK mapper against every MTPT contender, each at its faster
/// window.
void PrintRatios(
  const std::vector<std::string>& names, const std::map<std::string, WindowMeasurements>& results)
{
  for (const std::string& theirs : names)
  {
    if (theirs.rfind("mtpt", 0) == 0)
    {
      continue;
    }
    const WindowMeasurements& v = results.at(theirs);
    for (const std::string& ours : names)
    {
      if (ours.rfind("mtpt", 0) != 0)
      {
        continue;
      }
      const WindowMeasurements& m = results.at(ours);
      const Measurement &a = v.Fastest(), &b = m.Fastest();
      std::printf("%s / %s, each in its faster window: %s ms (%s) / %s ms (%s) = **%.2fx**",
        theirs.c_str(), ours.c_str(), FormatMs(a.moving).c_str(), WindowName(v.windows[v.Faster()]),
        FormatMs(b.moving).c_str(), WindowName(m.windows[m.Faster()]),
        a.moving.median / b.moving.median);
      for (std::size_t w = 0; w < m.windows.size() && m.windows.size() > 1; ++w)
      {
        const Measurement* same = v.In(m.windows[w]);
        if (same)
        {
          std::printf("%s%s %.2fx", w == 0 ? " (" : ", ", WindowName(m.windows[w]),
            same->moving.median / m.measurements[w].moving.median);
        }
      }
      std::printf("%s\n", m.windows.size() > 1 ? ")" : "");
    }
  }
}

void PrintScene(const Scene& scene, int width, int height, const std::vector<std::string>& names,
  const std::map<std::string, WindowMeasurements>& results, const Options& o, std::ofstream& csv)
{
  PrintHeader(scene, width, height, o);
  vtkNew<Mapper> probe;
  const int threads = probe->GetEffectiveNumberOfThreads();
  for (const std::string& name : names)
  {
    const WindowMeasurements& m = results.at(name);
    for (std::size_t w = 0; w < m.windows.size(); ++w)
    {
      PrintRow(scene, width, height, name, m, w, results, o, threads, csv);
    }
  }
  PrintRatios(names, results);
  const MapperSettings& mtpt = o.common.mapper;
  if (mtpt.autoAdjust || mtpt.imageSampleDistance != 1.0f)
  {
    for (const std::string& name : names)
    {
      const WindowMeasurements& m = results.at(name);
      for (std::size_t w = 0; w < m.windows.size(); ++w)
      {
        const StageFigures& f = m.measurements[w].mtpt;
        if (!f.backend.empty())
        {
          std::printf("%s, %s: the median frame composited at image sample distance %.2f (%d x "
                      "%d pixels)%s\n",
            name.c_str(), WindowName(m.windows[w]), f.imageSampleDistance, f.imageSize[0],
            f.imageSize[1],
            mtpt.autoAdjust ? ", adjusted to the window's desired update rate" : "");
        }
      }
    }
  }
}

} // namespace

int main(int argc, char* argv[])
try
{
  Options o;
  CLI::App app{ "Whole frames of MTPT's backends against VTK's unstructured-grid mappers, "
                "the camera turning before every timed frame." };
  AddCommonOptions(app, o.common);
  AddImageSamplingOptions(app, o.common);
  app.add_option("--meshes", o.meshes,
    "scenes (Harness.h: wavelet, grid:N, bluntfin, cubes, "
    "blocks, comb, kiefer, ...)");
  app.add_option("--sizes", o.sizes, "window sizes: 512 (square) or 1920x1080, comma-separated");
  app.add_option("--contenders", o.contenders,
    "mtpt-cpu, mtpt-gl, vtk-pt, raycast, zsweep, gpu-raycast (image data: the wavelet)");
  app.add_flag("--unchanged", o.unchanged, "also time frames whose view does not change");
  app.add_flag(
    "--opengl-info", o.openglInfo, "print OpenGL's vendor, renderer and version, and exit");
  app.add_option("--csv", o.csv, "append every figure to this CSV file");
  CLI11_PARSE(app, argc, argv);
  ApplyImageSamplingOptions(app, o.common);
  const OpenGLInfo gl = QueryOpenGL();
  std::printf("OpenGL vendor: %s\nOpenGL renderer: %s\nOpenGL version: %s\n", gl.vendor.c_str(),
    gl.renderer.c_str(), gl.version.c_str());
  if (o.openglInfo)
  {
    return 0;
  }

  std::vector<std::pair<int, int>> sizes;
  for (const std::string& text : SplitList(o.sizes))
  {
    int w = 0, h = 0;
    if (!ParseSize(text, w, h))
    {
      std::fprintf(stderr, "mtpt_bench_frames: not a window size: '%s'\n", text.c_str());
      return 2;
    }
    sizes.emplace_back(w, h);
  }
  const std::vector<std::string> names = SplitList(o.contenders);
  for (const std::string& name : names)
  {
    if (!MakeContender(name))
    {
      std::fprintf(stderr, "mtpt_bench_frames: unknown contender '%s'\n", name.c_str());
      return 2;
    }
  }
  std::ofstream csv;
  if (!o.csv.empty())
  {
    std::ifstream existing(o.csv);
    const bool header = !existing.good() || existing.peek() == std::ifstream::traits_type::eof();
    csv.open(o.csv, std::ios::app);
    if (header)
    {
      csv << "mesh,tetrahedra,width,height,contender,multisampling,shading,ms,slow,"
             "ms_unchanged,vtkpt_over_this_same_window,vtkpt_over_this_each_faster,rmse_vs_vtkpt,"
             "worst_vs_vtkpt,cpu_stages_ms,composite_ms,bin_ms,"
             "raster_ms,upload_ms,draw_ms,fragments,ns_per_fragment_core,sorted,pixel_culled,"
             "threads\n";
    }
  }
  std::printf("MTPT's CPU compositor runs %s here.\n", Mapper::GetCompositorInstructionSet());
  for (const std::string& meshName : SplitList(o.meshes))
  {
    Scene scene;
    std::string error;
    if (!LoadScene(meshName, o.common.dataFolder, scene, error))
    {
      std::fprintf(stderr, "mtpt_bench_frames: %s\n", error.c_str());
      return 1;
    }
    auto property = MakeProperty(scene);
    std::vector<std::string> drawn;
    for (const std::string& name : names)
    {
      if (DrawsImageData(name) && !scene.image)
      {
        std::printf(
          "%s: left out on %s, which has no image data\n", name.c_str(), meshName.c_str());
        continue;
      }
      drawn.push_back(name);
    }
    for (const auto& size : sizes)
    {
      const auto results =
        MeasureContenders(scene, property, drawn, size.first, size.second, o.common, o.unchanged);
      PrintScene(scene, size.first, size.second, drawn, results, o, csv);
      std::fflush(stdout);
      if (csv.is_open())
      {
        csv.flush(); // a run cut short keeps every scene it finished
      }
    }
  }
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_frames", error);
}
