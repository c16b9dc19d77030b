// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkMTPTCompositeFS.h"
#include "vtkMTPTMeshAdapter.h"
#include "vtkMTPTTetrahedralizer.h"
#include "vtkMTPTTetrahedraFS.h"
#include "vtkMTPTTetrahedraVS.h"

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"

#include "vtkBoundingBox.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDataArrayRange.h"
#include "vtkMath.h"
#include "vtkMatrix4x4.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLBufferObject.h"
#include "vtkOpenGLFramebufferObject.h"
#include "vtkOpenGLHelper.h"
#include "vtkOpenGLIndexBufferObject.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkOpenGLVertexArrayObject.h"
#include "vtkOpenGLVertexBufferObject.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPoints.h"
#include "vtkRenderer.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWeakPointer.h"
#include "vtk_glew.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <vector>

vtkStandardNewMacro(vtkMultiThreadedProjectedTetrahedraMapper);

namespace
{
/// Entries of the transfer-function table. The functions are piecewise linear and the
/// table is sampled with linear filtering, so it reproduces them exactly except within one
/// entry (1/4095 of the scalar range) of a breakpoint.
constexpr int TransferFunctionTableSize = 4096;

double SecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

class vtkMultiThreadedProjectedTetrahedraMapper::Internals
{
public:
  mtpt::vtkMTPTTetrahedralizer Tetrahedralizer;
  mtpt::vtkMTPTMeshAdapter Adapter;
  mtpt::FramePipeline Pipeline;

  // OpenGL resources, owned by LastWindow's context. Weak: a window destroyed while this
  // mapper was not in it must not be touched again.
  vtkWeakPointer<vtkRenderWindow> LastWindow;
  vtkNew<vtkOpenGLVertexBufferObject> VertexBuffer;
  vtkOpenGLHelper Triangles;
  vtkNew<vtkTextureObject> TransferFunction;
  vtkTimeStamp TransferFunctionUploadTime;
  vtkNew<vtkTextureObject> IntegralsHigh, IntegralsLow; // pre-integrated shading
  vtkNew<vtkTextureObject> ImageTexture;
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
  int SoftwareRenderer = -1; // of LastWindow: -1 unknown, 0 no, 1 yes

  // The transfer functions sampled over the scalar range (both backends read it).
  std::vector<float> Table;
  vtkTimeStamp TableBuildTime;
  vtkMTimeType TablePropertyTime = 0;
  vtkVolumeProperty* TableProperty = nullptr;
  double TableRange[2] = { 0, 0 };
  mtpt::PreIntegrationTable PreIntegration;     // integral functions of Table
  mtpt::PerspectiveInterpolation Interpolation; // of the current frame's projection

  // CPU backend.
  mtpt::Compositor Compositor;
  std::vector<float> Image, Depth, Colour;
  vtkNew<vtkOpenGLFramebufferObject> Framebuffer;
  bool FramebufferAllocated = false;
  bool FramebufferFailed = false;
  int FramebufferSize[2] = { 0, 0 };

  // What the pipeline's reusable results were computed from: a change of any of these
  // bumps DataVersion (FrameInput::dataVersion).
  struct DataKey
  {
    vtkUnstructuredGridBase* input = nullptr;
    vtkMTimeType inputTime = 0;
    vtkDataArray* scalars = nullptr;
    vtkMTimeType scalarTime = 0;
    int component = 0, cellFlag = 0;
    bool operator!=(const DataKey& o) const
    {
      return input != o.input || inputTime != o.inputTime || scalars != o.scalars ||
        scalarTime != o.scalarTime || component != o.component || cellFlag != o.cellFlag;
    }
  };
  DataKey LastData;
  std::uint64_t DataVersion = 0;
  // The OpenGL buffers hold the pipeline's whole (single-batch) decomposition.
  bool BuffersCurrent = false;

  // What GetBounds() last computed from.
  vtkUnstructuredGridBase* BoundsInput = nullptr;
  vtkMTimeType BoundsTime = 0;

  // Timers of the last frame.
  double UploadSeconds = 0, DrawSeconds = 0, CompositeSeconds = 0;
  int LastBackend = OPENGL_BACKEND;
  vtkIdType Tetrahedra = 0;

  // Messages are reported once per change of what caused them, not every frame: each
  // message once per modification time of the input it is about (several messages about
  // one input each appear once, not in turn every frame).
  vtkMTimeType BlendWarningTime = 0;
  std::map<std::string, vtkMTimeType> Reported;
  bool Report(vtkUnstructuredGridBase* input, const std::string& message)
  {
    const vtkMTimeType time = input->GetMTime();
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

void vtkMultiThreadedProjectedTetrahedraMapper::SetNumberOfThreads(int threads)
{
  if (threads < 0)
  {
    vtkWarningMacro(<< "SetNumberOfThreads(" << threads
                    << "): the thread count must be 0 (all cores) or positive; keeping "
                    << this->NumberOfThreads);
    return;
  }
  if (threads != this->NumberOfThreads)
  {
    this->NumberOfThreads = threads;
    this->Modified();
  }
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetOrderMethodAsString()
{
  return this->OrderMethod == PARTITION_SORT ? "PartitionSort" : "RadixSort";
}

const char* vtkMultiThreadedProjectedTetrahedraMapper::GetShadingModeAsString()
{
  return this->ShadingMode == PRE_INTEGRATED_SHADING ? "PreIntegrated" : "VTKCompatible";
}

double vtkMultiThreadedProjectedTetrahedraMapper::GetTransformSeconds()
{
  return this->Internal->Pipeline.Times().transform;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDepthKeySeconds()
{
  return this->Internal->Pipeline.Times().keys;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCullSeconds()
{
  return this->Internal->Pipeline.Times().cull;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetOrderSeconds()
{
  return this->Internal->Pipeline.Times().order;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDecomposeSeconds()
{
  return this->Internal->Pipeline.Times().decompose;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCPUStageSeconds()
{
  return this->Internal->Pipeline.Times().Total();
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetUploadSeconds()
{
  return this->Internal->UploadSeconds;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetDrawSeconds()
{
  return this->Internal->DrawSeconds;
}
double vtkMultiThreadedProjectedTetrahedraMapper::GetCompositeSeconds()
{
  return this->Internal->CompositeSeconds;
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetLastBackend()
{
  return this->Internal->LastBackend;
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
  return this->Internal->Tetrahedra;
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfOpacityCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.Stats().opacityCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfFrustumCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.Stats().frustumCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfPixelCulledCells()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.Stats().pixelCulled);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfNearClippedCells()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.Stats().nearClipped);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfNearClipPieces()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.Stats().nearPieces);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfTetrahedralizations()
{
  return this->Internal->Tetrahedralizer.GetNumberOfTetrahedralizations();
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetNumberOfBatches()
{
  return static_cast<int>(this->Internal->Pipeline.Stats().batches);
}
int vtkMultiThreadedProjectedTetrahedraMapper::GetLastFrameReuse()
{
  const mtpt::FrameStats& stats = this->Internal->Pipeline.Stats();
  return (stats.transformReused ? REUSED_TRANSFORM : 0) | (stats.orderReused ? REUSED_ORDER : 0) |
    (stats.orderFromPrevious ? ORDER_FROM_PREVIOUS : 0) |
    (stats.decompositionReused ? REUSED_DECOMPOSITION : 0);
}
vtkIdType vtkMultiThreadedProjectedTetrahedraMapper::GetMemoryBytes()
{
  return static_cast<vtkIdType>(this->Internal->Pipeline.MemoryBytes());
}
void vtkMultiThreadedProjectedTetrahedraMapper::SetBatchSize(vtkIdType size)
{
  if (size < 0)
  {
    vtkWarningMacro(<< "SetBatchSize(" << size
                    << "): the batch size must be 0 (one batch) or positive; keeping "
                    << this->BatchSize);
    return;
  }
  if (size != this->BatchSize)
  {
    this->BatchSize = size;
    this->Modified();
  }
}

double* vtkMultiThreadedProjectedTetrahedraMapper::GetBounds()
{
  vtkUnstructuredGridBase* input = this->GetInput();
  if (!input)
  {
    vtkMath::UninitializeBounds(this->Bounds);
    return this->Bounds;
  }
  this->Update();
  input = this->GetInput();
  Internals& in = *this->Internal;
  if (input == in.BoundsInput && input->GetMTime() == in.BoundsTime)
  {
    return this->Bounds;
  }
  in.BoundsInput = input;
  in.BoundsTime = input->GetMTime();
  vtkBoundingBox box;
  vtkPoints* points = input->GetPoints();
  if (points)
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
  in.VertexBuffer->ReleaseGraphicsResources();
  in.Triangles.ReleaseGraphicsResources(window);
  if (window)
  {
    in.TransferFunction->ReleaseGraphicsResources(window);
    in.IntegralsHigh->ReleaseGraphicsResources(window);
    in.IntegralsLow->ReleaseGraphicsResources(window);
    in.ImageTexture->ReleaseGraphicsResources(window);
    in.Framebuffer->ReleaseGraphicsResources(window);
    if (in.Quad)
    {
      in.Quad->ReleaseGraphicsResources(window);
    }
  }
  in.Quad.reset();
  in.BuffersCurrent = false;
  in.SoftwareRenderer = -1;
  in.FramebufferAllocated = false;
  in.FramebufferFailed = false;
  in.LastWindow = nullptr;
  this->Superclass::ReleaseGraphicsResources(window);
}

void vtkMultiThreadedProjectedTetrahedraMapper::Render(vtkRenderer* renderer, vtkVolume* volume)
{
  Internals& in = *this->Internal;
  in.UploadSeconds = in.DrawSeconds = in.CompositeSeconds = 0;
  in.Tetrahedra = 0;
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(renderer->GetRenderWindow());
  if (!window)
  {
    vtkErrorMacro(<< "needs an OpenGL render window (vtkOpenGLRenderWindow)");
    return;
  }
  if (in.LastWindow && in.LastWindow != window)
  {
    // GL resources belong to one context: release them there before moving windows.
    this->ReleaseGraphicsResources(in.LastWindow);
  }
  in.LastWindow = window;

  vtkUnstructuredGridBase* input = this->GetInput();
  if (!input)
  {
    vtkErrorMacro(<< "no input: connect an unstructured grid of tetrahedra");
    return;
  }
  if (input->GetNumberOfCells() == 0)
  {
    if (in.Report(input, "empty"))
    {
      vtkWarningMacro(<< "the input has no cells: nothing to draw");
    }
    return;
  }
  if (this->BlendMode != vtkUnstructuredGridVolumeMapper::COMPOSITE_BLEND &&
    in.BlendWarningTime != this->GetMTime())
  {
    in.BlendWarningTime = this->GetMTime(); // once per change of the mapper's settings
    vtkWarningMacro(<< "only composite blending is supported; drawing with it");
  }
  // Hexahedra, wedges, pyramids... are split into tetrahedra once per input change; from
  // here on `input` is the grid of tetrahedra that is drawn.
  vtkUnstructuredGridBase* tetrahedra = in.Tetrahedralizer.Update(input);
  if (!in.Tetrahedralizer.Warning().empty() && in.Report(input, in.Tetrahedralizer.Warning()))
  {
    vtkWarningMacro(<< in.Tetrahedralizer.Warning());
  }
  if (tetrahedra->GetNumberOfCells() == 0)
  {
    if (in.Report(input, "no 3D cells"))
    {
      vtkWarningMacro(<< "the input has no 3D cells: nothing to draw");
    }
    return;
  }
  input = tetrahedra;
  if (!in.Adapter.Update(input))
  {
    if (in.Report(input, in.Adapter.Error()))
    {
      vtkErrorMacro(<< "cannot render the input: " << in.Adapter.Error());
    }
    return;
  }
  if (!in.Adapter.Warning().empty() && in.Report(input, in.Adapter.Warning()))
  {
    vtkWarningMacro(<< in.Adapter.Warning());
  }

  // Scalars: the same selection rules as every VTK mapper.
  int cellFlag = 0;
  vtkDataArray* scalars = vtkAbstractMapper::GetScalars(
    input, this->ScalarMode, this->ArrayAccessMode, this->ArrayId, this->ArrayName, cellFlag);
  if (!scalars)
  {
    // Name the selection that found nothing (a misspelt array name is the usual cause).
    std::ostringstream selection;
    const bool pointField = this->ScalarMode == VTK_SCALAR_MODE_USE_POINT_FIELD_DATA;
    if (pointField || this->ScalarMode == VTK_SCALAR_MODE_USE_CELL_FIELD_DATA)
    {
      selection << " (selected: the " << (pointField ? "point" : "cell") << " array ";
      if (this->ArrayAccessMode == VTK_GET_ARRAY_BY_NAME)
      {
        selection << "named '" << this->ArrayName << "'";
      }
      else
      {
        selection << "number " << this->ArrayId;
      }
      selection << ", which the input does not have)";
    }
    if (in.Report(input, "no scalars" + selection.str()))
    {
      vtkErrorMacro(<< "the input has no scalars to map" << selection.str()
                    << ": give it point or cell scalars, or select an existing array with "
                       "SelectScalarArray() and SetScalarMode()");
    }
    return;
  }
  const vtkIdType needed = cellFlag ? input->GetNumberOfCells() : input->GetNumberOfPoints();
  if (scalars->GetNumberOfTuples() < needed)
  {
    if (in.Report(input, "short scalars"))
    {
      vtkErrorMacro(<< "the scalar array '" << (scalars->GetName() ? scalars->GetName() : "")
                    << "' has " << scalars->GetNumberOfTuples() << " tuples for " << needed
                    << (cellFlag ? " cells" : " points"));
    }
    return;
  }
  vtkVolumeProperty* property = volume->GetProperty();
  int component = -1; // magnitude
  if (property->GetColorChannels(0) == 1)
  {
    component = 0;
  }
  else if (property->GetRGBTransferFunction(0)->GetVectorMode() == vtkScalarsToColors::COMPONENT)
  {
    component = property->GetRGBTransferFunction(0)->GetVectorComponent();
  }
  double range[2];
  vtkIdType nonFinite = 0;
  const float* values = in.Adapter.Scalars(scalars, component, range, nonFinite);
  if (nonFinite > 0 && in.Report(input, "non-finite scalars"))
  {
    vtkWarningMacro(<< nonFinite
                    << " scalar values are NaN or infinite; the cells using them "
                       "are not drawn");
  }

  Internals::DataKey data;
  data.input = input;
  data.inputTime = input->GetMTime();
  data.scalars = scalars;
  data.scalarTime = scalars->GetMTime();
  data.component = component;
  data.cellFlag = cellFlag;
  if (data != in.LastData)
  {
    in.LastData = data;
    ++in.DataVersion;
  }
  this->UpdateTransferFunctionTable(property, range);

  int viewportSize[2] = { 0, 0 }, viewportOrigin[2] = { 0, 0 };
  renderer->GetTiledSizeAndOrigin(
    &viewportSize[0], &viewportSize[1], &viewportOrigin[0], &viewportOrigin[1]);
  if (viewportSize[0] <= 0 || viewportSize[1] <= 0)
  {
    // No pixel to draw (a zero-area viewport or tile): no work, and no message, as VTK's
    // own mappers. Its aspect ratio would not even give a usable projection.
    vtkDebugMacro(<< "the viewport has no pixels: nothing to draw");
    return;
  }

  mtpt::FrameInput frame;
  frame.points = in.Adapter.Points();
  frame.cells = in.Adapter.Cells();
  frame.scalars = { values,
    cellFlag ? mtpt::ScalarsView::Association::Cells : mtpt::ScalarsView::Association::Points };
  mtpt::ViewMatrices(renderer, volume, frame.modelView, frame.projection);
  frame.perspective = renderer->GetActiveCamera()->GetParallelProjection() == 0;
  // Orthographic projections give the linear default.
  this->Internal->Interpolation = mtpt::PerspectiveInterpolation::FromProjection(frame.projection);
  // Cells the opacity function hides are culled (exact: see mtpt/Culling.h).
  frame.opacity = { in.Table.data(), TransferFunctionTableSize, in.TableRange[0],
    in.TableRange[1] };
  frame.dataVersion = in.DataVersion;
  frame.opacityVersion = in.TableBuildTime.GetMTime();

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
  // Cells that cover no pixel centre produce no fragment when every pixel is sampled once
  // at its centre: always in the CPU compositor, in OpenGL unless the target multisamples.
  GLint sampleBuffers = 0;
  if (backend == OPENGL_BACKEND)
  {
    glGetIntegerv(GL_SAMPLE_BUFFERS, &sampleBuffers);
  }
  if (sampleBuffers == 0 && this->CullInvisibleCells)
  {
    int x0, y0;
    renderer->GetTiledSizeAndOrigin(&frame.viewportWidth, &frame.viewportHeight, &x0, &y0);
  }
  if (!this->CullInvisibleCells)
  {
    frame.opacity = mtpt::TransferFunctionTable{};
    frame.cullFrustum = false;
  }

  in.Pipeline.SetOrderMethod(this->OrderMethod == PARTITION_SORT ? mtpt::OrderMethod::PartitionSort
                                                                 : mtpt::OrderMethod::RadixSort,
    static_cast<std::size_t>(this->MaxSubArraySize));
  in.Pipeline.SetReuse(this->ReuseResults);
  if (!in.Pipeline.Prepare(frame, this->NumberOfThreads))
  {
    vtkErrorMacro(<< "the input has " << input->GetNumberOfCells()
                  << " cells; this mapper draws at most " << mtpt::FramePipeline::MaxTetrahedra());
    return;
  }
  in.Tetrahedra = static_cast<vtkIdType>(in.Pipeline.SortedCount());
  if (in.Tetrahedra == 0)
  {
    return; // everything culled: transparent or out of view
  }
  if (backend == CPU_BACKEND)
  {
    this->CompositeOnCPU(renderer, volume, window);
  }
  else
  {
    this->DrawTriangles(renderer, volume, window);
  }
}

std::size_t vtkMultiThreadedProjectedTetrahedraMapper::BatchTetrahedra() const
{
  const std::size_t sorted = this->Internal->Pipeline.SortedCount();
  return this->BatchSize > 0 ? std::min(sorted, static_cast<std::size_t>(this->BatchSize)) : sorted;
}

double vtkMultiThreadedProjectedTetrahedraMapper::UnitDistance(vtkVolume* volume)
{
  const double unitDistance = volume->GetProperty()->GetScalarOpacityUnitDistance(0);
  return unitDistance > 0 ? unitDistance : 1.0;
}

void vtkMultiThreadedProjectedTetrahedraMapper::CompositeOnCPU(
  vtkRenderer* renderer, vtkVolume* volume, vtkOpenGLRenderWindow* window)
{
  Internals& in = *this->Internal;
  int width = 0, height = 0, x0 = 0, y0 = 0;
  renderer->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width <= 0 || height <= 0)
  {
    return;
  }
  // The opaque geometry drawn so far occludes the volume: read its depth back.
  auto start = std::chrono::steady_clock::now();
  in.Depth.resize(static_cast<std::size_t>(width) * height);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(x0, y0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, in.Depth.data());
  double upload = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  mtpt::CompositeSettings settings;
  settings.width = width;
  settings.height = height;
  settings.transferFunction = { in.Table.data(), TransferFunctionTableSize, in.TableRange[0],
    in.TableRange[1] };
  settings.unitDistance = UnitDistance(volume);
  settings.opaqueDepth = in.Depth.data();
  if (this->ShadingMode == PRE_INTEGRATED_SHADING)
  {
    settings.UsePreIntegration(in.PreIntegration, in.Interpolation);
  }
  // Batch after batch, back to front, into one image. Decomposition and compositing both
  // use every thread, so they run one after the other.
  const std::size_t total = in.Pipeline.SortedCount(), batch = this->BatchTetrahedra();
  double composite = 0;
  std::size_t first = 0;
  do
  {
    in.Pipeline.DecomposeBatch(first, batch, this->NumberOfThreads);
    start = std::chrono::steady_clock::now();
    in.Compositor.Composite(in.Pipeline.Vertices().data(), in.Pipeline.Indices().data(),
      in.Pipeline.TetrahedronCount(), settings, in.Image, this->NumberOfThreads);
    composite += SecondsSince(start);
    settings.accumulate = true;
    first += batch;
  } while (first < total);
  in.CompositeSeconds = composite;

  // Composite over the colour drawn so far here, in float, and write the result back with
  // blending off: blending the image in OpenGL would round it to 8 bits before the blend
  // on an 8-bit framebuffer, a second rounding the OpenGL path does not have.
  start = std::chrono::steady_clock::now();
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  in.Colour.resize(4 * pixels);
  glReadPixels(x0, y0, width, height, GL_RGBA, GL_FLOAT, in.Colour.data());
  float* image = in.Image.data();
  const float* below = in.Colour.data();
  for (std::size_t i = 0; i < 4 * pixels; i += 4)
  {
    const float keep = 1.0f - image[i + 3];
    for (int c = 0; c < 4; ++c)
    {
      image[i + c] += keep * below[i + c];
    }
  }
  in.ImageTexture->SetContext(window);
  in.ImageTexture->SetWrapS(vtkTextureObject::ClampToEdge);
  in.ImageTexture->SetWrapT(vtkTextureObject::ClampToEdge);
  in.ImageTexture->SetMinificationFilter(vtkTextureObject::Nearest);
  in.ImageTexture->SetMagnificationFilter(vtkTextureObject::Nearest);
  in.ImageTexture->Create2DFromRaw(width, height, 4, VTK_FLOAT, in.Image.data());
  if (this->SynchronizedTiming)
  {
    glFinish();
  }
  in.UploadSeconds = upload + SecondsSince(start);

  start = std::chrono::steady_clock::now();
  if (!in.Quad)
  {
    in.Quad = std::make_unique<vtkOpenGLQuadHelper>(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), vtkMTPTCompositeFS, "");
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(in.Quad->Program);
  }
  if (!in.Quad->Program || !in.Quad->Program->GetCompiled())
  {
    vtkErrorMacro(<< "could not compile the compositing shader");
    return;
  }
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendSaver(state);
  vtkOpenGLState::ScopedglEnableDisable depthTestSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglEnableDisable blendEnableSaver(state, GL_BLEND);
  state->vtkglDepthMask(GL_FALSE);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDisable(GL_BLEND); // the image already holds what was drawn below it
  in.ImageTexture->Activate();
  in.Quad->Program->SetUniformi("image", in.ImageTexture->GetTextureUnit());
  in.Quad->Render();
  in.ImageTexture->Deactivate();
  if (this->SynchronizedTiming)
  {
    glFinish();
  }
  in.DrawSeconds = SecondsSince(start);
}

void vtkMultiThreadedProjectedTetrahedraMapper::DrawTriangles(
  vtkRenderer* renderer, vtkVolume* volume, vtkOpenGLRenderWindow* window)
{
  Internals& in = *this->Internal;
  vtkOpenGLState* state = window->GetState();

  // Program and vertex layout (the layout of mtpt::TetVertex).
  vtkShaderProgram* program = in.Triangles.Program;
  if (!program)
  {
    program =
      window->GetShaderCache()->ReadyShaderProgram(vtkMTPTTetrahedraVS, vtkMTPTTetrahedraFS, "");
    if (!program)
    {
      vtkErrorMacro(<< "could not compile the MTPT shaders");
      return;
    }
    in.Triangles.Program = program;
    in.Triangles.VAO->ShaderProgramChanged();
    in.Triangles.ShaderSourceTime.Modified();
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(program);
  }

  if (in.TransferFunctionUploadTime < in.TableBuildTime || in.TransferFunction->GetHandle() == 0)
  {
    in.TransferFunction->SetContext(window);
    in.TransferFunction->SetWrapS(vtkTextureObject::ClampToEdge);
    in.TransferFunction->SetWrapT(vtkTextureObject::ClampToEdge);
    in.TransferFunction->SetMinificationFilter(vtkTextureObject::Linear);
    in.TransferFunction->SetMagnificationFilter(vtkTextureObject::Linear);
    in.TransferFunction->Create2DFromRaw(
      TransferFunctionTableSize, 1, 4, VTK_FLOAT, in.Table.data());
    // The prefix integrals as float high + low parts (pre-integrated shading).
    const std::vector<double>& integrals = in.PreIntegration.integrals;
    std::vector<float> high(integrals.size()), low(integrals.size());
    for (std::size_t i = 0; i < integrals.size(); ++i)
    {
      high[i] = static_cast<float>(integrals[i]);
      low[i] = static_cast<float>(integrals[i] - high[i]);
    }
    for (vtkTextureObject* texture : { in.IntegralsHigh.Get(), in.IntegralsLow.Get() })
    {
      texture->SetContext(window);
      texture->SetWrapS(vtkTextureObject::ClampToEdge);
      texture->SetWrapT(vtkTextureObject::ClampToEdge);
      texture->SetMinificationFilter(vtkTextureObject::Nearest);
      texture->SetMagnificationFilter(vtkTextureObject::Nearest);
    }
    in.IntegralsHigh->Create2DFromRaw(TransferFunctionTableSize, 1, 4, VTK_FLOAT, high.data());
    in.IntegralsLow->Create2DFromRaw(TransferFunctionTableSize, 1, 4, VTK_FLOAT, low.data());
    in.TransferFunctionUploadTime.Modified();
  }
  in.TransferFunction->Activate();
  program->SetUniformi("transferFunction", in.TransferFunction->GetTextureUnit());
  const bool preIntegrated = this->ShadingMode == PRE_INTEGRATED_SHADING;
  program->SetUniformi("shadingMode", preIntegrated ? 1 : 0);
  program->SetUniformi("tableSize", TransferFunctionTableSize);
  if (preIntegrated)
  {
    in.IntegralsHigh->Activate();
    in.IntegralsLow->Activate();
    program->SetUniformi("integralsHigh", in.IntegralsHigh->GetTextureUnit());
    program->SetUniformi("integralsLow", in.IntegralsLow->GetTextureUnit());
  }
  const double low = in.TableRange[0], high = in.TableRange[1];
  // Texel centres: scalar `low` at 0.5/N, `high` at (N-0.5)/N.
  const double n = TransferFunctionTableSize;
  const double scale = (n - 1.0) / n / (high - low);
  program->SetUniformf("scalarScale", static_cast<float>(scale));
  program->SetUniformf("scalarShift", static_cast<float>(0.5 / n - low * scale));
  const double entryScale = (n - 1.0) / (high - low);
  program->SetUniformf("entryScale", static_cast<float>(entryScale));
  program->SetUniformf("entryShift", static_cast<float>(-low * entryScale));
  const mtpt::PerspectiveInterpolation& view = in.Interpolation;
  program->SetUniformi("perspectiveExact", preIntegrated && view.perspective ? 1 : 0);
  program->SetUniformf("inverseDepthScale", static_cast<float>(view.inverseWScale));
  program->SetUniformf("inverseDepthOffset", static_cast<float>(view.inverseWOffset));
  const float rayScale[2] = { static_cast<float>(view.scaleX), static_cast<float>(view.scaleY) };
  const float rayShift[2] = { static_cast<float>(view.shiftX), static_cast<float>(view.shiftY) };
  program->SetUniform2f("rayScale", rayScale);
  program->SetUniform2f("rayShift", rayShift);
  program->SetUniformf("inverseUnitDistance", static_cast<float>(1.0 / UnitDistance(volume)));

  int width = 0, height = 0, x0 = 0, y0 = 0;
  renderer->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  const bool floatTarget =
    this->UseFloatingPointFrameBuffer && this->PrepareFramebuffer(window, width, height);

  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendSaver(state);
  vtkOpenGLState::ScopedglEnableDisable depthTestSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglEnableDisable blendSaver2(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable cullSaver(state, GL_CULL_FACE);
  vtkOpenGLState::ScopedglViewport viewportSaver(state);
  vtkOpenGLState::ScopedglScissor scissorSaver(state);

  if (floatTarget)
  {
    // Copy what is drawn so far (colour and the opaque geometry's depth) into the float
    // target, blend there, and copy the colour back.
    state->PushFramebufferBindings();
    in.Framebuffer->Bind(vtkOpenGLFramebufferObject::GetDrawMode());
    in.Framebuffer->ActivateDrawBuffer(0);
    state->vtkglBlitFramebuffer(x0, y0, x0 + width, y0 + height, 0, 0, width, height,
      GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    state->vtkglViewport(0, 0, width, height);
    state->vtkglScissor(0, 0, width, height);
  }

  // VTK's PT state: depth test against opaque geometry without depth writes, back-to-front
  // "over" blending of non-premultiplied colour (DESIGN.md section 2, step 6).
  state->vtkglDepthMask(GL_FALSE);
  state->vtkglEnable(GL_DEPTH_TEST);
  state->vtkglEnable(GL_BLEND);
  state->vtkglDisable(GL_CULL_FACE);
  state->vtkglBlendFuncSeparate(
    GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);

  // Batch after batch: decompose, upload, draw. Draw calls return before the GPU is done,
  // so the next batch's decomposition overlaps the previous batch's drawing.
  const std::size_t total = in.Pipeline.SortedCount(), batch = this->BatchTetrahedra();
  const bool single = batch >= total;
  std::size_t first = 0;
  do
  {
    in.Pipeline.DecomposeBatch(first, batch, this->NumberOfThreads);
    const std::size_t count = in.Pipeline.TetrahedronCount();
    auto start = std::chrono::steady_clock::now();
    if (!(single && in.BuffersCurrent && in.Pipeline.Stats().decompositionReused))
    {
      in.VertexBuffer->SetStride(static_cast<unsigned int>(sizeof(mtpt::TetVertex)));
      in.VertexBuffer->Upload(reinterpret_cast<const float*>(in.Pipeline.Vertices().data()),
        count * mtpt::VerticesPerTetrahedron * 6, vtkOpenGLBufferObject::ArrayBuffer);
      in.Triangles.IBO->Upload(in.Pipeline.Indices().data(), count * mtpt::IndicesPerTetrahedron,
        vtkOpenGLBufferObject::ElementArrayBuffer);
      in.Triangles.IBO->IndexCount = count * mtpt::IndicesPerTetrahedron;
      if (this->SynchronizedTiming)
      {
        glFinish();
      }
    }
    in.BuffersCurrent = single;
    in.UploadSeconds += SecondsSince(start);

    start = std::chrono::steady_clock::now();
    in.VertexBuffer->Bind();
    in.Triangles.VAO->Bind();
    if (in.Triangles.ShaderSourceTime > in.Triangles.AttributeUpdateTime)
    {
      const auto stride = sizeof(mtpt::TetVertex);
      if (!in.Triangles.VAO->AddAttributeArray(
            program, in.VertexBuffer, "vertexNDC", 0, stride, VTK_FLOAT, 3, false) ||
        !in.Triangles.VAO->AddAttributeArray(
          program, in.VertexBuffer, "scalarFrontBack", 12, stride, VTK_FLOAT, 2, false) ||
        !in.Triangles.VAO->AddAttributeArray(
          program, in.VertexBuffer, "thickness", 20, stride, VTK_FLOAT, 1, false))
      {
        vtkErrorMacro(<< "could not set the vertex attributes");
      }
      in.Triangles.AttributeUpdateTime.Modified();
    }
    in.Triangles.IBO->Bind();
    // GLsizei is 32-bit: draw in chunks of whole tetrahedra below that limit.
    const std::size_t indices = in.Triangles.IBO->IndexCount;
    const std::size_t chunk = (static_cast<std::size_t>(INT_MAX) / 12) * 12;
    for (std::size_t offset = 0; offset < indices; offset += chunk)
    {
      const std::size_t size = std::min(chunk, indices - offset);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(size), GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(offset * sizeof(std::uint32_t)));
    }
    in.Triangles.IBO->Release();
    in.Triangles.VAO->Release();
    in.VertexBuffer->Release();
    if (this->SynchronizedTiming)
    {
      glFinish();
    }
    in.DrawSeconds += SecondsSince(start);
    first += batch;
  } while (first < total);
  in.TransferFunction->Deactivate();
  if (preIntegrated)
  {
    in.IntegralsHigh->Deactivate();
    in.IntegralsLow->Deactivate();
  }

  if (floatTarget)
  {
    in.Framebuffer->Bind(vtkOpenGLFramebufferObject::GetReadMode());
    state->PopDrawFramebufferBinding();
    state->vtkglBlitFramebuffer(
      0, 0, width, height, x0, y0, x0 + width, y0 + height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    state->PopReadFramebufferBinding();
  }
}

bool vtkMultiThreadedProjectedTetrahedraMapper::PrepareFramebuffer(
  vtkOpenGLRenderWindow* window, int width, int height)
{
  Internals& in = *this->Internal;
  if (in.FramebufferFailed || width <= 0 || height <= 0)
  {
    return false;
  }
  // A multisampled target cannot take a depth blit into a single-sampled one.
  GLint sampleBuffers = 0;
  glGetIntegerv(GL_SAMPLE_BUFFERS, &sampleBuffers);
  if (sampleBuffers > 0)
  {
    return false;
  }
  vtkOpenGLState* state = window->GetState();
  if (!in.FramebufferAllocated)
  {
    state->PushFramebufferBindings();
    in.Framebuffer->SetContext(window);
    int depthBits = window->GetDepthBufferSize();
    const bool ok = in.Framebuffer->PopulateFramebuffer(
      width, height, true, 1, VTK_FLOAT, true, depthBits > 0 ? depthBits : 24, 0);
    const char* description = nullptr;
    const bool complete = ok &&
      vtkOpenGLFramebufferObject::GetFrameBufferStatus(
        vtkOpenGLFramebufferObject::GetDrawMode(), description);
    state->PopFramebufferBindings();
    if (!complete)
    {
      vtkWarningMacro(<< "no float framebuffer ("
                      << (description ? description : "allocation failed")
                      << "); blending in the window's own framebuffer");
      in.FramebufferFailed = true;
      return false;
    }
    in.FramebufferAllocated = true;
    in.FramebufferSize[0] = width;
    in.FramebufferSize[1] = height;
  }
  else if (in.FramebufferSize[0] != width || in.FramebufferSize[1] != height)
  {
    state->PushFramebufferBindings();
    in.Framebuffer->Bind();
    in.Framebuffer->Resize(width, height);
    in.Framebuffer->UnBind();
    state->PopFramebufferBindings();
    in.FramebufferSize[0] = width;
    in.FramebufferSize[1] = height;
  }
  return true;
}

void vtkMultiThreadedProjectedTetrahedraMapper::UpdateTransferFunctionTable(
  vtkVolumeProperty* property, const double range[2])
{
  Internals& in = *this->Internal;
  double low = range[0], high = range[1];
  if (!(high > low))
  {
    high = low + 1.0; // a constant field still needs a table with a width
  }
  if (in.TablePropertyTime >= property->GetMTime() && in.TableProperty == property &&
    in.TableRange[0] == low && in.TableRange[1] == high && !in.Table.empty())
  {
    return;
  }
  const int n = TransferFunctionTableSize;
  std::vector<float> rgb(3 * n), opacity(n);
  if (property->GetColorChannels(0) == 1)
  {
    std::vector<float> gray(n);
    property->GetGrayTransferFunction(0)->GetTable(low, high, n, gray.data());
    for (int i = 0; i < n; ++i)
    {
      rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = gray[i];
    }
  }
  else
  {
    property->GetRGBTransferFunction(0)->GetTable(low, high, n, rgb.data());
  }
  property->GetScalarOpacity(0)->GetTable(low, high, n, opacity.data());
  in.Table.resize(4 * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    in.Table[4 * i + 0] = rgb[3 * i + 0];
    in.Table[4 * i + 1] = rgb[3 * i + 1];
    in.Table[4 * i + 2] = rgb[3 * i + 2];
    in.Table[4 * i + 3] = opacity[i];
  }
  in.PreIntegration.Build({ in.Table.data(), n, low, high });
  in.TablePropertyTime = property->GetMTime();
  in.TableProperty = property;
  in.TableRange[0] = low;
  in.TableRange[1] = high;
  in.TableBuildTime.Modified();
}

void vtkMultiThreadedProjectedTetrahedraMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfThreads: " << this->NumberOfThreads
     << (this->NumberOfThreads == 0 ? " (all cores)" : "") << "\n";
  os << indent << "Backend: "
     << (this->Backend == AUTOMATIC_BACKEND ? "Automatic"
                                            : (this->Backend == CPU_BACKEND ? "CPU" : "OpenGL"))
     << " (last frame: " << (this->Internal->LastBackend == CPU_BACKEND ? "CPU" : "OpenGL")
     << ")\n";
  os << indent << "OrderMethod: " << this->GetOrderMethodAsString() << "\n";
  os << indent << "ShadingMode: " << this->GetShadingModeAsString() << "\n";
  os << indent << "MaxSubArraySize: " << this->MaxSubArraySize << "\n";
  os << indent << "UseFloatingPointFrameBuffer: " << this->UseFloatingPointFrameBuffer << "\n";
  os << indent << "SynchronizedTiming: " << this->SynchronizedTiming << "\n";
  os << indent << "BatchSize: " << this->BatchSize << (this->BatchSize == 0 ? " (one batch)" : "")
     << "\n";
  os << indent << "ReuseResults: " << this->ReuseResults << "\n";
  os << indent << "CullInvisibleCells: " << this->CullInvisibleCells << "\n";
  const mtpt::FrameStats& stats = this->Internal->Pipeline.Stats();
  os << indent << "Last frame culled: " << stats.opacityCulled << " transparent, "
     << stats.frustumCulled << " outside the view, " << stats.pixelCulled << " covering no pixel; "
     << stats.batches << " batches; " << this->GetMemoryBytes() << " bytes of buffers\n";
  os << indent << "Last frame: " << this->Internal->Tetrahedra << " tetrahedra; transform "
     << this->GetTransformSeconds() << " s, cull " << this->GetCullSeconds() << " s, depth keys "
     << this->GetDepthKeySeconds() << " s, order " << this->GetOrderSeconds() << " s, decompose "
     << this->GetDecomposeSeconds() << " s, upload " << this->GetUploadSeconds() << " s, draw "
     << this->GetDrawSeconds() << " s\n";
}
