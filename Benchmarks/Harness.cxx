// SPDX-License-Identifier: BSD-3-Clause
#include "Harness.h"

#include "MeshLoader.h"
#include "TetrahedralGrid.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCallbackCommand.h"
#include "vtkCamera.h"
#include "vtkXMLMultiBlockDataReader.h"
#include "vtkMultiBlockUnstructuredGridVolumeMapper.h"
#include "vtkDataObjectTreeIterator.h"
#include "vtkDataObjectTree.h"
#include "vtkAppendFilter.h"
#include "vtkDataArray.h"
#include "vtkXMLUnstructuredGridReader.h"
#include "vtkDataSetReader.h"
#include "vtkDataSet.h"
#include "vtkCellData.h"
#include "vtkCellTypeSource.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkDoubleArray.h"
#include "vtkGPUVolumeRayCastMapper.h"
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

#include "mtpt/Compositor.h"
#include "mtpt/Timing.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#ifndef MTPT_SOURCE_DIR
#error "MTPT_SOURCE_DIR must be defined"
#endif

namespace mtpt
{
namespace bench
{

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
  scene.image = source->GetOutput();
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
  if (name == "bluntfin" &&
    vtksys::SystemTools::FileExists(MTPT_SOURCE_DIR "/Data/bluntfin_tets.vtu"))
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

namespace
{
bool EndsWith(const std::string& s, const std::string& suffix)
{
  return s.size() >= suffix.size() &&
    s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
} // namespace

namespace
{
/// Whether `mapper` takes a composite data set as its input.
bool TakesBlocks(vtkAbstractVolumeMapper* mapper)
{
  return vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(mapper) ||
    vtkMultiBlockUnstructuredGridVolumeMapper::SafeDownCast(mapper);
}

/// What `mapper` draws of `scene`: its image data for a mapper of image data, its blocks for
/// a mapper that takes them, else its grid.
vtkDataObject* InputOf(const Scene& scene, vtkAbstractVolumeMapper* mapper)
{
  if (!vtkUnstructuredGridVolumeMapper::SafeDownCast(mapper))
  {
    return scene.image;
  }
  return scene.blocks && TakesBlocks(mapper) ? scene.blocks.Get()
                                             : static_cast<vtkDataObject*>(scene.grid);
}

/// A multi-block file: its blocks kept, the array chosen in the first block with cells.
bool LoadBlocks(const std::string& path, const std::string& array, Scene& scene, std::string& error)
{
  vtkNew<vtkXMLMultiBlockDataReader> reader;
  if (!reader->CanReadFile(path.c_str()))
  {
    error = "cannot read '" + path + "' as a VTK XML multi-block data set";
    return false;
  }
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkDataObject* tree = reader->GetOutputDataObject(0);
  auto leaf = vtkSmartPointer<vtkDataObjectTreeIterator>::Take(
    vtkDataObjectTree::SafeDownCast(tree)->NewTreeIterator());
  leaf->VisitOnlyLeavesOn();
  vtkNew<vtkAppendFilter> append;
  std::string name = array;
  bool cells = false;
  scene.range[0] = 1e300;
  scene.range[1] = -1e300;
  for (leaf->InitTraversal(); !leaf->IsDoneWithTraversal(); leaf->GoToNextItem())
  {
    auto* block = vtkDataSet::SafeDownCast(leaf->GetCurrentDataObject());
    if (!block || block->GetNumberOfCells() == 0)
    {
      continue;
    }
    if (name.empty())
    {
      vtkDataArray* first = block->GetPointData()->GetScalars();
      first = first ? first : block->GetPointData()->GetArray(0);
      cells = !first && block->GetCellData()->GetArray(0);
      first = first ? first : block->GetCellData()->GetArray(0);
      name = first && first->GetName() ? first->GetName() : "";
    }
    vtkDataArray* scalars = block->GetPointData()->GetArray(name.c_str());
    cells = !scalars;
    scalars = scalars ? scalars : block->GetCellData()->GetArray(name.c_str());
    if (scalars)
    {
      (cells ? static_cast<vtkDataSetAttributes*>(block->GetCellData())
             : static_cast<vtkDataSetAttributes*>(block->GetPointData()))
        ->SetActiveScalars(name.c_str());
      double range[2];
      scalars->GetRange(range, scalars->GetNumberOfComponents() > 1 ? -1 : 0);
      scene.range[0] = std::min(scene.range[0], range[0]);
      scene.range[1] = std::max(scene.range[1], range[1]);
    }
    append->AddInputData(block);
  }
  if (append->GetNumberOfInputConnections(0) == 0 || !(scene.range[0] <= scene.range[1]))
  {
    error = "'" + path + "' has no block with cells and the scalars '" + name + "'";
    return false;
  }
  vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
  tetrahedralize->SetInputConnection(append->GetOutputPort());
  tetrahedralize->TetrahedraOnlyOn();
  tetrahedralize->Update();
  scene.name = vtksys::SystemTools::GetFilenameWithoutLastExtension(path);
  scene.grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  scene.grid->ShallowCopy(tetrahedralize->GetOutput());
  scene.blocks = tree;
  scene.arrayName = name;
  scene.cellScalars = cells;
  return true;
}
} // namespace

bool LoadSceneFile(
  const std::string& path, const std::string& array, Scene& scene, std::string& error)
{
  if (EndsWith(path, ".vtm"))
  {
    return LoadBlocks(path, array, scene, error);
  }
  vtkSmartPointer<vtkDataSet> data;
  if (EndsWith(path, ".vtu"))
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    if (!reader->CanReadFile(path.c_str()))
    {
      error = "cannot read '" + path + "' as a VTK XML unstructured grid";
      return false;
    }
    reader->SetFileName(path.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
  else if (EndsWith(path, ".vtk"))
  {
    vtkNew<vtkDataSetReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
  else
  {
    error = "'" + path + "' is none of .vtu, .vtk and .vtm";
    return false;
  }
  if (!data || data->GetNumberOfCells() == 0)
  {
    error = "'" + path + "' holds no cells (missing or unreadable file?)";
    return false;
  }
  vtkDataArray* scalars = nullptr;
  bool cells = false;
  if (!array.empty())
  {
    scalars = data->GetPointData()->GetArray(array.c_str());
    if (!scalars && (scalars = data->GetCellData()->GetArray(array.c_str())))
    {
      cells = true;
    }
    if (!scalars)
    {
      error = "'" + path + "' has no point or cell array named '" + array + "'";
      return false;
    }
  }
  else if (!(scalars = data->GetPointData()->GetScalars()) &&
    data->GetPointData()->GetNumberOfArrays() > 0)
  {
    scalars = data->GetPointData()->GetArray(0);
  }
  if (!scalars && data->GetCellData()->GetNumberOfArrays() > 0)
  {
    scalars = data->GetCellData()->GetArray(0);
    cells = scalars != nullptr;
  }
  if (!scalars)
  {
    error = "'" + path + "' has no data arrays to render";
    return false;
  }
  vtkDataSetAttributes* attributes = cells
    ? static_cast<vtkDataSetAttributes*>(data->GetCellData())
    : static_cast<vtkDataSetAttributes*>(data->GetPointData());
  attributes->SetActiveScalars(scalars->GetName());
  scalars->GetRange(scene.range, scalars->GetNumberOfComponents() > 1 ? -1 : 0);
  vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
  tetrahedralize->SetInputData(data);
  tetrahedralize->TetrahedraOnlyOn();
  tetrahedralize->Update();
  scene.name = vtksys::SystemTools::GetFilenameWithoutLastExtension(path);
  scene.grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  scene.grid->ShallowCopy(tetrahedralize->GetOutput());
  scene.arrayName = scalars->GetName() ? scalars->GetName() : "";
  scene.cellScalars = cells;
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
  static const std::vector<std::string> names = { "mtpt", "mtpt-cpu", "mtpt-gl", "vtk-pt",
    "vtk-multiblock", "raycast", "zsweep", "gpu-raycast" };
  return names;
}

const std::vector<std::string>& BlendModeNames()
{
  static const std::vector<std::string> names = { "composite", "maximum", "minimum", "average",
    "additive" };
  return names;
}

vtkSmartPointer<vtkUnstructuredGridVolumeMapper> MakeMapper(
  const std::string& name, const MapperSettings& settings)
{
  using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;
  if (name == "mtpt" || name == "mtpt-cpu" || name == "mtpt-gl")
  {
    auto mapper = vtkSmartPointer<Mapper>::New();
    mapper->SetBackend(name == "mtpt-cpu" ? Mapper::CPU_BACKEND
        : name == "mtpt-gl"               ? Mapper::OPENGL_BACKEND
                                          : Mapper::AUTOMATIC_BACKEND);
    mapper->SetNumberOfThreads(settings.threads);
    mapper->SetShadingMode(settings.shading == "pre-integrated" ? Mapper::PRE_INTEGRATED_SHADING
                                                                : Mapper::VTK_COMPATIBLE_SHADING);
    mapper->SetOrderMethod(
      settings.order == "partition" ? Mapper::PARTITION_SORT : Mapper::RADIX_SORT);
    const auto& blends = BlendModeNames();
    const auto blend = std::find(blends.begin(), blends.end(), settings.blend);
    mapper->SetBlendMode(blend == blends.end() ? 0 : static_cast<int>(blend - blends.begin()));
    mapper->SynchronizedTimingOn(); // stage timers that measure the work, not its submission
    mapper->SetAutoAdjustSampleDistances(settings.autoAdjust ? 1 : 0);
    mapper->SetAutoAdjustCellFraction(settings.autoAdjust ? 1 : 0);
    mapper->SetImageSampleDistance(settings.imageSampleDistance);
    mapper->SetBatchSize(static_cast<vtkIdType>(settings.batchSize));
    mapper->SetMemoryLimit(static_cast<vtkIdType>(settings.memoryLimitMiB) << 20);
    return mapper;
  }
  if (name == "vtk-pt")
  {
    return vtkSmartPointer<vtkProjectedTetrahedraMapper>::New();
  }
  if (name == "vtk-multiblock")
  {
    return vtkSmartPointer<vtkMultiBlockUnstructuredGridVolumeMapper>::New();
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

vtkSmartPointer<vtkAbstractVolumeMapper> MakeContender(
  const std::string& name, const MapperSettings& settings)
{
  if (name == "gpu-raycast")
  {
    auto mapper = vtkSmartPointer<vtkGPUVolumeRayCastMapper>::New();
    mapper->AutoAdjustSampleDistancesOff();
    mapper->SetImageSampleDistance(1.0);
    return mapper;
  }
  return MakeMapper(name, settings);
}

bool DrawsImageData(const std::string& name)
{
  return name == "gpu-raycast";
}

OpenGLInfo QueryOpenGL()
{
  vtkNew<vtkRenderWindow> probe;
  probe->SetOffScreenRendering(1);
  probe->Render();
  const std::string caps = probe->ReportCapabilities();
  OpenGLInfo info;
  const std::pair<const char*, std::string*> fields[] = { { "OpenGL vendor string:", &info.vendor },
    { "OpenGL renderer string:", &info.renderer }, { "OpenGL version string:", &info.version } };
  for (const auto& field : fields)
  {
    const auto at = caps.find(field.first);
    if (at == std::string::npos)
    {
      *field.second = "unknown";
      continue;
    }
    const std::size_t from = at + std::char_traits<char>::length(field.first);
    std::string value = caps.substr(from, caps.find('\n', from) - from);
    value.erase(0, value.find_first_not_of(' '));
    *field.second = value;
  }
  return info;
}

namespace
{
/// The ErrorEvent observer of a Stage's mapper: prints the message (VTK's, formatted as its
/// output window prints it) and keeps it (client data: the stage's list).
void CollectError(vtkObject*, unsigned long, void* clientData, void* callData)
{
  const std::string message = callData ? static_cast<const char*>(callData) : "(no message)";
  std::fprintf(stderr, "%s", message.c_str());
  static_cast<std::vector<std::string>*>(clientData)->push_back(message);
}
} // namespace

int ReportMapperError(const char* program, const MapperError& error)
{
  std::fprintf(stderr,
    "%s: %s for a frame (above), so nothing was written. A smaller window, the other backend "
    "or fewer cells may avoid it.\n",
    program, error.what());
  return 1;
}

Stage::Stage(const Scene& scene, vtkVolumeProperty* property, vtkAbstractVolumeMapper* mapper,
  int width, int height, const StageOptions& options)
  : Mapper(mapper)
  , StartCamera(options.view)
{
  this->ErrorWatch->SetCallback(CollectError);
  this->ErrorWatch->SetClientData(&this->Errors);
  this->ErrorObserver = mapper->AddObserver(vtkCommand::ErrorEvent, this->ErrorWatch);
  mapper->SetInputDataObject(InputOf(scene, mapper));
  this->Volume->SetMapper(mapper);
  this->Volume->SetProperty(property);
  this->Renderer->SetBackground(
    options.background[0], options.background[1], options.background[2]);
  this->Renderer->AddVolume(this->Volume);
  this->Window->SetOffScreenRendering(options.onScreen ? 0 : 1);
  if (!options.multisampling)
  {
    this->Window->SetMultiSamples(0);
  }
  this->Window->SetSize(width, height);
  this->Window->AddRenderer(this->Renderer);
  if (options.desiredUpdateRate > 0)
  {
    this->Window->SetDesiredUpdateRate(options.desiredUpdateRate);
  }
  this->StartView();
}

Stage::~Stage()
{
  this->Mapper->RemoveObserver(this->ErrorObserver);
  this->Mapper->ReleaseGraphicsResources(this->Window);
}

void Stage::SetMapper(vtkAbstractVolumeMapper* mapper, vtkDataObject* input)
{
  this->Mapper->RemoveObserver(this->ErrorObserver);
  this->Mapper->ReleaseGraphicsResources(this->Window);
  mapper->SetInputDataObject(input ? input : this->Mapper->GetInputDataObject(0, 0));
  this->Mapper = mapper;
  this->ErrorObserver = mapper->AddObserver(vtkCommand::ErrorEvent, this->ErrorWatch);
  this->Volume->SetMapper(mapper);
}

void Stage::StartView()
{
  // From VTK's default direction every time: ResetCamera keeps the current direction.
  vtkCamera* camera = this->Renderer->GetActiveCamera();
  camera->SetPosition(0, 0, 1);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  camera->SetParallelProjection(this->StartCamera.parallel ? 1 : 0);
  this->Renderer->ResetCamera();
  camera->Azimuth(this->StartCamera.azimuth);
  camera->Elevation(this->StartCamera.elevation);
  camera->OrthogonalizeViewUp();
  camera->Zoom(this->StartCamera.zoom);
  this->Renderer->ResetCameraClippingRange();
}

void Stage::Turn(double degrees)
{
  this->Renderer->GetActiveCamera()->Azimuth(degrees);
  this->Renderer->ResetCameraClippingRange();
}

double Stage::Frame()
{
  this->Errors.clear();
  const auto start = Clock::now();
  this->Window->Render();
  this->Window->WaitForCompletion();
  const double ms = 1e3 * SecondsSince(start);
  if (!this->Errors.empty())
  {
    const std::size_t n = this->Errors.size();
    throw MapperError(std::string("the mapper (") + this->Mapper->GetClassName() + ") reported " +
      (n == 1 ? "an error" : std::to_string(n) + " errors"));
  }
  return ms;
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

FrameTiming TimeFrames(
  Stage& stage, const TimingOptions& options, const std::function<void(std::size_t)>& afterFrame)
{
  FrameTiming timing;
  stage.StartView();
  for (int i = 1; i < options.warmUp; ++i) // an automatic image sample distance settles
  {
    stage.Turn(options.step);
    stage.Frame();
  }
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

StageFigures FiguresOf(vtkAbstractVolumeMapper* mapper)
{
  StageFigures f;
  auto* ours = vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(mapper);
  if (!ours)
  {
    return f;
  }
  f.transform = 1e3 * ours->GetTransformSeconds();
  f.cull = 1e3 * ours->GetCullSeconds();
  f.keys = 1e3 * ours->GetDepthKeySeconds();
  f.order = 1e3 * ours->GetOrderSeconds();
  f.decompose = 1e3 * ours->GetDecomposeSeconds();
  f.cpuStages = 1e3 * ours->GetCPUStageSeconds();
  f.composite = 1e3 * ours->GetCompositeSeconds();
  f.bin = 1e3 * ours->GetBinSeconds();
  f.raster = 1e3 * ours->GetRasterSeconds();
  f.upload = 1e3 * ours->GetUploadSeconds();
  f.draw = 1e3 * ours->GetDrawSeconds();
  f.fragments = static_cast<double>(ours->GetNumberOfFragments());
  f.sorted = static_cast<long long>(ours->GetNumberOfTetrahedra());
  f.pixelCulled = static_cast<long long>(ours->GetNumberOfPixelCulledCells());
  f.hidden = static_cast<long long>(ours->GetNumberOfHiddenCells());
  f.memoryBytes = static_cast<long long>(ours->GetMemoryBytes());
  f.imageSampleDistance = ours->GetImageSampleDistance();
  f.imageSize[0] = ours->GetImageInUseSize()[0];
  f.imageSize[1] = ours->GetImageInUseSize()[1];
  f.backend = ours->GetLastBackend() == vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND
    ? "CPU"
    : "OpenGL";
  return f;
}

double NsPerFragmentCore(const StageFigures& f, int threads)
{
  return f.fragments > 0 ? 1e6 * f.raster * threads / f.fragments : 0;
}

Measurement Measure(const Scene& scene, vtkVolumeProperty* property, const std::string& name,
  int width, int height, const CommonOptions& options, bool unchanged,
  const StageOptions& stageOptions)
{
  Measurement m;
  auto mapper = MakeContender(name, options.mapper);
  StageOptions look = stageOptions;
  if (options.desiredUpdateRate > 0)
  {
    look.desiredUpdateRate = options.desiredUpdateRate;
  }
  Stage stage(scene, property, mapper, width, height, look);
  std::vector<StageFigures> figures;
  m.moving =
    TimeFrames(stage, options.timing, [&](std::size_t) { figures.push_back(FiguresOf(mapper)); });
  m.image = stage.Image();
  if (!figures.empty())
  {
    m.mtpt = figures[std::min(m.moving.medianFrame, figures.size() - 1)];
  }
  if (unchanged && !m.moving.slow)
  {
    TimingOptions still = options.timing;
    still.step = 0;
    m.unchanged = TimeFrames(stage, still);
  }
  return m;
}

const char* WindowName(bool multisampling)
{
  return multisampling ? "multisampled" : "single-sampled";
}

std::size_t WindowMeasurements::Faster() const
{
  std::size_t best = 0;
  for (std::size_t i = 1; i < this->measurements.size(); ++i)
  {
    if (this->measurements[i].moving.median < this->measurements[best].moving.median)
    {
      best = i;
    }
  }
  return best;
}

const Measurement* WindowMeasurements::In(bool multisampling) const
{
  for (std::size_t i = 0; i < this->windows.size(); ++i)
  {
    if (this->windows[i] == multisampling)
    {
      return &this->measurements[i];
    }
  }
  return nullptr;
}

Measurement MedianRound(std::vector<Measurement> rounds)
{
  std::vector<double> medians;
  for (const Measurement& m : rounds)
  {
    medians.push_back(m.moving.median);
  }
  return rounds.empty() ? Measurement{} : rounds[MedianIndex(medians)];
}

std::map<std::string, WindowMeasurements> MeasureContenders(const Scene& scene,
  vtkVolumeProperty* property, const std::vector<std::string>& names, int width, int height,
  const CommonOptions& options, bool unchanged, const StageOptions& stage)
{
  // rounds[name][window]: every round goes through every contender and window in turn.
  std::map<std::string, std::vector<std::vector<Measurement>>> rounds;
  for (int round = 0; round < std::max(1, options.rounds); ++round)
  {
    for (const std::string& name : names)
    {
      auto& byWindow = rounds[name];
      byWindow.resize(options.windows.size());
      for (std::size_t w = 0; w < options.windows.size(); ++w)
      {
        StageOptions look = stage;
        look.multisampling = options.windows[w];
        byWindow[w].push_back(
          Measure(scene, property, name, width, height, options, unchanged, look));
      }
    }
  }
  std::map<std::string, WindowMeasurements> results;
  for (auto& entry : rounds)
  {
    WindowMeasurements& m = results[entry.first];
    m.windows = options.windows;
    for (auto& byRound : entry.second)
    {
      m.measurements.push_back(MedianRound(std::move(byRound)));
    }
  }
  return results;
}

std::string FormatWindows(const WindowMeasurements& m)
{
  std::string text;
  for (std::size_t i = 0; i < m.measurements.size(); ++i)
  {
    const std::string ms = FormatMs(m.measurements[i].moving);
    text += i == 0 ? ms : (i == 1 ? " (" : ", ") + std::string(WindowName(m.windows[i])) + " " + ms;
  }
  return m.measurements.size() > 1 ? text + ")" : text;
}

std::string FormatMs(const FrameTiming& t)
{
  char text[32];
  std::snprintf(
    text, sizeof(text), t.median < 100 ? "%.1f%s" : "%.0f%s", t.median, t.slow ? "*" : "");
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

void AddMemoryOptions(CLI::App& app, MapperSettings& settings)
{
  app
    .add_option("--batch-size", settings.batchSize,
      "MTPT's tetrahedra decomposed and drawn at a time (0: the whole mesh at once)")
    ->check(CLI::NonNegativeNumber);
  app
    .add_option("--memory-limit", settings.memoryLimitMiB,
      "MiB MTPT's buffers may take; a frame that needs more is refused with an error (0: the "
      "memory available)")
    ->check(CLI::NonNegativeNumber);
}

void AddCommonOptions(CLI::App& app, CommonOptions& options)
{
  app.add_option("--repeat", options.timing.repeat, "timed frames per measurement (median)")
    ->check(CLI::PositiveNumber);
  app
    .add_option("--rounds", options.rounds,
      "frames and scaling: measure everything this many times, contenders and windows "
      "alternating; each result is its median round")
    ->check(CLI::PositiveNumber);
  app
    .add_option_function<std::string>(
      "--multisampling",
      [&options](const std::string& list)
      {
        options.windows.clear();
        for (const std::string& item : SplitList(list))
        {
          options.windows.push_back(item == "on");
        }
      },
      "the windows every contender is timed in: on (VTK's default, multisampled), off "
      "(SetMultiSamples(0)), or on,off (default: both; ratios take each mapper at its faster)")
    ->check(
      [](const std::string& list)
      {
        const auto items = SplitList(list);
        for (const std::string& item : items)
        {
          if (item != "on" && item != "off")
          {
            return std::string("--multisampling takes on, off or on,off");
          }
        }
        return items.empty() ? std::string("--multisampling takes on, off or on,off")
                             : std::string();
      });
  app.add_option("--step", options.timing.step,
    "degrees the camera turns before every timed frame (0: an unchanged view)");
  app
    .add_option("--slow-limit", options.timing.slowLimit,
      "seconds: a slower warm-up frame is the measurement (one frame)")
    ->check(CLI::PositiveNumber);
  app.add_option("--threads", options.mapper.threads, "MTPT's threads (0: the default)")
    ->check(CLI::NonNegativeNumber);
  app.add_option("--shading", options.mapper.shading, "MTPT's shading")
    ->check(CLI::IsMember({ "vtk", "pre-integrated" }));
  app.add_option("--order", options.mapper.order, "MTPT's visibility order")
    ->check(CLI::IsMember({ "radix", "partition" }));
  app.add_option("--blend-mode", options.mapper.blend, "MTPT's blend mode")
    ->check(CLI::IsMember(BlendModeNames()));
  AddMemoryOptions(app, options.mapper);
  app
    .add_option_function<std::string>(
      "--instruction-set",
      [](const std::string& name) { mtpt::Compositor::UseInstructionSet(name); },
      "MTPT's SIMD code with this instruction set (default: the best this processor has)")
    ->check(CLI::IsMember(mtpt::Compositor::InstructionSets()));
  options.dataFolder = DefaultDataFolder();
  app.add_option("--data", options.dataFolder,
    "folder of real meshes beyond the repository's (comb, kiefer, pulley, ...; default "
    "$MTPT_DATA_DIR)");
}

void AddImageSamplingOptions(CLI::App& app, CommonOptions& options)
{
  app
    .add_option("--image-sample-distance", options.mapper.imageSampleDistance,
      "MTPT composites one sample per D x D pixels, stretched over the window (default 1)")
    ->check(CLI::Range(0.1, 100.0));
  app
    .add_option("--desired-update-rate", options.desiredUpdateRate,
      "the window asks for this many frames a second, as an interactor does while the user "
      "drags, and MTPT adjusts its image sample distance and cell fraction to it (its defaults)")
    ->check(CLI::PositiveNumber);
  app
    .add_option("--warm-up", options.timing.warmUp,
      "untimed frames before the timed ones (default 1; 10 with --desired-update-rate)")
    ->check(CLI::PositiveNumber);
}

void ApplyImageSamplingOptions(CLI::App& app, CommonOptions& options)
{
  if (options.desiredUpdateRate > 0)
  {
    options.mapper.autoAdjust = true;
    if (app.count("--warm-up") == 0)
    {
      options.timing.warmUp = 10;
    }
  }
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

long StatusKiB(const char* field)
{
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(in, line))
  {
    if (line.compare(0, prefix.size(), prefix) == 0)
    {
      return std::atol(line.c_str() + prefix.size());
    }
  }
  return -1;
}

void ResetPeakMemory()
{
  std::ofstream("/proc/self/clear_refs") << "5";
}

} // namespace bench
} // namespace mtpt
