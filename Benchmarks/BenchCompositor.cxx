// SPDX-License-Identifier: BSD-3-Clause
/**
 * mtpt_bench_compositor: the CPU backend's frame without VTK or a window: the core's CPU
 * stages, the fans (DecomposeFans) and the CPU compositor (binning, rasterization, resolve),
 * on a generated grid of about the wavelet's size (1.08M tetrahedra by default), in a
 * perspective view that turns before every frame, with the frame benchmark's transfer
 * functions (cool-warm colours, opacity rising linearly over the scalars, unit distance a
 * fiftieth of the diagonal) and an opaque depth of 1 everywhere, as the CPU backend reads it
 * back from an empty window. Prints a Markdown table of medians per image size: stage times,
 * fragments, nanoseconds per covered fragment and core (every fragment the fans cover,
 * counted in a frame of the same view whose table makes nothing opaque: the compositor skips
 * fans and fragments behind opaque pixels, and counts only the fans it draws), tetrahedra
 * per second of the CPU stages.
 *
 * Without VTK and X it runs the same under a profiler (valgrind --tool=callgrind, perf) as
 * alone; the frame benchmark (BenchFrames.cxx) measures whole frames against VTK's mappers.
 *
 * --floor measures instead the fragment loop's floor and the rungs above it
 * (FragmentFloor.h; Documentation/compositor.md, "The floor"), on one thread, with every
 * instruction set this processor runs, beside the frame's nanoseconds per covered fragment
 * with the same instruction set. --instruction-set runs everything with one instruction set.
 *
 * --coverage adds a table of the fans by the pixel centres each covers (FanCoverage.h), from
 * the frame with nothing opaque, and of them the quadrilateral projections; the centres'
 * sum must be the compositor's count of the fragments covered in that frame, or the
 * program says so and exits with 1.
 */
#include "Camera.h"
#include "FanCoverage.h"
#include "FragmentFloor.h"
#include "Statistics.h"
#include "TetrahedralGrid.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/Threads.h"
#include "mtpt/Timing.h"

#include <CLI/CLI.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace
{

using mtpt::Matrix4;
using mtpt::bench::Median;
using mtpt::bench::LookAt;
using mtpt::bench::Perspective;
using mtpt::bench::Vec3;

struct Options
{
  long long tetrahedra = 1080000;
  std::vector<int> sizes = { 512, 1024 };
  int frames = 5;
  int threads = 0;
  double step = 1.0;
  std::string shading = "vtk";
  double attenuation = 1.0; ///< the table's attenuations times this
  bool floor = false;
  bool coverage = false;      ///< count the pixel centres each fan covers
  std::string instructionSet; ///< empty: the best this processor has
};

/// The view of frame `frame`: the grid (within [-1, 1]^3) filling a 30 degree view from an
/// oblique direction (azimuth 30, elevation 20, as the frame benchmark starts), turned by
/// `step` degrees of azimuth per frame.
void SetView(mtpt::FrameInput& input, int frame, double step)
{
  const double pi = 3.14159265358979323846;
  const double azimuth = (30.0 + step * frame) * pi / 180, elevation = 20.0 * pi / 180;
  const double distance = std::sqrt(3.0) / std::sin(15.0 * pi / 180);
  const Vec3 eye = { distance * std::cos(elevation) * std::sin(azimuth),
    distance * std::sin(elevation), distance * std::cos(elevation) * std::cos(azimuth) };
  input.modelView = LookAt(eye, { 0, 0, 0 }, { 0, 1, 0 });
  input.projection = Perspective(30, 1, distance - 2, distance + 2);
  input.perspective = true;
}

/// The frame benchmark's transfer functions (Harness.cxx, MakeProperty) as a table over
/// the scalars' range [0, 1]: cool-warm colours, opacity 0 -> `opacity`.
std::vector<float> Table(int entries, double opacity)
{
  std::vector<float> table;
  for (int i = 0; i < entries; ++i)
  {
    const float t = i / (entries - 1.0f), u = t < 0.5f ? 2 * t : 2 * t - 1;
    const float low[3] = { 0.23f, 0.30f, 0.75f }, mid[3] = { 0.87f, 0.87f, 0.87f },
                high[3] = { 0.71f, 0.02f, 0.15f };
    for (int c = 0; c < 3; ++c)
    {
      table.push_back(t < 0.5f ? low[c] + u * (mid[c] - low[c]) : mid[c] + u * (high[c] - mid[c]));
    }
    table.push_back(static_cast<float>(t * opacity));
  }
  return table;
}

struct FrameFigures
{
  double stages = 0, decompose = 0, bin = 0, raster = 0, resolve = 0, total = 0;
  double fragments = 0, hidden = 0, vectors = 0;
};

FrameFigures Frame(mtpt::FramePipeline& pipeline, mtpt::Compositor& compositor,
  mtpt::FrameInput& input, const mtpt::CompositeSettings& settings, std::vector<float>& image,
  int threads)
{
  FrameFigures f;
  const auto start = mtpt::Clock::now();
  pipeline.Prepare(input, threads);
  pipeline.DecomposeFans(0, pipeline.SortedCount(), threads);
  const mtpt::StageTimes& times = pipeline.Times();
  f.stages = 1e3 * times.Total();
  f.decompose = 1e3 * times.decompose;
  compositor.Begin(settings);
  compositor.Composite(pipeline.Fans().data(), pipeline.FanCount(), threads);
  const mtpt::PixelRegion region{ 0, 0, settings.width, settings.height };
  compositor.Resolve(region, nullptr, image.data(), threads);
  f.total = 1e3 * mtpt::SecondsSince(start);
  const mtpt::CompositorStats& stats = compositor.Stats();
  f.bin = 1e3 * stats.binSeconds;
  f.raster = 1e3 * stats.rasterSeconds;
  f.resolve = 1e3 * stats.resolveSeconds;
  f.fragments = static_cast<double>(stats.fragments);
  f.hidden = static_cast<double>(stats.hiddenFans);
  f.vectors = static_cast<double>(stats.fanVectors);
  return f;
}

/// `table` with its attenuations divided by 10^6: no pixel becomes opaque, so the compositor
/// counts every covered fragment (and culling, by zero opacity, keeps the same cells).
std::vector<float> Faint(std::vector<float> table)
{
  for (std::size_t i = 3; i < table.size(); i += 4)
  {
    table[i] *= 1e-6f;
  }
  return table;
}

/// The medians of a size's timed frames, and every fragment its fans cover (counted with
/// nothing opaque).
struct SizeFigures
{
  FrameFigures median;
  double covered = 0;        ///< every fragment covered, with nothing opaque
  double coveredVectors = 0; ///< the fan path's vectors then
  /// --coverage: the fans of that frame by the pixel centres each covers (FanCoverage.h).
  mtpt::bench::CoverageHistogram coverage;

  /// The rasterization's time per covered fragment and core.
  double NanosecondsPerFragment(int threads) const
  {
    return this->covered > 0 ? 1e6 * this->median.raster * threads / this->covered : 0;
  }
};

/// The pixel centres each of the pipeline's fans covers in a size x size image, counted by
/// `threads` threads, a range of the fans each, into `result`.
void CountCentres(const mtpt::FramePipeline& pipeline, int size, int threads, SizeFigures& result)
{
  const mtpt::Fan* fans = pipeline.Fans().data();
  const std::size_t count = pipeline.FanCount();
  std::vector<mtpt::bench::CoverageHistogram> parts(static_cast<std::size_t>(threads));
  std::vector<std::thread> team;
  for (int t = 0; t < threads; ++t)
  {
    team.emplace_back(
      [&, t]
      {
        const std::size_t first = count * t / threads, end = count * (t + 1) / threads;
        mtpt::bench::CountCoveredCentres(
          fans + first, end - first, size, size, parts[static_cast<std::size_t>(t)]);
      });
  }
  for (std::thread& member : team)
  {
    member.join();
  }
  for (const mtpt::bench::CoverageHistogram& part : parts)
  {
    result.coverage.Add(part);
  }
}

/// `o.frames` timed frames of `mesh` at size x size after one warm-up, the view turning.
SizeFigures MeasureSize(const mtpt::bench::TetMesh& mesh, int size, const Options& o, int threads)
{
  const std::vector<float> table = Table(256, o.attenuation), faint = Faint(table);
  mtpt::FrameInput input;
  input.points = mesh.Points();
  input.cells = mesh.Cells();
  input.scalars = mesh.Scalars();
  input.opacity = { table.data(), 256, 0.0, 1.0 };
  mtpt::CompositeSettings settings;
  settings.width = settings.height = size;
  settings.transferFunction = input.opacity;
  settings.unitDistance = 2 * std::sqrt(3.0) / 50;
  mtpt::PreIntegrationTable integrals;
  if (o.shading == "pre-integrated")
  {
    integrals.Build(settings.transferFunction);
    settings.UsePreIntegration(integrals, mtpt::PerspectiveInterpolation{});
  }
  const std::vector<float> depth(static_cast<std::size_t>(size) * size, 1.0f);
  settings.opaqueDepth = depth.data();
  std::vector<float> image(4 * static_cast<std::size_t>(size) * size);
  input.imageSize = { size, size };
  mtpt::FramePipeline pipeline;
  pipeline.SetReuse(true);
  mtpt::Compositor compositor;
  std::vector<FrameFigures> figures;
  for (int frame = 0; frame <= o.frames; ++frame)
  {
    SetView(input, frame, o.step);
    if (o.shading == "pre-integrated")
    {
      settings.interpolation = mtpt::PerspectiveInterpolation::FromProjection(input.projection);
    }
    const FrameFigures f = Frame(pipeline, compositor, input, settings, image, threads);
    if (frame > 0)
    {
      figures.push_back(f);
    }
  }
  SizeFigures result;
  auto median = [&](double FrameFigures::*field)
  {
    std::vector<double> values;
    for (const FrameFigures& f : figures)
    {
      values.push_back(f.*field);
    }
    return Median(values);
  };
  for (double FrameFigures::*field : { &FrameFigures::stages, &FrameFigures::decompose,
         &FrameFigures::bin, &FrameFigures::raster, &FrameFigures::resolve, &FrameFigures::total,
         &FrameFigures::fragments, &FrameFigures::hidden })
  {
    result.median.*field = median(field);
  }
  // Every covered fragment, counted at the first timed frame's view with nothing opaque.
  mtpt::CompositeSettings faintSettings = settings;
  faintSettings.transferFunction.table = faint.data();
  SetView(input, 1, o.step);
  if (o.shading == "pre-integrated")
  {
    faintSettings.interpolation = mtpt::PerspectiveInterpolation::FromProjection(input.projection);
  }
  const FrameFigures all = Frame(pipeline, compositor, input, faintSettings, image, threads);
  result.covered = all.fragments;
  result.coveredVectors = all.vectors;
  if (o.coverage)
  {
    CountCentres(pipeline, size, threads, result);
  }
  return result;
}

std::string Join(const std::vector<std::string>& items)
{
  std::string text;
  for (const std::string& item : items)
  {
    text += (text.empty() ? "" : ", ") + item;
  }
  return text;
}

/**
 * --floor: per instruction set, the nanoseconds per fragment of each rung of the floor
 * (FragmentFloor, 2^22 vectors, the median of 5 runs), and the frame's rasterization
 * per covered fragment at 1024x1024, all on one thread; for the frame with nothing opaque,
 * how full the fan path's vectors are, what its vectors would cost at the top rung's rate,
 * and the rest: what the fans' set-up and the triangle path cost per covered fragment.
 */
int Floor(const mtpt::bench::TetMesh& mesh, const Options& o)
{
  static const char* const rungs[mtpt::bench::FragmentFloorRungs] = { "registers (the floor)",
    "+ memory", "+ planes", "+ lane lookups", "+ coverage" };
  constexpr int T = mtpt::TileSize;
  std::vector<float> rgba(4 * T * T, 0.0f), depth(T * T, 1.0f);
  std::printf("The fragment loop's floor and its rungs, one thread, ns per fragment (every lane "
              "a fragment); the frame: %zu tetrahedra at 1024x1024, ns per covered fragment\n\n"
              "| instruction set | lanes |",
    mesh.CellCount());
  for (const char* rung : rungs)
  {
    std::printf(" %s |", rung);
  }
  std::printf(" frame, opaque where it becomes so | frame, nothing opaque | its vectors' lanes "
              "covered | its vectors at the top rung's rate | the rest: set-up, triangle path |"
              "\n|---|---:|");
  for (int r = 0; r <= mtpt::bench::FragmentFloorRungs + 4; ++r)
  {
    std::printf("---:|");
  }
  std::printf("\n");
  const std::vector<std::string> sets =
    o.instructionSet.empty() ? mtpt::Compositor::InstructionSets()
                             : std::vector<std::string>{ o.instructionSet };
  for (const std::string& set : sets)
  {
    mtpt::Compositor::UseInstructionSet(set);
    const std::size_t lanes = mtpt::bench::FragmentLanes();
    std::printf("| %s | %zu |", set.c_str(), lanes);
    const std::size_t vectors = std::size_t{ 1 } << 22;
    float sink = 0;
    double top = 0;
    for (int r = 0; r < mtpt::bench::FragmentFloorRungs; ++r)
    {
      std::vector<double> ns;
      for (int run = 0; run < 5; ++run)
      {
        const auto start = mtpt::Clock::now();
        sink += mtpt::bench::FragmentFloor(r, vectors, rgba.data(), depth.data());
        ns.push_back(1e9 * mtpt::SecondsSince(start) / (vectors * lanes));
      }
      top = Median(ns);
      if (lanes > 1)
      {
        std::printf(" %.2f |", top);
      }
      else
      {
        std::printf(" - |");
      }
    }
    SizeFigures f;
    for (double attenuation : { o.attenuation, 0.01 })
    {
      Options frame = o;
      frame.attenuation = attenuation;
      f = MeasureSize(mesh, 1024, frame, 1);
      std::printf(" %.2f |", f.NanosecondsPerFragment(1));
    }
    const double slots = f.coveredVectors * static_cast<double>(lanes);
    const double loop = f.covered > 0 && lanes > 1 ? top * slots / f.covered : 0;
    std::printf(" %.0f%% | %.2f | %.2f |", slots > 0 ? 100 * f.covered / slots : 0, loop,
      f.NanosecondsPerFragment(1) - loop);
    std::printf("%s\n", sink == 12345.0f ? " " : "");
    std::fflush(stdout);
  }
  mtpt::Compositor::UseInstructionSet("");
  return 0;
}

/// One row of the --coverage table: `fans[c]` as shares of `total`.
void PrintCoverageRow(int size, const char* which, const std::size_t* fans, std::size_t total)
{
  std::size_t these = 0;
  for (int c = 0; c < mtpt::bench::CoverageBins; ++c)
  {
    these += fans[c];
  }
  std::printf("| %dx%d | %s | %zu |", size, size, which, these);
  for (int c = 0; c < mtpt::bench::CoverageBins; ++c)
  {
    std::printf(" %.1f%% |", total > 0 ? 100.0 * fans[c] / total : 0.0);
  }
  std::printf("\n");
}

/// --coverage: the table of the fans by the pixel centres each covers, per image size, and
/// of them the quadrilateral projections (shares of all fans with triangles); 1 (with a
/// message) where the count disagrees with the compositor's covered fragments.
int PrintCoverage(const std::vector<int>& sizes, const std::vector<SizeFigures>& figures)
{
  constexpr int bins = mtpt::bench::CoverageBins;
  std::printf("\nThe fans by the pixel centres each covers, at the first timed frame's view, as "
              "shares of the fans with triangles:\n\n"
              "| image | fans | how many |");
  for (int c = 0; c < bins; ++c)
  {
    std::printf(c + 1 < bins ? " %d |" : " %d or more |", c);
  }
  std::printf("\n|---|---|---:|");
  for (int c = 0; c < bins; ++c)
  {
    std::printf("---:|");
  }
  std::printf("\n");
  int status = 0;
  for (std::size_t i = 0; i < figures.size(); ++i)
  {
    const mtpt::bench::CoverageHistogram& h = figures[i].coverage;
    std::size_t fans = 0;
    for (int c = 0; c < bins; ++c)
    {
      fans += h.fans[c];
    }
    PrintCoverageRow(sizes[i], "with triangles", h.fans, fans);
    PrintCoverageRow(sizes[i], "of them with 4 corners", h.quadrilaterals, fans);
    if (static_cast<double>(h.centres) != figures[i].covered)
    {
      std::fprintf(stderr,
        "mtpt_bench_compositor: at %dx%d the fans cover %zu pixel centres by this count, but "
        "the compositor drew %.0f fragments of them\n",
        sizes[i], sizes[i], h.centres, figures[i].covered);
      status = 1;
    }
  }
  return status;
}

} // namespace

int main(int argc, char* argv[])
{
  Options o;
  CLI::App app{ "The CPU backend's frame without VTK: CPU stages, fans and the CPU compositor "
                "on a generated grid, the view turning before every frame." };
  app.add_option("--tets", o.tetrahedra, "tetrahedra of the generated grid, at least")
    ->check(CLI::PositiveNumber);
  app.add_option("--sizes", o.sizes, "square image sizes, comma-separated")
    ->delimiter(',')
    ->check(CLI::Range(1, 16384));
  app.add_option("--frames", o.frames, "timed frames per size (median), after one warm-up")
    ->check(CLI::PositiveNumber);
  app.add_option("--threads", o.threads, "threads (0: the default)")->check(CLI::NonNegativeNumber);
  app.add_option("--step", o.step, "degrees the view turns before every frame");
  app.add_option("--shading", o.shading, "vtk or pre-integrated")
    ->check(CLI::IsMember({ "vtk", "pre-integrated" }));
  app
    .add_option("--attenuation", o.attenuation,
      "the opacity ramp's top (1: opaque pixels behind most of the image; 0.01: nearly none)")
    ->check(CLI::PositiveNumber);
  app.add_flag("--coverage", o.coverage,
    "also the fans by the pixel centres each covers, and the quadrilaterals among them, at the "
    "view of the first timed frame (checked against the compositor's count of covered "
    "fragments)");
  app.add_flag("--floor", o.floor,
    "the fragment loop's floor and its rungs, with every instruction set, on one thread");
  app
    .add_option("--instruction-set", o.instructionSet,
      "run with this instruction set (" + Join(mtpt::Compositor::InstructionSets()) + ")")
    ->check(CLI::IsMember(mtpt::Compositor::InstructionSets()));
  CLI11_PARSE(app, argc, argv);
  mtpt::Compositor::UseInstructionSet(o.instructionSet);

  mtpt::bench::GridOptions grid;
  grid.cells = mtpt::bench::GridCellsForTetrahedra(
    static_cast<std::size_t>(o.tetrahedra), mtpt::bench::HexSplit::Five);
  grid.jitter = 0.3 * mtpt::bench::MaxJitter(grid.split);
  const mtpt::bench::TetMesh mesh = mtpt::bench::GenerateTetrahedralGrid(grid);
  if (o.floor)
  {
    return Floor(mesh, o);
  }
  const int threads = mtpt::ResolveThreadCount(o.threads);
  std::printf("Generated grid, %zu tetrahedra, %d threads, %s shading, opacity 0 -> %g, the view "
              "turning %.1f degrees before each frame; median of %d frames (ms); compositor %s\n\n",
    mesh.CellCount(), threads, o.shading.c_str(), o.attenuation, o.step, o.frames,
    mtpt::Compositor::InstructionSet());
  std::printf("| image | CPU stages | of which decompose | Mtets/s (CPU stages) | bin | raster | "
              "resolve | frame | fragments covered | of the fans drawn | fans skipped behind "
              "opaque pixels | ns per covered fragment x core |\n"
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<SizeFigures> figures;
  for (int size : o.sizes)
  {
    const SizeFigures f = MeasureSize(mesh, size, o, threads);
    figures.push_back(f);
    std::printf(
      "| %dx%d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.0f | %.0f | %.0f | %.1f |\n",
      size, size, f.median.stages, f.median.decompose, 1e-3 * mesh.CellCount() / f.median.stages,
      f.median.bin, f.median.raster, f.median.resolve, f.median.total, f.covered,
      f.median.fragments, f.median.hidden, f.NanosecondsPerFragment(threads));
    std::fflush(stdout);
  }
  return o.coverage ? PrintCoverage(o.sizes, figures) : 0;
}
