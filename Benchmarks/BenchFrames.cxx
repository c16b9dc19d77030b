// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_frames: whole frames of vtkMultiThreadedProjectedTetrahedraMapper (CPU and
// OpenGL backends) against VTK's projected tetrahedra, ray-cast and Z-sweep unstructured
// mappers, on the same scenes in one run, with the camera turning before every timed frame
// (Harness.h states the rules). Per measurement: the median frame, for MTPT its stages and
// the CPU compositor's work (fragments, nanoseconds per fragment and core, binning against
// fragment work), and each image's difference from VTK's PT at the same final view.
// --unchanged also times frames whose view does not change, as a separate column.
// --csv writes every figure; run under a display (Testing/xvfb-launch.sh without one).
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
  std::string csv;
};

void PrintScene(const Scene& scene, int width, int height, const std::vector<std::string>& names,
  std::map<std::string, Measurement>& results, const Options& o, std::ofstream& csv)
{
  const Measurement* pt = results.count("vtk-pt") ? &results["vtk-pt"] : nullptr;
  std::printf("\n%s, %lld tetrahedra, %dx%d, camera turning %.2f degrees per frame, median of %d "
              "(* one frame, slower than %.0f s)\n",
    scene.name.c_str(), static_cast<long long>(scene.grid->GetNumberOfCells()), width, height,
    o.common.timing.step, o.common.timing.repeat, o.common.timing.slowLimit);
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
  std::printf("| contender | ms (moving) |%s VTK PT / this | RMSE vs VTK PT | MTPT: CPU stages | "
              "composite (bin + raster) | upload + draw | fragments | ns per fragment x core |\n",
    o.unchanged ? " ms (unchanged view) |" : "");
  std::printf("|---|---:|%s---:|---:|---:|---:|---:|---:|---:|\n", o.unchanged ? "---:|" : "");
  vtkNew<Mapper> probe;
  const int threads = probe->GetEffectiveNumberOfThreads();
  for (const std::string& name : names)
  {
    Measurement& m = results[name];
    const double ratio = pt ? pt->moving.median / m.moving.median : 0;
    const ImageError e = pt ? CompareImages(m.image, pt->image) : ImageError{};
    const double nsPerFragment = m.mtpt.fragments > 0 ? 1e6 * m.mtpt.raster * threads / m.mtpt.fragments : 0;
    std::printf("| %s | %s |%s %.2fx | %.4f | %.1f | %.1f (%.1f + %.1f) | %.1f | %.0f | %.1f |\n",
      name.c_str(), FormatMs(m.moving).c_str(),
      o.unchanged ? (" " + FormatMs(m.unchanged) + " |").c_str() : "", ratio, e.rmse, m.mtpt.cpuStages,
      m.mtpt.composite, m.mtpt.bin, m.mtpt.raster, m.mtpt.upload + m.mtpt.draw, m.mtpt.fragments, nsPerFragment);
    if (csv)
    {
      csv << scene.name << ',' << scene.grid->GetNumberOfCells() << ',' << width << ',' << height
          << ',' << name << ',' << o.common.mapper.shading << ',' << m.moving.median << ','
          << (m.moving.slow ? 1 : 0) << ',' << m.unchanged.median << ',' << ratio << ','
          << e.rmse << ',' << e.worst << ',' << m.mtpt.cpuStages << ',' << m.mtpt.composite << ',' << m.mtpt.bin
          << ',' << m.mtpt.raster << ',' << m.mtpt.upload << ',' << m.mtpt.draw << ',' << m.mtpt.fragments << ','
          << nsPerFragment << ',' << m.mtpt.sorted << ',' << m.mtpt.pixelCulled << ',' << threads << '\n';
    }
  }
  const MapperSettings& mtpt = o.common.mapper;
  if (mtpt.autoAdjust || mtpt.imageSampleDistance != 1.0f)
  {
    for (const std::string& name : names)
    {
      const Measurement& m = results[name];
      if (!m.mtpt.backend.empty())
      {
        std::printf("%s: the median frame composited at image sample distance %.2f (%d x %d "
                    "pixels)%s\n",
          name.c_str(), m.mtpt.imageSampleDistance, m.mtpt.imageSize[0], m.mtpt.imageSize[1],
          mtpt.autoAdjust ? ", adjusted to the window's desired update rate" : "");
      }
    }
  }
}

} // namespace

int main(int argc, char* argv[])
{
  Options o;
  CLI::App app{ "Whole frames of MTPT's backends against VTK's unstructured-grid mappers, "
                "the camera turning before every timed frame." };
  AddCommonOptions(app, o.common);
  AddImageSamplingOptions(app, o.common);
  app.add_option("--meshes", o.meshes, "scenes (Harness.h: wavelet, grid:N, bluntfin, cubes, "
                                       "blocks, comb, kiefer, ...)");
  app.add_option("--sizes", o.sizes, "window sizes: 512 (square) or 1920x1080, comma-separated");
  app.add_option("--contenders", o.contenders, "mtpt-cpu, mtpt-gl, vtk-pt, raycast, zsweep");
  app.add_flag("--unchanged", o.unchanged, "also time frames whose view does not change");
  app.add_option("--csv", o.csv, "append every figure to this CSV file");
  CLI11_PARSE(app, argc, argv);
  ApplyImageSamplingOptions(app, o.common);

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
    if (!MakeMapper(name))
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
      csv << "mesh,tetrahedra,width,height,contender,shading,ms,slow,ms_unchanged,"
             "vtkpt_over_this,rmse_vs_vtkpt,worst_vs_vtkpt,cpu_stages_ms,composite_ms,bin_ms,"
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
    for (const auto& size : sizes)
    {
      std::map<std::string, Measurement> results;
      // VTK's PT first: the others' images are compared with it.
      if (results.count("vtk-pt") == 0 && std::find(names.begin(), names.end(), "vtk-pt") != names.end())
      {
        results["vtk-pt"] = Measure(scene, property, "vtk-pt", size.first, size.second, o.common, o.unchanged);
      }
      for (const std::string& name : names)
      {
        if (!results.count(name))
        {
          results[name] = Measure(scene, property, name, size.first, size.second, o.common, o.unchanged);
        }
      }
      PrintScene(scene, size.first, size.second, names, results, o, csv);
      std::fflush(stdout);
    }
  }
  return 0;
}
