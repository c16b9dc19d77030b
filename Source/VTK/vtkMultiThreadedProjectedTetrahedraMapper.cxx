// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "Drawing/CPUBackend.h"
#include "Drawing/OpenGLBackend.h"
#include "Drawing/VolumetricPeel.h"
#include "Input/DependentColours.h"
#include "Input/MeshSource.h"
#include "Input/TransferFunctionTables.h"
#include "Input/VolumeInput.h"

#include "mtpt/Faults.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/Gradients.h"
#include "mtpt/ImageSampling.h"
#include "mtpt/Threads.h"
#include "mtpt/Timing.h"

#include "vtkBoundingBox.h"
#include "vtkCamera.h"
#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkDataArrayRange.h"
#include "vtkInformation.h"
#include "vtkMath.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkPlane.h"
#include "vtkPlaneCollection.h"
#include "vtkOpenGLState.h"
#include "vtkPoints.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeCollection.h"
#include "vtkVolumeProperty.h"
#include "vtkWeakPointer.h"
#include "vtksys/SystemInformation.hxx"
#include "Basics/OpenGLHeader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <set>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkMultiThreadedProjectedTetrahedraMapper);

namespace
{

/// Testing only: MTPT_TESTING_ORDER=reversed or storage draws the cells in a wrong order,
/// to check that the image tests see the order (scripts/ci/mutation-check.sh).
mtpt::OrderMutation OrderMutationFromEnvironment()
{
  const char* order = std::getenv("MTPT_TESTING_ORDER");
  if (order && std::strcmp(order, "reversed") == 0)
  {
    return mtpt::OrderMutation::Reversed;
  }
  if (order && std::strcmp(order, "storage") == 0)
  {
    return mtpt::OrderMutation::Storage;
  }
  return mtpt::OrderMutation::None;
}

/// Testing only: MTPT_TESTING_FAULT=allocation:SITE makes the frame's allocation at SITE
/// fail (std::bad_alloc; mtpt/Faults.h names the sites: transform, culling,
/// level-of-detail, depth-keys, near-plane, order, decomposition, tiles), as one would where
/// memory runs out partway through a frame (see the robustness tests).
mtpt::AllocationSite AllocationFaultFromEnvironment()
{
  const char* fault = std::getenv("MTPT_TESTING_FAULT");
  const std::string prefix = "allocation:";
  mtpt::AllocationSite site = mtpt::AllocationSite::None;
  if (fault && std::strncmp(fault, prefix.c_str(), prefix.size()) == 0)
  {
    mtpt::AllocationSiteNamed(fault + prefix.size(), site);
  }
  return site;
}

/// Fraction of a frame's progress reached at the end of each pipeline stage; the backend's
/// batches share the rest.
double StageProgress(mtpt::Stage stage)
{
  switch (stage)
  {
    case mtpt::Stage::Transform:
      return 0.1;
    case mtpt::Stage::Cull:
      return 0.15;
    case mtpt::Stage::DepthKeys:
      return 0.25;
    default:
      return 0.35;
  }
}

} // namespace

class vtkMultiThreadedProjectedTetrahedraMapper::Internals
{
public:
  mtpt::MeshSource Source;
  mtpt::FramePipeline Pipeline;
  mtpt::TransferFunctionTables Tables;
  mtpt::DependentColours Colours; ///< of dependent components
  bool Dependent = false;         ///< the last input has dependent components
  /// The last input is volumes of several matrices, each placed by its own (GroupVolumes).
  bool Placed = false;
  /// The render time the renderer allotted the volumes this mapper draws together, seconds
  /// (0: it draws its own volume alone).
  double GroupAllotted = 0;
  /// Shading: each cell's normal (mtpt/Lighting.h), computed for NormalsKey, counted by
  /// NormalsVersion; and the last frame's lighting.
  std::vector<float> Normals;
  mtpt::MeshKey NormalsKey;
  std::uint64_t NormalsVersion = 0;
  mtpt::VolumetricPeel Peel;
  /// The pass peeling volumes this frame (depth peeling for volumes), and the volume drawn.
  vtkOpenGLRenderPass* PeelPass = nullptr;
  vtkVolume* PeelVolume = nullptr;
  mtpt::OpenGLBackend OpenGL;
  mtpt::CPUBackend CPU;
  // The window whose context owns the backends' OpenGL objects. Weak: a window destroyed
  // while this mapper was not in it must not be touched again.
  vtkWeakPointer<vtkRenderWindow> LastWindow;
  int SoftwareRenderer = -1; ///< of LastWindow: -1 unknown, 0 no, 1 yes

  // What GetBounds() last computed from.
  vtkDataObject* BoundsInput = nullptr;
  vtkMTimeType BoundsTime = 0;

  /// The time of the last frame drawn per renderer and volume (automatic image sample
  /// distance); entries of destroyed renderers or volumes are dropped.
  struct RenderTime
  {
    vtkWeakPointer<vtkRenderer> renderer;
    vtkWeakPointer<vtkVolume> volume;
    double seconds = 0;
  };
  std::vector<RenderTime> RenderTimes;

  /// The level of detail of the last frame drawn (automatic adjustment).
  mtpt::Detail LastDetail;
  /// When the current and the last frame started (Render's entry; none before the first).
  mtpt::Clock::time_point FrameStart, LastFrameStart;

  // The last frame: its plan, and what its drawing measured.
  mtpt::FramePlan Plan;
  mtpt::DrawTimes Times;
  int LastBackend = OPENGL_BACKEND;
  vtkIdType Tetrahedra = 0;
  bool Stopped = false;
  /// The seconds the level of detail's analysis of the input took in the last frame: not
  /// part of its time.
  double AnalysisSeconds = 0;
  /// The bound the last frame's buffers were checked against (FitsInMemory), bytes.
  std::size_t MemoryBound = 0;

  /**
   * Whether `message` about `cause` is new: each message is reported once per modification
   * time of the object it is about, not every frame (several messages about one object
   * each appear once, not in turn every frame).
   */
  /// The last frame's record: the pipeline's times and counts, the drawing's, the
  /// compositor's.
  mtpt::FrameStatistics Statistics() const
  {
    mtpt::FrameStatistics statistics;
    statistics.stages = this->Pipeline.Times();
    statistics.counts = this->Pipeline.Stats();
    statistics.drawing = this->Times;
    statistics.cpu = this->LastBackend == CPU_BACKEND;
    if (statistics.cpu)
    {
      statistics.compositor = this->CPU.Stats();
    }
    statistics.tetrahedra = static_cast<std::size_t>(this->Tetrahedra);
    statistics.stopped = this->Stopped;
    return statistics;
  }

  bool Report(vtkObject* cause, const std::string& message)
  {
    const vtkMTimeType time = cause ? cause->GetMTime() : 0;
    const auto found = this->Reported.find(message);
    if (found != this->Reported.end() && found->second == time)
    {
      return false;
    }
    if (this->Reported.size() >= 64)
    {
      this->Reported.clear(); // messages carry counts: keep the memory bounded
    }
    this->Reported[message] = time;
    return true;
  }
  /// OpenGL failures are reported once per window.
  bool ReportOpenGL(const std::string& message)
  {
    return this->OpenGLReported.insert(message).second;
  }
  void ForgetOpenGLReports() { this->OpenGLReported.clear(); }

private:
  std::map<std::string, vtkMTimeType> Reported;
  std::set<std::string> OpenGLReported;
};

vtkMultiThreadedProjectedTetrahedraMapper::vtkMultiThreadedProjectedTetrahedraMapper()
  : Internal(new Internals)
{
}

vtkMultiThreadedProjectedTetrahedraMapper::~vtkMultiThreadedProjectedTetrahedraMapper()
{
  // As VTK's own mappers: a live window has released its props' resources already.
  this->ReleaseGraphicsResources(nullptr);
}

template <typename T>
void vtkMultiThreadedProjectedTetrahedraMapper::SetNonNegative(
  const char* setter, const char* what, const char* zero, T value, T& setting)
{
  if (value < 0)
  {
    vtkWarningMacro(<< setter << "(" << value << "): " << what << " must be 0 (" << zero
                    << ") or positive; keeping " << setting);
    return;
  }
  if (value != setting)
  {
    setting = value;
    this->Modified();
  }
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetNumberOfThreads(int threads)
{
  this->SetNonNegative(
    "SetNumberOfThreads", "the thread count", "the default", threads, this->NumberOfThreads);
}

int vtkMultiThreadedProjectedTetrahedraMapper::GetEffectiveNumberOfThreads()
{
  return mtpt::ResolveThreadCount(this->NumberOfThreads);
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetBatchSize(vtkIdType size)
{
  this->SetNonNegative("SetBatchSize", "the batch size", "one batch", size, this->BatchSize);
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetMemoryLimit(vtkIdType bytes)
{
  this->SetNonNegative(
    "SetMemoryLimit", "the limit", "the memory available", bytes, this->MemoryLimit);
}

bool vtkMultiThreadedProjectedTetrahedraMapper::FitsInMemory(const mtpt::FramePlan& plan)
{
  const mtpt::MemoryNeed& need = plan.memory;
  const mtpt::MemoryVerdict verdict = mtpt::CheckMemory(need,
    static_cast<std::size_t>(this->MemoryLimit), this->Internal->Pipeline.MemoryBytes(),
    []
    {
      vtksys::SystemInformation system;
      system.RunMemoryCheck();
      return static_cast<std::size_t>(system.GetAvailablePhysicalMemory()) << 20;
    });
  this->Internal->MemoryBound = verdict.bytes;
  if (verdict.fits)
  {
    return true;
  }
  // MiB (rounded up), or bytes where the limit is less than one: each figure then says
  // what it is.
  const bool bytes = verdict.limit < (std::size_t{ 1 } << 20);
  const auto size = [bytes](std::size_t b)
  {
    return bytes ? std::to_string(b) + " bytes"
                 : std::to_string((b + (std::size_t{ 1 } << 20) - 1) >> 20) + " MiB";
  };
  std::ostringstream text;
  text << "drawing " << need.cells << " tetrahedra (" << need.points << " points) needs up to "
       << size(verdict.bytes) << " of buffers, over "
       << (this->MemoryLimit > 0 ? "the memory limit of " : "the memory available, ")
       << size(verdict.limit) << (this->MemoryLimit > 0 ? " (SetMemoryLimit)" : "")
       << "; nothing was drawn. A smaller batch size (SetBatchSize, now " << this->BatchSize
       << "), a larger limit or fewer cells may fit";
  vtkErrorMacro(<< text.str()); // every frame: each draws nothing
  return false;
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetDistance(
  const char* name, float distance, float& setting)
{
  if (std::isnan(distance))
  {
    vtkWarningMacro(<< "Set" << name << "(nan): an image sample distance must be a number in "
                    << "[0.1, 100]; keeping " << setting);
    return;
  }
  distance = std::min(100.0f, std::max(0.1f, distance)); // the range of VTK's ray caster
  if (distance != setting)
  {
    setting = distance;
    this->Modified();
  }
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetImageSampleDistance(float distance)
{
  this->SetDistance("ImageSampleDistance", distance, this->ImageSampleDistance);
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetMinimumImageSampleDistance(float distance)
{
  this->SetDistance("MinimumImageSampleDistance", distance, this->MinimumImageSampleDistance);
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetMaximumImageSampleDistance(float distance)
{
  this->SetDistance("MaximumImageSampleDistance", distance, this->MaximumImageSampleDistance);
}

double vtkMultiThreadedProjectedTetrahedraMapper::RetrieveRenderTime(
  vtkRenderer* renderer, vtkVolume* volume)
{
  for (const Internals::RenderTime& entry : this->Internal->RenderTimes)
  {
    if (entry.renderer.GetPointer() == renderer && entry.volume.GetPointer() == volume)
    {
      return entry.seconds;
    }
  }
  return 0.0;
}

void vtkMultiThreadedProjectedTetrahedraMapper::StoreRenderTime(
  vtkRenderer* renderer, vtkVolume* volume, double seconds)
{
  auto& times = this->Internal->RenderTimes;
  times.erase(std::remove_if(times.begin(), times.end(),
                [](const Internals::RenderTime& entry)
                { return !entry.renderer.GetPointer() || !entry.volume.GetPointer(); }),
    times.end());
  for (Internals::RenderTime& entry : times)
  {
    if (entry.renderer.GetPointer() == renderer && entry.volume.GetPointer() == volume)
    {
      entry.seconds = seconds;
      return;
    }
  }
  times.push_back({ renderer, volume, seconds });
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetOrderMethodAsString()
{
  return this->OrderMethod == PARTITION_SORT ? "PartitionSort" : "RadixSort";
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetShadingModeAsString()
{
  return this->ShadingMode == PRE_INTEGRATED_SHADING ? "PreIntegrated" : "VTKCompatible";
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetBlendModeAsString()
{
  return mtpt::BlendModeName(this->BlendMode);
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetBackendAsString()
{
  return this->Backend == AUTOMATIC_BACKEND ? "Automatic"
                                            : (this->Backend == CPU_BACKEND ? "CPU" : "OpenGL");
}

double vtkMultiThreadedProjectedTetrahedraMapper::GetTransformSeconds()
{
  return this->Internal->Statistics().stages.transform;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDepthKeySeconds()
{
  return this->Internal->Statistics().stages.keys;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCullSeconds()
{
  const mtpt::StageTimes stages = this->Internal->Statistics().stages;
  return stages.cull + stages.select;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetOrderSeconds()
{
  return this->Internal->Statistics().stages.order;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDecomposeSeconds()
{
  return this->Internal->Statistics().stages.decompose;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetLightingSeconds()
{
  return this->Internal->Statistics().stages.light;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCPUStageSeconds()
{
  return this->Internal->Statistics().stages.Total();
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetUploadSeconds()
{
  return this->Internal->Statistics().drawing.upload;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDrawSeconds()
{
  return this->Internal->Statistics().drawing.draw;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCompositeSeconds()
{
  return this->Internal->Statistics().drawing.composite;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetBinSeconds()
{
  return this->Internal->Statistics().compositor.binSeconds;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetRasterSeconds()
{
  return this->Internal->Statistics().compositor.rasterSeconds;
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfFragments()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().compositor.fragments);
}
const char* vtkMultiThreadedProjectedTetrahedraMapper::GetCompositorInstructionSet()
{
  return mtpt::Compositor::InstructionSet();
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetLastBackend()
{
  return this->Internal->LastBackend;
}
bool vtkMultiThreadedProjectedTetrahedraMapper::GetLastFrameStopped()
{
  return this->Internal->Statistics().stopped;
}

bool vtkMultiThreadedProjectedTetrahedraMapper::IsSoftwareRenderer(const char* renderer)
{
  if (!renderer)
  {
    return false;
  }
  for (const char* name : { "llvmpipe", "softpipe", "SWR", "swrast", "Software Rasterizer" })
  {
    if (std::strstr(renderer, name))
    {
      return true;
    }
  }
  return false;
}

vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfTetrahedra()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().tetrahedra);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfCellsLeftOut()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.leftOut);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfOpacityCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.opacityCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfFrustumCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.frustumCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfPixelCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.pixelCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfNearClippedCells()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.nearClipped);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfNearClipPieces()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.nearPieces);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfHiddenCells()
{
  return static_cast<vtkIdType>(this->Internal->Statistics().counts.hidden);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfTetrahedralizations()
{
  return this->Internal->Source.Tetrahedralizations();
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfBatches()
{
  return this->Internal->Statistics().drawing.batches;
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetLastFrameReuse()
{
  const mtpt::FrameStatistics statistics = this->Internal->Statistics();
  const mtpt::FrameStats& stats = statistics.counts;
  const bool imageReused = statistics.drawing.imageReused; // nothing decomposed either
  return (stats.transformReused ? REUSED_TRANSFORM : 0) | (stats.orderReused ? REUSED_ORDER : 0) |
    (stats.orderFromPrevious ? ORDER_FROM_PREVIOUS : 0) |
    (stats.decompositionReused || imageReused ? REUSED_DECOMPOSITION : 0) |
    (imageReused ? REUSED_IMAGE : 0) | (stats.unordered ? ORDER_NOT_NEEDED : 0);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetMemoryBytes()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.MemoryBytes());
}

vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetMemoryBytesBound()
{
  return static_cast<vtkIdType>(this->Internal->MemoryBound);
}

double* vtkMultiThreadedProjectedTetrahedraMapper::GetBounds()
{
  if (!this->GetInputDataObject(0, 0))
  {
    vtkMath::UninitializeBounds(this->Bounds);
    return this->Bounds;
  }
  this->Update();
  vtkDataObject* input = this->GetInputDataObject(0, 0);
  Internals& in = *this->Internal;
  if (input == in.BoundsInput && input->GetMTime() == in.BoundsTime)
  {
    return this->Bounds;
  }
  in.BoundsInput = input;
  in.BoundsTime = input->GetMTime();
  vtkBoundingBox box;
  for (const auto& grid : mtpt::MeshSource::Grids(input))
  {
    if (vtkPoints* points = grid.first->GetPoints())
    {
      for (const auto p : vtk::DataArrayTupleRange<3>(points->GetData()))
      {
        const double x = p[0], y = p[1], z = p[2];
        if (std::isfinite(x) && std::isfinite(y) && std::isfinite(z))
        {
          box.AddPoint(x, y, z);
        }
      }
    }
  }
  if (box.IsValid())
  {
    box.GetBounds(this->Bounds);
  }
  else
  {
    vtkMath::UninitializeBounds(this->Bounds);
  }
  return this->Bounds;
}

void vtkMultiThreadedProjectedTetrahedraMapper::GetBounds(double bounds[6])
{
  const double* own = this->GetBounds();
  std::copy(own, own + 6, bounds);
}

bool vtkMultiThreadedProjectedTetrahedraMapper::IsSupported(vtkRenderWindow* window)
{
  return vtkOpenGLRenderWindow::SafeDownCast(window) != nullptr;
}

void vtkMultiThreadedProjectedTetrahedraMapper::ReleaseGraphicsResources(vtkWindow* window)
{
  Internals& in = *this->Internal;
  in.OpenGL.ReleaseGraphicsResources(window);
  in.CPU.ReleaseGraphicsResources(window);
  in.Peel.ReleaseGraphicsResources(window);
  in.SoftwareRenderer = -1;
  in.LastWindow = nullptr;
  in.ForgetOpenGLReports();
  this->Superclass::ReleaseGraphicsResources(window);
}

void vtkMultiThreadedProjectedTetrahedraMapper::MoveToWindow(vtkOpenGLRenderWindow* window)
{
  Internals& in = *this->Internal;
  if (in.LastWindow == window)
  {
    return;
  }
  if (vtkRenderWindow* previous = in.LastWindow)
  {
    // The OpenGL objects belong to the previous window's context: free them there (in this
    // window's context the same names may be another object's), then come back.
    previous->MakeCurrent();
    this->ReleaseGraphicsResources(previous);
    window->MakeCurrent();
  }
  in.LastWindow = window;
}

int vtkMultiThreadedProjectedTetrahedraMapper::FillInputPortInformation(
  int port, vtkInformation* info)
{
  if (port != 0)
  {
    return 0;
  }
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGridBase");
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataObjectTree");
  return 1;
}

namespace
{
/// Whether two volumes are placed by the same matrix.
bool SameMatrix(vtkVolume* a, vtkVolume* b)
{
  const double* x = a->GetMatrix()->GetData();
  const double* y = b->GetMatrix()->GetData();
  return std::equal(x, x + 16, y);
}

/// The rest of the warning given once when two MTPT volumes of a renderer are drawn apart.
const char* const SeparateVolumesWarning =
  ": the two are drawn one after the other, as VTK draws volumes, so where their cells "
  "interleave in depth one lies wrongly over the other. Volumes of one blend mode, shading "
  "mode, clipping planes and lighting are composited in one visibility order "
  "(SetCompositeWithOtherVolumes)";

/**
 * What the volumes drawn together must share: the rest of each mapper's settings are the
 * first's. One blend mode, shading mode, clipping planes and lighting; one matrix where
 * shading by lights is on (the cells' normals are taken to the eye by one matrix); and one
 * property object where a table of several properties cannot serve: blend modes other than
 * composite (their scalars compare across cells) and dependent components (classified per
 * property).
 */
struct GroupKey
{
  std::array<double, 16> matrix{};
  int blendMode = 0;
  int shadingMode = 0;
  double averageRange[2] = { 0, 0 };
  std::vector<std::array<double, 6>> planes; ///< origin and normal of each clipping plane
  bool shade = false;
  double lighting[4] = { 0, 0, 0, 0 };   ///< ambient, diffuse, specular, specular power
  vtkVolumeProperty* property = nullptr; ///< null: any property
};

GroupKey GroupKeyOf(vtkVolume* volume, vtkMultiThreadedProjectedTetrahedraMapper* mapper)
{
  GroupKey key;
  std::copy_n(volume->GetMatrix()->GetData(), 16, key.matrix.begin());
  key.blendMode = mapper->GetBlendMode();
  key.shadingMode = mapper->GetShadingMode();
  if (key.blendMode == vtkMultiThreadedProjectedTetrahedraMapper::AVERAGE_INTENSITY_BLEND)
  {
    mapper->GetAverageIPScalarRange(key.averageRange);
  }
  if (vtkPlaneCollection* planes = mapper->GetClippingPlanes())
  {
    for (int i = 0; i < planes->GetNumberOfItems(); ++i)
    {
      std::array<double, 6> plane{};
      planes->GetItem(i)->GetOrigin(plane.data());
      planes->GetItem(i)->GetNormal(plane.data() + 3);
      key.planes.push_back(plane);
    }
  }
  vtkVolumeProperty* property = volume->GetProperty();
  key.shade = property->GetShade(0) != 0;
  if (key.shade)
  {
    key.lighting[0] = property->GetAmbient(0);
    key.lighting[1] = property->GetDiffuse(0);
    key.lighting[2] = property->GetSpecular(0);
    key.lighting[3] = property->GetSpecularPower(0);
  }
  if (key.blendMode != vtkMultiThreadedProjectedTetrahedraMapper::COMPOSITE_BLEND ||
    !property->GetIndependentComponents())
  {
    key.property = property;
  }
  return key;
}

/**
 * The entry of `volumes` for `volume` drawn by `mapper`: the volume itself, or the prop that
 * holds it and draws through the mapper (ParaView's vtkPVLODVolume draws an inner volume of
 * its own); null when there is none.
 */
vtkVolume* EntryOf(vtkVolumeCollection* volumes, vtkVolume* volume, vtkAbstractVolumeMapper* mapper)
{
  vtkVolume* entry = nullptr;
  vtkCollectionSimpleIterator it;
  volumes->InitTraversal(it);
  while (vtkVolume* other = volumes->GetNextVolume(it))
  {
    if (other == volume || (!entry && other->GetMapper() == mapper))
    {
      entry = other;
    }
  }
  return entry;
}

/// Why volumes of keys `a` and `b` are drawn apart, or empty when they are drawn together.
std::string Difference(const GroupKey& a, const GroupKey& b)
{
  if (a.matrix != b.matrix && (a.shade || b.shade))
  {
    return "a matrix of its own (its position, orientation, scale or user matrix) where "
           "shading by lights is on (the property's Shade)";
  }
  if (a.blendMode != b.blendMode || a.averageRange[0] != b.averageRange[0] ||
    a.averageRange[1] != b.averageRange[1])
  {
    return "another blend mode";
  }
  if (a.shadingMode != b.shadingMode)
  {
    return "another shading mode (SetShadingMode)";
  }
  if (a.planes != b.planes)
  {
    return "clipping planes of its own";
  }
  if (a.shade != b.shade || !std::equal(a.lighting, a.lighting + 4, b.lighting))
  {
    return "a property of other lighting (Shade, Ambient, Diffuse, Specular, SpecularPower)";
  }
  if (a.property != b.property)
  {
    return "a property of its own, which a blend mode other than composite or dependent "
           "components (IndependentComponents off) cannot share a table with";
  }
  return std::string();
}
} // namespace

bool vtkMultiThreadedProjectedTetrahedraMapper::GroupVolumes(
  vtkRenderer* renderer, vtkVolume* volume, std::vector<mtpt::GroupedVolume>& group)
{
  Internals& in = *this->Internal;
  group.assign(1, { this->GetInputDataObject(0, 0), this, volume->GetProperty() });
  in.GroupAllotted = 0;
  if (!this->CompositeWithOtherVolumes)
  {
    return true;
  }
  // The renderer's visible MTPT volumes that composite with others, in its order: those of
  // this volume's key are drawn together by the first of them. A volume the renderer's
  // culler left out of this frame (wholly outside the view: its render time multiplier 0)
  // is not drawn, so it neither leads a group nor adds cells to one.
  vtkVolumeCollection* volumes = renderer->GetVolumes();
  vtkVolume* self = EntryOf(volumes, volume, this);
  if (!self)
  {
    return true; // not among the renderer's volumes: drawn by itself
  }
  const GroupKey key = GroupKeyOf(volume, this);
  std::vector<vtkVolume*> members;
  vtkCollectionSimpleIterator it;
  volumes->InitTraversal(it);
  while (vtkVolume* other = volumes->GetNextVolume(it))
  {
    auto* mapper = vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(other->GetMapper());
    if (!other->GetVisibility() || !(other->GetRenderTimeMultiplier() > 0) || !mapper ||
      !mapper->CompositeWithOtherVolumes || !mapper->GetInputDataObject(0, 0) ||
      !other->GetProperty())
    {
      continue;
    }
    const std::string difference =
      other == self ? std::string() : Difference(key, GroupKeyOf(other, mapper));
    if (difference.empty())
    {
      members.push_back(other);
      continue;
    }
    const std::string warning = "another volume of this renderer drawn by a "
                                "vtkMultiThreadedProjectedTetrahedraMapper has " +
      difference + SeparateVolumesWarning;
    if (in.Report(other, warning))
    {
      vtkWarningMacro(<< warning);
    }
  }
  if (members.size() <= 1 || std::find(members.begin(), members.end(), self) == members.end())
  {
    return true; // alone (or hidden, or culled)
  }
  if (members.front() != self)
  {
    return false; // the first of the group draws this volume's cells with its own
  }
  // Where their matrices differ, each volume's cells are placed by its own matrix and the
  // frame's model coordinates are world coordinates (SetUpFrame).
  bool placed = false;
  for (vtkVolume* member : members)
  {
    placed = placed || !SameMatrix(member, self);
  }
  group.clear();
  for (vtkVolume* member : members)
  {
    in.GroupAllotted += member->GetAllocatedRenderTime();
    auto* mapper = static_cast<vtkMultiThreadedProjectedTetrahedraMapper*>(member->GetMapper());
    if (mapper != this)
    {
      mapper->Update(); // its input as of this frame, as its own GetBounds brings it
    }
    group.push_back({ mapper->GetInputDataObject(0, 0), mapper, member->GetProperty(),
      placed ? member->GetMatrix()->GetData() : nullptr });
  }
  return true;
}

bool vtkMultiThreadedProjectedTetrahedraMapper::PrepareInput(
  const std::vector<mtpt::GroupedVolume>& group, vtkVolumeProperty* property,
  mtpt::FrameInput& frame)
{
  Internals& in = *this->Internal;
  // Problems are reported once per change of what they are about, not every frame.
  const auto report = [this, &in](vtkObject* subject, const std::string& text, bool error)
  {
    if (in.Report(subject, text))
    {
      if (error)
      {
        vtkErrorMacro(<< text);
      }
      else
      {
        vtkWarningMacro(<< text);
      }
    }
  };
  if (!in.Source.Update(group, report))
  {
    return false;
  }
  // One table segment per property object (volumes drawn together may each have one), and
  // where there are several, each volume's scalars mapped into its segment.
  std::vector<mtpt::TransferFunctionTables::Segment> segments;
  for (const mtpt::MeshSource::Segment& segment : in.Source.Segments())
  {
    segments.push_back({ segment.property, segment.range[0], segment.range[1] });
    std::string warning;
    mtpt::UnitDistance(segment.property, &warning);
    if (segment.property != property && !warning.empty() && in.Report(segment.property, warning))
    {
      vtkWarningMacro(<< warning);
    }
  }
  in.Tables.Update(segments);
  in.Source.MapToSegments(
    [&in](int segment, double scalar) { return in.Tables.EntryOf(segment, scalar); });
  frame.points = in.Source.Points();
  frame.cells = in.Source.Cells();
  frame.scalars = in.Source.Scalars();
  frame.dataVersion = in.Source.Version();
  frame.placementVersion = in.Source.PlacementVersion();
  in.Placed = group.size() > 1 && group.front().matrix;
  in.Dependent = in.Source.Channels() > 1;
  if (in.Dependent)
  {
    // Dependent components: colours per point or cell, classified at the vertices.
    const std::size_t tuples = frame.scalars.association == mtpt::ScalarsView::Association::Cells
      ? frame.cells.cellCount
      : frame.points.count;
    in.Colours.Update(frame.scalars, in.Source.Channels(), tuples, property, in.Source.Version());
    frame.scalars = in.Colours.Attenuations();
    frame.colours = in.Colours.Colours();
    frame.dataVersion = in.Colours.Version();
  }
  return true;
}

mtpt::RenderBackend* vtkMultiThreadedProjectedTetrahedraMapper::ChooseBackend()
{
  Internals& in = *this->Internal;
  int backend = this->Backend;
  if (backend == AUTOMATIC_BACKEND)
  {
    if (in.SoftwareRenderer < 0)
    {
      in.SoftwareRenderer =
        IsSoftwareRenderer(reinterpret_cast<const char*>(glGetString(GL_RENDERER))) ? 1 : 0;
    }
    backend = in.SoftwareRenderer ? CPU_BACKEND : OPENGL_BACKEND;
  }
  in.LastBackend = backend;
  return backend == CPU_BACKEND ? static_cast<mtpt::RenderBackend*>(&in.CPU) : &in.OpenGL;
}

void vtkMultiThreadedProjectedTetrahedraMapper::ReportProgress(
  vtkOpenGLRenderWindow* window, double fraction)
{
  if (!this->HasObserver(vtkCommand::ProgressEvent))
  {
    return;
  }
  // An observer may draw elsewhere (a progress bar in another window): keep this frame's
  // context and framebuffers.
  window->GetState()->PushFramebufferBindings();
  this->UpdateProgress(fraction);
  window->MakeCurrent();
  window->GetState()->PopFramebufferBindings();
}

void vtkMultiThreadedProjectedTetrahedraMapper::Render(vtkRenderer* renderer, vtkVolume* volume)
{
  // However the frame ends, OpenMP's idle workers stop busy-waiting when it does, so they
  // leave the cores to the OpenGL rasterizer (llvmpipe draws on the same cores).
  struct ReleaseThreadsAtEnd
  {
    ~ReleaseThreadsAtEnd() { mtpt::ReleaseIdleThreads(); }
  } releaseThreads;
  Internals& in = *this->Internal;
  in.Times = mtpt::DrawTimes{};
  in.Tetrahedra = 0;
  in.Stopped = false;
  in.LastFrameStart = in.FrameStart;
  in.FrameStart = mtpt::Clock::now();
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(renderer->GetRenderWindow());
  if (!window)
  {
    vtkErrorMacro(<< "needs an OpenGL render window (vtkOpenGLRenderWindow)");
    return;
  }
  this->MoveToWindow(window);
  std::vector<mtpt::GroupedVolume> group;
  if (!this->GroupVolumes(renderer, volume, group))
  {
    this->TimeToDraw = 0; // drawn by the first volume of its group
    return;
  }
  mtpt::FrameInput frame;
  if (!this->PrepareInput(group, volume->GetProperty(), frame))
  {
    return;
  }
  // Timed from here, as VTK's ray caster times its frames: the update of the input, and its
  // analysis for the level of detail (DrawPrepared), are not part of the frame.
  const float distance = this->ImageSampleDistance, fraction = this->CellFraction;
  this->AdjustDetail(renderer, volume);
  const auto start = mtpt::Clock::now();
  in.AnalysisSeconds = 0;
  bool drawn = false;
  // A fault injected for a test holds for this frame only, whether it comes to its site.
  mtpt::InjectAllocationFault(AllocationFaultFromEnvironment());
  try
  {
    drawn = this->DrawPrepared(renderer, volume, window, frame);
    mtpt::InjectAllocationFault(mtpt::AllocationSite::None);
  }
  catch (const std::bad_alloc&)
  {
    // An allocation the memory check did not foresee (other programs took the memory since):
    // no frame, no buffers kept, and the next frame starts afresh.
    mtpt::InjectAllocationFault(mtpt::AllocationSite::None);
    in.Pipeline.Release();
    vtkErrorMacro(<< "ran out of memory drawing " << frame.cells.cellCount
                  << " tetrahedra; nothing was drawn and the buffers were freed. A smaller "
                     "batch size (SetBatchSize), a memory limit (SetMemoryLimit) or fewer "
                     "cells may fit");
  }
  if (!drawn)
  {
    // No frame, or a stopped one: nothing to learn the next detail from (VTK's ray caster
    // restores the distance of an aborted frame too).
    this->ImageSampleDistance = distance;
    this->CellFraction = fraction;
    return;
  }
  if (this->AutoAdjustSampleDistances || this->AutoAdjustCellFraction)
  {
    glFinish(); // the time of the drawing, not of its submission
  }
  this->TimeToDraw = std::max(mtpt::SecondsSince(start) - in.AnalysisSeconds, 0.0);
  this->StoreRenderTime(renderer, volume, this->TimeToDraw);
  in.LastDetail = { frame.cellFraction, this->ImageSampleDistance };
}

double vtkMultiThreadedProjectedTetrahedraMapper::RetrieveFrameInterval()
{
  const Internals& in = *this->Internal;
  return in.LastFrameStart == mtpt::Clock::time_point{}
    ? 0.0
    : std::chrono::duration<double>(in.FrameStart - in.LastFrameStart).count();
}

void vtkMultiThreadedProjectedTetrahedraMapper::RetrieveFrameCosts(
  double& cellSeconds, double& sampleSeconds, double& viewportSeconds)
{
  const mtpt::FrameStatistics statistics = this->Internal->Statistics();
  cellSeconds = statistics.CellSeconds();
  sampleSeconds = statistics.SampleSeconds();
  viewportSeconds = statistics.drawing.viewport;
}

void vtkMultiThreadedProjectedTetrahedraMapper::AdjustDetail(
  vtkRenderer* renderer, vtkVolume* volume)
{
  const double last = this->RetrieveRenderTime(renderer, volume);
  // The first volume of a group draws every member's cells in the time allotted to them all.
  const double allotted = this->Internal->GroupAllotted > 0 ? this->Internal->GroupAllotted
                                                            : volume->GetAllocatedRenderTime();
  if (!this->AutoAdjustCellFraction)
  {
    // VTK's own rule for the distance alone (vtkUnstructuredGridVolumeRayCastMapper).
    if (this->AutoAdjustSampleDistances)
    {
      this->ImageSampleDistance =
        static_cast<float>(mtpt::AdjustImageSampleDistance(this->ImageSampleDistance, last,
          allotted, this->MinimumImageSampleDistance, this->MaximumImageSampleDistance));
    }
    return;
  }
  mtpt::DetailLimits limits;
  limits.adjustDistance = this->AutoAdjustSampleDistances != 0;
  limits.minimumFraction = this->MinimumCellFraction;
  limits.minimumDistance = this->MinimumImageSampleDistance;
  limits.maximumDistance = this->MaximumImageSampleDistance;
  mtpt::MeasuredFrame measured;
  measured.detail = this->Internal->LastDetail;
  measured.seconds = last;
  this->RetrieveFrameCosts(measured.cellSeconds, measured.sampleSeconds, measured.viewportSeconds);
  const mtpt::Detail next =
    mtpt::ChooseDetail(measured, mtpt::VolumeBudget(allotted, this->RetrieveFrameInterval(), last),
      limits, { this->CellFraction, this->ImageSampleDistance });
  this->CellFraction = static_cast<float>(next.cellFraction);
  this->ImageSampleDistance = static_cast<float>(next.sampleDistance);
}

bool vtkMultiThreadedProjectedTetrahedraMapper::DrawPrepared(
  vtkRenderer* renderer, vtkVolume* volume, vtkOpenGLRenderWindow* window, mtpt::FrameInput& frame)
{
  Internals& in = *this->Internal;
  mtpt::BackendFrame draw;
  renderer->GetTiledSizeAndOrigin(&draw.size[0], &draw.size[1], &draw.origin[0], &draw.origin[1]);
  if (draw.size[0] <= 0 || draw.size[1] <= 0)
  {
    // No pixel to draw (a zero-area viewport or tile): no work, and no message, as VTK's
    // own mappers. Its aspect ratio would not even give a usable projection.
    return false;
  }
  mtpt::RenderBackend* backend = this->ChooseBackend();
  this->SetUpFrame(renderer, volume, window, backend, frame, draw);
  this->ReportProgress(window, 0.0);
  if (!this->FitsInMemory(in.Plan))
  {
    return false;
  }
  // The level of detail's importance order (once per mesh), after the memory check, which
  // counts it.
  const auto analysis = mtpt::Clock::now();
  in.Pipeline.PrepareLevelOfDetail(frame, this->NumberOfThreads);
  in.AnalysisSeconds = mtpt::SecondsSince(analysis);
  if (!in.Pipeline.Prepare(frame, this->NumberOfThreads))
  {
    in.Stopped = in.Pipeline.Stopped();
    if (!in.Stopped)
    {
      vtkErrorMacro(<< "the input has " << frame.cells.cellCount
                    << " tetrahedra; this mapper draws at most "
                    << mtpt::FramePipeline::MaxTetrahedra());
    }
    return false;
  }
  // The near plane's pieces are known now that the stages have cut the cells: where they
  // are more than the last frame's, the bound again with them, before the batches allocate.
  // A frame over the limit then gives its buffers back.
  if (in.Pipeline.Stats().nearPieces > in.Plan.memory.pieces)
  {
    in.Plan.memory.pieces = in.Pipeline.Stats().nearPieces;
    if (!this->FitsInMemory(in.Plan))
    {
      in.Pipeline.Release();
      return false;
    }
  }
  in.Tetrahedra = static_cast<vtkIdType>(in.Pipeline.SortedCount());
  if (in.Tetrahedra > 0) // else everything is culled: transparent or out of view
  {
    this->DrawFrame(backend, draw);
  }
  this->ReportProgress(window, 1.0);
  return !in.Stopped;
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetUpFrame(vtkRenderer* renderer, vtkVolume* volume,
  vtkOpenGLRenderWindow* window, mtpt::RenderBackend* backend, mtpt::FrameInput& frame,
  mtpt::BackendFrame& draw)
{
  Internals& in = *this->Internal;
  // Volumes placed by matrices of their own are drawn in world coordinates (GroupVolumes).
  mtpt::ViewMatrices(renderer, in.Placed ? nullptr : volume, frame.modelView, frame.projection);
  frame.perspective = renderer->GetActiveCamera()->GetParallelProjection() == 0;
  draw.renderer = renderer;
  draw.window = window;
  draw.floatFramebuffer = this->UseFloatingPointFrameBuffer;
  draw.synchronizedTiming = this->SynchronizedTiming;
  // Inside a depth-peeling pass's peel loop: the pass's targets are the viewport's size at
  // the origin.
  in.PeelPass = mtpt::VolumetricPeel::ActivePass(volume, this);
  in.PeelVolume = volume;
  if (in.PeelPass)
  {
    draw.peel = &in.Peel;
    draw.origin[0] = draw.origin[1] = 0;
  }
  vtkVolumeProperty* property = volume->GetProperty();
  in.Plan = mtpt::PlanFrame(
    this->FrameSettingsOf(property), this->FrameFactsOf(renderer, window, backend, frame, draw));
  for (const mtpt::PlanNote& note : in.Plan.notes)
  {
    if (in.Report(
          note.about == mtpt::PlanNote::About::Property ? static_cast<vtkObject*>(property) : this,
          note.key))
    {
      if (note.error)
      {
        vtkErrorMacro(<< note.text);
      }
      else
      {
        vtkWarningMacro(<< note.text);
      }
    }
  }
  this->ImageInUseSize[0] = in.Plan.sampledSize.width;
  this->ImageInUseSize[1] = in.Plan.sampledSize.height;
  draw.plan = &in.Plan;
  draw.pipeline = &in.Pipeline;
  draw.tables = &in.Tables;
  frame.opacity = in.Tables.Table();
  frame.opacityVersion = in.Tables.Version();
  mtpt::ApplyPlan(in.Plan, frame);
  if (in.Plan.lit)
  {
    this->SetUpLighting(renderer, property, frame);
  }
  this->ConfigurePipeline(window);
}

mtpt::FrameSettings vtkMultiThreadedProjectedTetrahedraMapper::FrameSettingsOf(
  vtkVolumeProperty* property)
{
  mtpt::FrameSettings settings;
  settings.shading = this->ShadingMode == PRE_INTEGRATED_SHADING ? mtpt::Shading::PreIntegrated
                                                                 : mtpt::Shading::VTKCompatible;
  settings.blendMode = this->BlendMode;
  settings.averageRange[0] = this->AverageIPScalarRange[0];
  settings.averageRange[1] = this->AverageIPScalarRange[1];
  settings.shade = property->GetShade(0) != 0;
  settings.cullInvisibleCells = this->CullInvisibleCells;
  settings.cellFraction = this->CellFraction;
  settings.imageSampleDistance = this->ImageSampleDistance;
  settings.autoAdjustCellFraction = this->AutoAdjustCellFraction != 0;
  settings.batchSize = static_cast<std::size_t>(this->BatchSize);
  settings.threads = this->NumberOfThreads;
  std::string warning;
  settings.unitDistance = mtpt::UnitDistance(property, &warning);
  if (!warning.empty() && this->Internal->Report(property, warning))
  {
    vtkWarningMacro(<< warning);
  }
  if (this->Internal->Tables.Segments() > 1)
  {
    // Each segment's attenuation is per its own unit distance, folded into the table.
    settings.unitDistance = this->Internal->Tables.UnitDistance();
  }
  return settings;
}

mtpt::FrameFacts vtkMultiThreadedProjectedTetrahedraMapper::FrameFactsOf(vtkRenderer* renderer,
  vtkOpenGLRenderWindow* window, mtpt::RenderBackend* backend, const mtpt::FrameInput& frame,
  const mtpt::BackendFrame& draw)
{
  Internals& in = *this->Internal;
  mtpt::FrameFacts facts;
  facts.points = frame.points.count;
  facts.cells = frame.cells.cellCount;
  facts.vertexColours = in.Dependent;
  facts.cellScalars = frame.scalars.association == mtpt::ScalarsView::Association::Cells;
  facts.peeling = in.PeelPass != nullptr;
  facts.target = backend == &in.CPU ? mtpt::BatchTarget::Fans : mtpt::BatchTarget::Slots;
  facts.viewport[0] = draw.size[0];
  facts.viewport[1] = draw.size[1];
  facts.sampledImageLimit = backend->SampledImageLimit(window);
  facts.centresOnly = backend->SamplesPixelCentresOnly(false, draw.floatFramebuffer);
  facts.sampledCentresOnly = backend->SamplesPixelCentresOnly(true, draw.floatFramebuffer);
  facts.projection = frame.projection;
  facts.nearPieces = in.Pipeline.Stats().nearPieces;
  int ignored = 0;
  facts.clipPlanes = mtpt::EyeClipPlanes(this, renderer, ignored);
  if (ignored > 0 && in.Report(this->ClippingPlanes, "too many clipping planes"))
  {
    vtkWarningMacro(<< "clipping with the first " << mtpt::ClipPlanes::Max << " of "
                    << mtpt::ClipPlanes::Max + ignored << " clipping planes, as many as VTK's "
                    << "GPU ray caster takes");
  }
  return facts;
}

void vtkMultiThreadedProjectedTetrahedraMapper::SetUpLighting(
  vtkRenderer* renderer, vtkVolumeProperty* property, mtpt::FrameInput& frame)
{
  Internals& in = *this->Internal;
  const mtpt::MeshKey key =
    mtpt::MeshKey::Of(frame.points, frame.cells, frame.scalars, nullptr, frame.dataVersion);
  if (in.NormalsVersion == 0 || !(key == in.NormalsKey))
  {
    // Once per change of the data: the points' gradients, then each cell's normal.
    std::vector<float> gradients;
    mtpt::PointGradients(
      frame.points, frame.cells, frame.scalars, gradients, this->NumberOfThreads);
    mtpt::CellNormals(
      frame.cells, frame.points.count, gradients, in.Normals, this->NumberOfThreads);
    in.NormalsKey = key;
    ++in.NormalsVersion;
  }
  int ignored = 0;
  frame.lighting = mtpt::VolumeLighting(renderer, property, ignored);
  if (ignored > 0 && in.Report(renderer, "too many lights"))
  {
    vtkWarningMacro(<< "shading with the first " << mtpt::Lighting::MaxLights << " of "
                    << mtpt::Lighting::MaxLights + ignored << " lights");
  }
  frame.normals = in.Normals.data();
  frame.normalsVersion = in.NormalsVersion;
}

void vtkMultiThreadedProjectedTetrahedraMapper::ConfigurePipeline(vtkOpenGLRenderWindow* window)
{
  mtpt::FramePipeline& pipeline = this->Internal->Pipeline;
  pipeline.SetOrderMethod(this->OrderMethod == PARTITION_SORT ? mtpt::OrderMethod::PartitionSort
                                                              : mtpt::OrderMethod::RadixSort,
    static_cast<std::size_t>(this->MaxSubArraySize));
  pipeline.SetReuse(this->ReuseResults);
  pipeline.SetOrderMutationForTesting(OrderMutationFromEnvironment());
  pipeline.SetStageCallback(
    [this, window](mtpt::Stage stage)
    {
      this->ReportProgress(window, StageProgress(stage));
      return window->CheckAbortStatus() == 0;
    });
  pipeline.SetBatchCallback(
    [this, window](double fraction)
    {
      const double begin = StageProgress(mtpt::Stage::Order);
      this->ReportProgress(window, begin + (1.0 - begin) * fraction);
      return window->CheckAbortStatus() == 0;
    });
}

void vtkMultiThreadedProjectedTetrahedraMapper::DrawFrame(
  mtpt::RenderBackend* backend, mtpt::BackendFrame& draw)
{
  Internals& in = *this->Internal;
  auto run = [&draw, &in](mtpt::RenderBackend* b)
  { return draw.peel ? b->DrawPeel(draw, in.Times) : b->Draw(draw, in.Times); };
  std::string peelError;
  if (draw.peel &&
    !in.Peel.RecordRanges(draw.window, in.PeelPass, this, in.PeelVolume, draw.size, peelError))
  {
    if (in.ReportOpenGL(peelError))
    {
      vtkErrorMacro(<< "depth peeling: " << peelError);
    }
    return;
  }
  bool drawn = run(backend);
  if (!in.OpenGL.Warning().empty() && in.ReportOpenGL(in.OpenGL.Warning()))
  {
    vtkWarningMacro(<< in.OpenGL.Warning());
  }
  if (!drawn)
  {
    const bool fallBack = backend == &in.CPU;
    const std::string message = std::string(fallBack ? "the CPU backend" : "the OpenGL backend") +
      " failed: " + backend->Error() + (fallBack ? "; drawing with OpenGL instead" : "");
    if (in.ReportOpenGL(message))
    {
      vtkErrorMacro(<< message);
    }
    if (fallBack)
    {
      // The prepared frame, drawn by the other backend: its batches become slots.
      in.LastBackend = OPENGL_BACKEND;
      in.Times = mtpt::DrawTimes{};
      in.Plan.target = mtpt::BatchTarget::Slots;
      drawn = run(&in.OpenGL);
      if (!drawn && in.ReportOpenGL(in.OpenGL.Error()))
      {
        vtkErrorMacro(<< "the OpenGL backend failed too: " << in.OpenGL.Error());
      }
    }
  }
  in.Stopped = in.Times.stopped;
  // A peel's answer goes into the pass's targets even when stopped: what was composited.
  if (draw.peel && drawn &&
    !in.Peel.Answer(draw.window, in.PeelPass, this, in.PeelVolume, peelError) &&
    in.ReportOpenGL(peelError))
  {
    vtkErrorMacro(<< "depth peeling: " << peelError);
  }
}

void vtkMultiThreadedProjectedTetrahedraMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfThreads: " << this->NumberOfThreads
     << (this->NumberOfThreads == 0 ? " (default: " : " (") << this->GetEffectiveNumberOfThreads()
     << " in use)\n";
  os << indent << "Backend: " << this->GetBackendAsString()
     << " (last frame: " << (this->Internal->LastBackend == CPU_BACKEND ? "CPU" : "OpenGL")
     << ")\n";
  os << indent << "OrderMethod: " << this->GetOrderMethodAsString() << "\n";
  os << indent << "CompositorInstructionSet: " << GetCompositorInstructionSet() << "\n";
  os << indent << "ShadingMode: " << this->GetShadingModeAsString() << "\n";
  os << indent << "BlendMode: " << this->GetBlendModeAsString() << "\n";
  os << indent << "AverageIPScalarRange: " << this->AverageIPScalarRange[0] << " "
     << this->AverageIPScalarRange[1] << "\n";
  os << indent << "MaxSubArraySize: " << this->MaxSubArraySize << "\n";
  os << indent << "UseFloatingPointFrameBuffer: " << this->UseFloatingPointFrameBuffer << "\n";
  os << indent << "SynchronizedTiming: " << this->SynchronizedTiming << "\n";
  os << indent << "BatchSize: " << this->BatchSize << (this->BatchSize == 0 ? " (one batch)" : "")
     << "\n";
  os << indent << "MemoryLimit: " << this->MemoryLimit
     << (this->MemoryLimit == 0 ? " (the memory available)" : "") << "\n";
  os << indent << "ReuseResults: " << this->ReuseResults << "\n";
  os << indent << "CompositeWithOtherVolumes: " << this->CompositeWithOtherVolumes << "\n";
  os << indent << "CullInvisibleCells: " << this->CullInvisibleCells << "\n";
  os << indent << "ImageSampleDistance: " << this->ImageSampleDistance << "\n";
  os << indent << "MinimumImageSampleDistance: " << this->MinimumImageSampleDistance << "\n";
  os << indent << "MaximumImageSampleDistance: " << this->MaximumImageSampleDistance << "\n";
  os << indent << "AutoAdjustSampleDistances: " << this->AutoAdjustSampleDistances << "\n";
  os << indent << "CellFraction: " << this->CellFraction << "\n";
  os << indent << "MinimumCellFraction: " << this->MinimumCellFraction << "\n";
  os << indent << "AutoAdjustCellFraction: " << this->AutoAdjustCellFraction << "\n";
  os << indent << "ImageInUseSize (last frame): " << this->ImageInUseSize[0] << " x "
     << this->ImageInUseSize[1] << "\n";
  const mtpt::FrameStats& stats = this->Internal->Pipeline.Stats();
  os << indent << "Last frame culled: " << stats.opacityCulled << " transparent, "
     << stats.frustumCulled << " outside the view, " << stats.pixelCulled << " covering no pixel, "
     << stats.hidden << " hidden behind opaque pixels; " << this->GetNumberOfBatches()
     << " batches; " << this->GetMemoryBytes() << " bytes of buffers\n";
  os << indent << "Last frame: " << this->Internal->Tetrahedra << " tetrahedra; transform "
     << this->GetTransformSeconds() << " s, cull " << this->GetCullSeconds() << " s, depth keys "
     << this->GetDepthKeySeconds() << " s, order " << this->GetOrderSeconds() << " s, decompose "
     << this->GetDecomposeSeconds() << " s, lighting " << this->GetLightingSeconds()
     << " s, composite " << this->GetCompositeSeconds() << " s, upload " << this->GetUploadSeconds()
     << " s, draw " << this->GetDrawSeconds() << " s\n";
}
