// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_volumes: what drawing several volumes in one visibility order costs. For each
// mesh, in a --size window on MTPT's CPU backend, the camera turning before every timed frame
// (Harness.h), in each kind of window (--multisampling):
// - "one": one volume of the mesh's n tetrahedra;
// - "together": the mesh split into two volumes of n/2 (its cells in --slabs slabs of equal
//   counts along x, in turn, each volume with its own points and its own vtkVolumeProperty
//   of the same functions), drawn by the first volume's mapper in one order
//   (CompositeWithOtherVolumes, the default);
// - "apart": the same two volumes drawn one after the other (CompositeWithOtherVolumes off),
//   as VTK draws volumes.
// The three alternate over --rounds rounds; each result is its median round. Prints a
// Markdown table per mesh and window: the median frames, "together" over "one" (the cost of
// the grouping), and the covered-pixel RMSE of each two-volume image against the one-volume
// image of the same view (0 for "together" up to the order of cells at equal depth). Writes
// several_volumes.csv to --out.
#include "Harness.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
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
  std::string meshes = "grid:1000000,bluntfin";
  std::string size = "1024";
  int slabs = 6;
  std::string out = ".";
};

/// Each cell's centre along x.
std::vector<double> CentresX(vtkUnstructuredGrid* grid)
{
  std::vector<double> centres(static_cast<std::size_t>(grid->GetNumberOfCells()));
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    grid->GetCellPoints(c, ids);
    double sum = 0;
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
    {
      sum += grid->GetPoint(ids->GetId(k))[0];
    }
    centres[static_cast<std::size_t>(c)] = sum / std::max<vtkIdType>(ids->GetNumberOfIds(), 1);
  }
  return centres;
}

/// The cells of the scene's grid in slabs `parity` (0 or 1) of `slabs` slabs along x of equal
/// cell counts (by their centres), with their own points and the scene's scalars: one of two
/// interleaved halves.
vtkSmartPointer<vtkUnstructuredGrid> Half(
  const Scene& scene, const std::vector<double>& centres, int slabs, int parity)
{
  vtkUnstructuredGrid* grid = scene.grid;
  std::vector<double> sorted = centres;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> walls; // the slabs' upper ends but the last's
  for (int k = 1; k < slabs; ++k)
  {
    walls.push_back(sorted[sorted.size() * static_cast<std::size_t>(k) / slabs]);
  }
  vtkDataArray* scalars = grid->GetPointData()->GetArray(scene.arrayName.c_str());
  if (!scalars)
  {
    scalars = grid->GetPointData()->GetScalars();
  }
  auto half = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  points->SetDataType(grid->GetPoints()->GetDataType());
  auto values = vtkSmartPointer<vtkDataArray>::Take(scalars->NewInstance());
  values->SetName(scalars->GetName());
  values->SetNumberOfComponents(scalars->GetNumberOfComponents());
  std::vector<vtkIdType> newId(static_cast<std::size_t>(grid->GetNumberOfPoints()), -1);
  vtkNew<vtkCellArray> cells;
  vtkNew<vtkUnsignedCharArray> types;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    const double centre = centres[static_cast<std::size_t>(c)];
    const auto slab = std::upper_bound(walls.begin(), walls.end(), centre) - walls.begin();
    if (slab % 2 != parity)
    {
      continue;
    }
    grid->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
    {
      vtkIdType& id = newId[static_cast<std::size_t>(ids->GetId(k))];
      if (id < 0)
      {
        id = points->InsertNextPoint(grid->GetPoint(ids->GetId(k)));
        values->InsertNextTuple(ids->GetId(k), scalars);
      }
      ids->SetId(k, id);
    }
    cells->InsertNextCell(ids);
    types->InsertNextValue(static_cast<unsigned char>(grid->GetCellType(c)));
  }
  half->SetPoints(points);
  half->SetCells(types, cells);
  half->GetPointData()->SetScalars(values);
  return half;
}

/// Times `arrangement` ("one", "together" or "apart") of `scene` in one window kind.
Measurement MeasureArrangement(const Scene& scene, const Scene (&halves)[2],
  const std::string& arrangement, int width, int height, bool multisampling,
  const CommonOptions& options)
{
  StageOptions stageOptions;
  stageOptions.multisampling = multisampling;
  Measurement m;
  auto first = MakeMapper("mtpt-cpu", options.mapper);
  auto property = MakeProperty(scene);
  if (arrangement == "one")
  {
    Stage stage(scene, property, first, width, height, stageOptions);
    m.moving = TimeFrames(stage, options.timing);
    m.image = stage.Image();
    return m;
  }
  const bool together = arrangement == "together";
  auto second = MakeMapper("mtpt-cpu", options.mapper);
  static_cast<Mapper*>(first.Get())->SetCompositeWithOtherVolumes(together);
  static_cast<Mapper*>(second.Get())->SetCompositeWithOtherVolumes(together);
  Stage stage(halves[0], property, first, width, height, stageOptions);
  second->SetInputDataObject(halves[1].grid);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(second);
  auto otherProperty = MakeProperty(scene); // the same functions, another object
  volume->SetProperty(otherProperty);
  stage.GetRenderer()->AddVolume(volume);
  m.moving = TimeFrames(stage, options.timing);
  m.image = stage.Image();
  second->ReleaseGraphicsResources(stage.GetWindow());
  return m;
}

/// RMSE over the pixels either image covers (differs from the white background).
double CoveredRmse(vtkImageData* a, vtkImageData* b)
{
  auto* pa = a->GetPointData()->GetScalars();
  auto* pb = b->GetPointData()->GetScalars();
  double sum = 0;
  long long count = 0;
  for (vtkIdType i = 0; i < pa->GetNumberOfTuples(); ++i)
  {
    bool covered = false;
    double squared = 0;
    for (int c = 0; c < 3; ++c)
    {
      const double x = pa->GetComponent(i, c) / 255.0, y = pb->GetComponent(i, c) / 255.0;
      covered = covered || x < 1.0 - 2.0 / 255 || y < 1.0 - 2.0 / 255;
      squared += (x - y) * (x - y);
    }
    if (covered)
    {
      sum += squared / 3.0;
      ++count;
    }
  }
  return count ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

} // namespace

int main(int argc, char** argv)
{
  Options options;
  CLI::App app{ "mtpt_bench_volumes: two volumes of n/2 tetrahedra drawn in one visibility "
                "order against one volume of n, and drawn one after the other" };
  AddCommonOptions(app, options.common);
  app.add_option("--meshes", options.meshes, "comma-separated scenes (Harness.h: LoadScene)")
    ->capture_default_str();
  app.add_option("--size", options.size, "window size: 1024 or 1920x1080")->capture_default_str();
  app.add_option("--slabs", options.slabs, "slabs of cells along x, given to the volumes in turn")
    ->check(CLI::Range(2, 1000))
    ->capture_default_str();
  app.add_option("--out", options.out, "folder of several_volumes.csv")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  int width = 0, height = 0;
  if (!ParseSize(options.size, width, height))
  {
    std::fprintf(stderr, "mtpt_bench_volumes: --size %s is not a window size\n",
      options.size.c_str());
    return 1;
  }
  const std::string csvPath = options.out + "/several_volumes.csv";
  std::ofstream csv(csvPath);
  if (!csv)
  {
    std::fprintf(stderr, "mtpt_bench_volumes: cannot write %s\n", csvPath.c_str());
    return 1;
  }
  csv << "mesh,tetrahedra,window,one_ms,together_ms,apart_ms,together_over_one,"
         "together_rmse,apart_rmse\n";
  const std::vector<std::string> arrangements = { "one", "together", "apart" };
  try
  {
    for (const std::string& name : SplitList(options.meshes))
    {
      Scene scene;
      std::string error;
      if (!LoadScene(name, options.common.dataFolder, scene, error))
      {
        std::fprintf(stderr, "mtpt_bench_volumes: %s\n", error.c_str());
        return 1;
      }
      if (scene.cellScalars || scene.blocks || !scene.grid->GetPointData()->GetScalars())
      {
        std::fprintf(stderr, "mtpt_bench_volumes: %s: needs one grid with point scalars\n",
          name.c_str());
        return 1;
      }
      Scene halves[2] = { scene, scene };
      const std::vector<double> centres = CentresX(scene.grid);
      for (int h = 0; h < 2; ++h)
      {
        halves[h].grid = Half(scene, centres, options.slabs, h);
      }
      const vtkIdType n = scene.grid->GetNumberOfCells();
      std::printf("\n%s: %lld tetrahedra; halves of %lld and %lld; %dx%d, CPU backend\n\n",
        name.c_str(), static_cast<long long>(n),
        static_cast<long long>(halves[0].grid->GetNumberOfCells()),
        static_cast<long long>(halves[1].grid->GetNumberOfCells()), width, height);
      std::printf("| window | one volume ms | two together ms | two apart ms | together / one "
                  "| together RMSE | apart RMSE |\n|---|---:|---:|---:|---:|---:|---:|\n");
      for (const bool multisampling : options.common.windows)
      {
        std::map<std::string, std::vector<Measurement>> rounds;
        for (int r = 0; r < options.common.rounds; ++r)
        {
          for (const std::string& arrangement : arrangements)
          {
            rounds[arrangement].push_back(MeasureArrangement(
              scene, halves, arrangement, width, height, multisampling, options.common));
          }
        }
        std::map<std::string, Measurement> median;
        for (const std::string& arrangement : arrangements)
        {
          median[arrangement] = MedianRound(rounds[arrangement]);
        }
        const double one = median["one"].moving.median;
        const double together = median["together"].moving.median;
        const double apart = median["apart"].moving.median;
        const double togetherRmse =
          CoveredRmse(median["together"].image, median["one"].image);
        const double apartRmse = CoveredRmse(median["apart"].image, median["one"].image);
        std::printf("| %s | %.1f | %.1f | %.1f | %.3f | %.5f | %.4f |\n",
          WindowName(multisampling), one, together, apart, together / one, togetherRmse,
          apartRmse);
        csv << name << ',' << n << ',' << WindowName(multisampling) << ',' << one << ','
            << together << ',' << apart << ',' << together / one << ',' << togetherRmse << ','
            << apartRmse << '\n';
      }
    }
  }
  catch (const MapperError& error)
  {
    return ReportMapperError("mtpt_bench_volumes", error);
  }
  std::printf("\nwrote %s\n", csvPath.c_str());
  return 0;
}
