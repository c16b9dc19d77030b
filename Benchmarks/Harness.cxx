// SPDX-License-Identifier: BSD-3-Clause
#include "Harness.h"

#include "MeshLoader.h"
#include "TetrahedralGrid.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkCellTypeSource.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkDoubleArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRTAnalyticSource.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridVolumeRayCastMapper.h"
#include "vtkUnstructuredGridVolumeZSweepMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"
#include "vtksys/SystemTools.hxx"

#include <CLI/CLI.hpp>

#include "mtpt/Timing.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <memory>
#include <sstream>

#ifndef MTPT_SOURCE_DIR
#error "MTPT_SOURCE_DIR must be defined"
#endif

namespace mtpt
{
namespace bench
{

double Median(std::vector<double> values)
{
  if (values.empty())
  {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::size_t MedianIndex(const std::vector<double>& values)
{
  std::vector<std::size_t> order(values.size());
  for (std::size_t i = 0; i < order.size(); ++i)
  {
    order[i] = i;
  }
  std::sort(order.begin(), order.end(),
    [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  return order.empty() ? 0 : order[(order.size() - 1) / 2];
}

namespace
{

/// A scene whose grid uses `mesh`'s arrays in place; the scene keeps the mesh alive.
Scene FromMesh(const std::string& name, std::shared_ptr<TetMesh> mesh)
{
  Scene scene;
  scene.name = name;
  scene.grid = ToUnstructuredGrid(*mesh);
  const auto minmax = std::minmax_element(mesh->scalars.begin(), mesh->scalars.end());
  scene.range[0] = mesh->scalars.empty() ? 0.0 : *minmax.first;
  scene.range[1] = mesh->scalars.empty() ? 1.0 : *minmax.second;
  scene.storage = std::move(mesh);
  return scene;
}

/// vtkRTAnalyticSource over [-30, 30]^3, tetrahedralized: 1,080,000 tetrahedra.
Scene Wavelet()
{
  vtkNew<vtkRTAnalyticSource> source;
  source->SetWholeExtent(-30, 30, -30, 30, -30, 30);
  vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
  tetrahedralize->SetInputConnection(source->GetOutputPort());
  tetrahedralize->Update();
  Scene scene;
  scene.name = "wavelet";
  scene.grid = tetrahedralize->GetOutput();
  scene.grid->GetPointData()->GetScalars()->GetRange(scene.range);
  return scene;
}

/// A block source of tetrahedra (blocks^3 blocks), scalar = the sum of the coordinates.
Scene Blocks(const std::string& name, int blocks)
{
  vtkNew<vtkCellTypeSource> source;
  source->SetCellType(VTK_TETRA);
  source->SetBlocksDimensions(blocks, blocks, blocks);
  source->Update();
  Scene scene;
  scene.name = name;
  scene.grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  scene.grid->ShallowCopy(source->GetOutput());
  vtkNew<vtkDoubleArray> sum;
  sum->SetName("sum");
  for (vtkIdType i = 0; i < scene.grid->GetNumberOfPoints(); ++i)
  {
    const double* p = scene.grid->GetPoint(i);
    sum->InsertNextValue(p[0] + p[1] + p[2]);
  }
  scene.grid->GetPointData()->SetScalars(sum);
  sum->GetRange(scene.range);
  return scene;
}

} // namespace

bool LoadScene(
  const std::string& name, const std::string& dataFolder, Scene& scene, std::string& error)
{
  if (name == "wavelet")
  {
    scene = Wavelet();
    return true;
  }
  if (name == "cubes")
  {
    scene = Blocks(name, 1);
    return true;
  }
  if (name == "blocks")
  {
    scene = Blocks(name, 10);
    return true;
  }
  if (name.rfind("grid:", 0) == 0)
  {
    long long tets = 0;
    std::istringstream in(name.substr(5));
    if (!(in >> tets) || !in.eof() || tets < 1)
    {
      error = "grid:N needs a positive number of tetrahedra, not '" + name.substr(5) + "'";
      return false;
    }
    GridOptions options;
    options.cells = GridCellsForTetrahedra(static_cast<std::size_t>(tets), options.split);
    options.jitter = 0.3 * MaxJitter(options.split);
    auto mesh = std::make_shared<TetMesh>(GenerateTetrahedralGrid(options));
    scene = FromMesh(name, std::move(mesh));
    return true;
  }
  std::string path, scalar;
  if (name == "bluntfin")
  {
    path = MTPT_SOURCE_DIR "/Data/bluntfin_tets.vtu";
    scalar = "Density";
  }
  for (const DataSetEntry& entry : SharedDataSets())
  {
    if (path.empty() && name == entry.name)
    {
      if (dataFolder.empty())
      {
        error = "the mesh '" + name + "' needs a data folder (--data)";
        return false;
      }
      path = dataFolder + "/" + entry.relativePath;
      scalar = entry.scalarName;
    }
  }
  if (path.empty())
  {
    error = "unknown scene '" + name + "'";
    return false;
  }
  auto mesh = std::make_shared<TetMesh>();
  if (!LoadTetMesh(path, scalar, *mesh, error))
  {
    return false;
  }
  scene = FromMesh(name, std::move(mesh));
  return true;
}

vtkSmartPointer<vtkVolumeProperty> MakeProperty(const Scene& scene)
{
  const double low = scene.range[0], high = scene.range[1];
  vtkNew<vtkColorTransferFunction> colour;
  colour->AddRGBPoint(low, 0.23, 0.30, 0.75);
  colour->AddRGBPoint(0.5 * (low + high), 0.87, 0.87, 0.87);
  colour->AddRGBPoint(high, 0.71, 0.02, 0.15);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(low, 0.0);
  opacity->AddPoint(high, 1.0);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(scene.grid->GetLength() / 50);
  return property;
}

const std::vector<std::string>& ContenderNames()
{
  static const std::vector<std::string> names = { "mtpt-cpu", "mtpt-gl", "vtk-pt", "raycast",
    "zsweep" };
  return names;
}

vtkSmartPointer<vtkUnstructuredGridVolumeMapper> MakeMapper(
  const std::string& name, int threads, const std::string& shading)
{
  using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;
  if (name == "mtpt-cpu" || name == "mtpt-gl")
  {
    auto mapper = vtkSmartPointer<Mapper>::New();
    mapper->SetBackend(name == "mtpt-cpu" ? Mapper::CPU_BACKEND : Mapper::OPENGL_BACKEND);
    mapper->SetNumberOfThreads(threads);
    mapper->SetShadingMode(
      shading == "pre-integrated" ? Mapper::PRE_INTEGRATED_SHADING : Mapper::VTK_COMPATIBLE_SHADING);
    mapper->SynchronizedTimingOn(); // stage timers that measure the work, not its submission
    return mapper;
  }
  if (name == "vtk-pt")
  {
    return vtkSmartPointer<vtkProjectedTetrahedraMapper>::New();
  }
  if (name == "raycast")
  {
    auto mapper = vtkSmartPointer<vtkUnstructuredGridVolumeRayCastMapper>::New();
    mapper->AutoAdjustSampleDistancesOff();
    mapper->SetImageSampleDistance(1.0);
    return mapper;
  }
  if (name == "zsweep")
  {
    auto mapper = vtkSmartPointer<vtkUnstructuredGridVolumeZSweepMapper>::New();
    mapper->AutoAdjustSampleDistancesOff();
    mapper->SetImageSampleDistance(1.0);
    return mapper;
  }
  return nullptr;
}

Stage::Stage(const Scene& scene, vtkVolumeProperty* property,
  vtkUnstructuredGridVolumeMapper* mapper, int width, int height)
  : Mapper(mapper)
{
  mapper->SetInputData(scene.grid);
  this->Volume->SetMapper(mapper);
  this->Volume->SetProperty(property);
  this->Renderer->SetBackground(1, 1, 1);
  this->Renderer->AddVolume(this->Volume);
  this->Window->SetOffScreenRendering(1);
  this->Window->SetSize(width, height);
  this->Window->AddRenderer(this->Renderer);
  this->StartView();
}

Stage::~Stage()
{
  this->Mapper->ReleaseGraphicsResources(this->Window);
}

void Stage::StartView()
{
  this->Renderer->ResetCamera();
  vtkCamera* camera = this->Renderer->GetActiveCamera();
  camera->Azimuth(30);
  camera->Elevation(20);
  camera->OrthogonalizeViewUp();
  this->Renderer->ResetCameraClippingRange();
}

void Stage::Turn(double degrees)
{
  this->Renderer->GetActiveCamera()->Azimuth(degrees);
  this->Renderer->ResetCameraClippingRange();
}

double Stage::Frame()
{
  const auto start = Clock::now();
  this->Window->Render();
  this->Window->WaitForCompletion();
  return 1e3 * SecondsSince(start);
}

vtkSmartPointer<vtkImageData> Stage::Image()
{
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(this->Window);
  grab->SetShouldRerender(false);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(grab->GetOutput());
  return image;
}

FrameTiming TimeFrames(Stage& stage, const TimingOptions& options,
  const std::function<void(std::size_t)>& afterFrame)
{
  FrameTiming timing;
  stage.StartView();
  stage.Turn(options.step);
  const double warmUp = stage.Frame(); // input analysis, shaders, buffers
  if (warmUp > 1e3 * options.slowLimit)
  {
    timing.slow = true;
    timing.frames.push_back(warmUp);
    timing.median = warmUp;
    if (afterFrame)
    {
      afterFrame(0);
    }
    return timing;
  }
  for (int i = 0; i < options.repeat; ++i)
  {
    stage.Turn(options.step);
    timing.frames.push_back(stage.Frame());
    if (afterFrame)
    {
      afterFrame(static_cast<std::size_t>(i));
    }
  }
  timing.median = Median(timing.frames);
  timing.medianFrame = MedianIndex(timing.frames);
  return timing;
}

bool ParseSize(const std::string& text, int& width, int& height)
{
  const std::size_t x = text.find('x');
  try
  {
    std::size_t used = 0;
    width = std::stoi(text.substr(0, x), &used);
    if (used != (x == std::string::npos ? text.size() : x))
    {
      return false;
    }
    height = x == std::string::npos ? width : std::stoi(text.substr(x + 1), &used);
    return (x == std::string::npos || used == text.size() - x - 1) && width > 0 && height > 0;
  }
  catch (const std::exception&)
  {
    return false;
  }
}

Measurement Measure(const Scene& scene, vtkVolumeProperty* property, const std::string& name,
  int width, int height, const CommonOptions& options, const std::string& shading,
  bool unchanged)
{
  Measurement m;
  auto mapper = MakeMapper(name, options.threads, shading);
  Stage stage(scene, property, mapper, width, height);
  auto* ours = vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(mapper);
  struct Record
  {
    double cpu, composite, bin, raster, upload, draw, fragments;
    long long sorted, pixelCulled;
  };
  std::vector<Record> records;
  m.moving = TimeFrames(stage, options.timing,
    [&](std::size_t)
    {
      if (ours)
      {
        records.push_back({ ours->GetCPUStageSeconds(), ours->GetCompositeSeconds(),
          ours->GetBinSeconds(), ours->GetRasterSeconds(), ours->GetUploadSeconds(),
          ours->GetDrawSeconds(), static_cast<double>(ours->GetNumberOfFragments()),
          static_cast<long long>(ours->GetNumberOfTetrahedra()),
          static_cast<long long>(ours->GetNumberOfPixelCulledCells()) });
      }
    });
  m.image = stage.Image();
  if (ours && !records.empty())
  {
    const Record& r = records[std::min(m.moving.medianFrame, records.size() - 1)];
    m.cpuStages = 1e3 * r.cpu;
    m.composite = 1e3 * r.composite;
    m.bin = 1e3 * r.bin;
    m.raster = 1e3 * r.raster;
    m.upload = 1e3 * r.upload;
    m.draw = 1e3 * r.draw;
    m.fragments = r.fragments;
    m.sorted = r.sorted;
    m.pixelCulled = r.pixelCulled;
  }
  if (unchanged && !m.moving.slow)
  {
    TimingOptions still = options.timing;
    still.step = 0;
    m.unchanged = TimeFrames(stage, still);
  }
  return m;
}

std::string FormatMs(const FrameTiming& t)
{
  char text[32];
  std::snprintf(text, sizeof(text), t.median < 100 ? "%.1f%s" : "%.0f%s", t.median,
    t.slow ? "*" : "");
  return text;
}

ImageError CompareImages(vtkImageData* a, vtkImageData* b)
{
  ImageError e;
  auto* pa = vtkUnsignedCharArray::SafeDownCast(a->GetPointData()->GetScalars());
  auto* pb = vtkUnsignedCharArray::SafeDownCast(b->GetPointData()->GetScalars());
  if (!pa || !pb || pa->GetNumberOfValues() != pb->GetNumberOfValues())
  {
    return e;
  }
  double sum = 0, worst = 0;
  const vtkIdType n = pa->GetNumberOfValues();
  for (vtkIdType i = 0; i < n; ++i)
  {
    const double d = std::fabs(pa->GetValue(i) - pb->GetValue(i)) / 255.0;
    sum += d * d;
    worst = std::max(worst, d);
  }
  e.rmse = n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
  e.worst = worst;
  return e;
}

std::string DefaultDataFolder()
{
  const std::string folder = MTPT_SOURCE_DIR "/../shared/data";
  return vtksys::SystemTools::FileIsDirectory(folder)
    ? vtksys::SystemTools::CollapseFullPath(folder)
    : std::string();
}

void AddCommonOptions(CLI::App& app, CommonOptions& options)
{
  app.add_option("--repeat", options.timing.repeat, "timed frames per measurement (median)")
    ->check(CLI::PositiveNumber);
  app.add_option("--step", options.timing.step,
    "degrees the camera turns before every timed frame (0: an unchanged view)");
  app.add_option("--slow-limit", options.timing.slowLimit,
    "seconds: a slower warm-up frame is the measurement (one frame)")
    ->check(CLI::PositiveNumber);
  app.add_option("--threads", options.threads, "MTPT's threads (0: the default)")
    ->check(CLI::NonNegativeNumber);
  options.dataFolder = DefaultDataFolder();
  app.add_option("--data", options.dataFolder,
    "folder of the real meshes beyond the repository's (comb, kiefer, pulley, ...)");
}

std::vector<std::string> SplitList(const std::string& list)
{
  std::vector<std::string> items;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');)
  {
    if (!item.empty())
    {
      items.push_back(item);
    }
  }
  return items;
}

} // namespace bench
} // namespace mtpt
