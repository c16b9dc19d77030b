// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/CPUBackend.h"

#include "Drawing/VolumetricPeel.h"
#include "Input/TransferFunctionTables.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/ImageSampling.h"
#include "mtpt/Timing.h"

#include "vtkActor2D.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkPropCollection.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkOpenGLState.h"
#include "vtkTextureObject.h"
#include "vtkType.h"
#include "Basics/OpenGLHeader.h"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace mtpt
{

namespace
{

/// Testing only: MTPT_TESTING_FAULT=cpu-read-back makes the read-back fail with a real
/// OpenGL error, to exercise the path a failing driver takes (see the robustness tests).
bool ReadBackFaultInjected()
{
  const char* fault = std::getenv("MTPT_TESTING_FAULT");
  return fault && std::strcmp(fault, "cpu-read-back") == 0;
}

} // namespace

CPUBackend::CPUBackend()
  : Target(VTK_UNSIGNED_CHAR)
{
}

CPUBackend::~CPUBackend() = default;

bool CPUBackend::SamplesPixelCentresOnly(const BackendFrame&) const
{
  return true; // the compositor samples each pixel once, at its centre
}

int CPUBackend::SampledImageLimit(vtkOpenGLRenderWindow*)
{
  return INT_MAX; // the image lives in the compositor's tiles; only the viewport is uploaded
}

bool CPUBackend::Draw(const BackendFrame& frame, BackendTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  // The window's colour and depth, resolved to one sample per pixel; nothing is written to
  // the window before every read succeeded.
  auto start = Clock::now();
  if (!this->Target.Capture(frame.window, frame.origin, frame.size, this->ErrorMessage))
  {
    return false;
  }
  const bool depthRead = this->ReadDepth(frame);
  times.upload += SecondsSince(start);
  if (!depthRead)
  {
    this->Target.Restore(frame.window);
    return false;
  }
  const ImageKey key = ImageKey::Of(frame);
  times.imageReused = this->HaveImage && key == this->Kept && this->Depth == this->KeptDepth;
  if (times.imageReused)
  {
    this->LastStats = CompositorStats{};
  }
  else
  {
    this->Composite(frame, times);
    this->LastStats = this->Compositing.Stats();
    // A stopped frame's image is incomplete: never reused.
    this->HaveImage = !times.stopped;
    this->Kept = key;
    this->Depth.swap(this->KeptDepth); // read into the other buffer next frame
  }
  // The colour beneath: of the viewport pixels the touched region reaches only.
  start = Clock::now();
  const PixelRegion region = this->Compositing.TouchedRegion();
  const PixelRegion target = frame.Sampled()
    ? MagnifiedRegion(
        region, frame.imageSize.width, frame.imageSize.height, frame.size[0], frame.size[1])
    : region;
  const bool colourRead = target.Empty() || this->ReadColour(frame, target);
  this->Target.Restore(frame.window);
  times.upload += SecondsSince(start);
  const bool written = colourRead && this->WriteBack(frame, region, target, times);
  times.viewport += times.upload + times.draw;
  return written;
}

bool CPUBackend::MayHaveOpaqueGeometry(vtkRenderer* renderer)
{
  // Volumes are drawn after the opaque and translucent geometry, and 2D props after the
  // volumes: with only those in the renderer, and its depth cleared, the depth buffer holds
  // the clear value, which occludes nothing.
  if (!renderer || renderer->GetPreserveDepthBuffer())
  {
    return true;
  }
  vtkPropCollection* props = renderer->GetViewProps();
  vtkCollectionSimpleIterator it;
  props->InitTraversal(it);
  while (vtkProp* prop = props->GetNextProp(it))
  {
    if (prop->GetVisibility() && !vtkVolume::SafeDownCast(prop) && !vtkActor2D::SafeDownCast(prop))
    {
      return true;
    }
  }
  return false;
}

bool CPUBackend::ReadDepth(const BackendFrame& frame)
{
  if (ReadBackFaultInjected())
  {
    glReadPixels(0, 0, 1, 1, GL_RGBA, GL_DEPTH_COMPONENT, nullptr); // an invalid read
  }
  if (!MayHaveOpaqueGeometry(frame.renderer))
  {
    this->Depth.clear(); // no occlusion; Read still reports the errors of the capture
    return this->Target.Read(frame.window, 0, 0, 0, 0, nullptr, nullptr, this->ErrorMessage);
  }
  const bool sampled = frame.Sampled();
  std::vector<float>& viewport = sampled ? this->ViewportDepth : this->Depth;
  viewport.resize(static_cast<std::size_t>(frame.size[0]) * frame.size[1]);
  if (!this->Target.Read(frame.window, 0, 0, frame.size[0], frame.size[1], viewport.data(), nullptr,
        this->ErrorMessage))
  {
    return false;
  }
  if (sampled)
  {
    // Each sampled pixel is tested against the viewport pixel under its centre.
    this->Depth.resize(static_cast<std::size_t>(frame.imageSize.width) * frame.imageSize.height);
    SampleDepth(viewport.data(), frame.size[0], frame.size[1], this->Depth.data(),
      frame.imageSize.width, frame.imageSize.height, frame.threads);
  }
  return true;
}

bool CPUBackend::ReadColour(const BackendFrame& frame, const PixelRegion& region)
{
  const int width = region.x1 - region.x0, height = region.y1 - region.y0;
  this->Below.resize(4 * static_cast<std::size_t>(width) * height);
  return this->Target.Read(frame.window, region.x0, region.y0, width, height, nullptr,
    this->Below.data(), this->ErrorMessage);
}

CPUBackend::ImageKey CPUBackend::ImageKey::Of(const BackendFrame& frame)
{
  ImageKey key;
  key.pipeline = frame.pipeline;
  key.order = frame.pipeline->OrderVersionNumber();
  key.tables = frame.tables->Version();
  key.batch = frame.batchSize;
  key.size = frame.imageSize;
  key.shading = frame.shading;
  key.vertexColours = frame.vertexColours;
  key.unitDistance = frame.unitDistance;
  key.interpolation = frame.interpolation;
  return key;
}

bool CPUBackend::ImageKey::operator==(const ImageKey& o) const
{
  const PerspectiveInterpolation &a = this->interpolation, &b = o.interpolation;
  return pipeline == o.pipeline && order == o.order && tables == o.tables && batch == o.batch &&
    size == o.size && shading == o.shading &&
    vertexColours == o.vertexColours && unitDistance == o.unitDistance &&
    a.perspective == b.perspective && a.inverseWScale == b.inverseWScale &&
    a.inverseWOffset == b.inverseWOffset && a.scaleX == b.scaleX && a.shiftX == b.shiftX &&
    a.scaleY == b.scaleY && a.shiftY == b.shiftY;
}

bool CPUBackend::DrawPeel(const BackendFrame& frame, BackendTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  // The compositor's image will be a peel's, not the kept frame's.
  this->HaveImage = false;
  auto start = Clock::now();
  if (!frame.peel->ReadRanges(
        frame.window, this->PeelRanges[0], this->PeelRanges[1], this->ErrorMessage))
  {
    return false;
  }
  times.upload += SecondsSince(start);
  CompositorStats stats;
  for (int which = 0; which < 2 && !times.stopped; ++which)
  {
    this->Composite(frame, times, this->PeelRanges[which].data());
    start = Clock::now();
    std::vector<float>& image = this->PeelColours[which];
    image.resize(4 * static_cast<std::size_t>(frame.size[0]) * frame.size[1]);
    this->Compositing.Resolve({ 0, 0, frame.size[0], frame.size[1] },
      static_cast<const float*>(nullptr), image.data(), frame.threads);
    times.composite += SecondsSince(start);
    const CompositorStats& part = this->Compositing.Stats();
    stats.fans += part.fans;
    stats.binEntries += part.binEntries;
    stats.triangles += part.triangles;
    stats.fragments += part.fragments;
    stats.tiles += part.tiles;
    stats.binSeconds += part.binSeconds;
    stats.rasterSeconds += part.rasterSeconds;
  }
  this->LastStats = stats;
  start = Clock::now();
  const bool uploaded = frame.peel->UploadColours(
    frame.window, this->PeelColours[0].data(), this->PeelColours[1].data(), this->ErrorMessage);
  times.upload += SecondsSince(start);
  return uploaded;
}

void CPUBackend::Composite(const BackendFrame& frame, BackendTimes& times, const float* ranges)
{
  CompositeSettings& settings = this->Settings;
  settings = CompositeSettings{};
  settings.width = frame.imageSize.width;
  settings.height = frame.imageSize.height;
  settings.transferFunction = frame.tables->Table();
  settings.unitDistance = frame.unitDistance;
  settings.opaqueDepth = this->Depth.empty() || ranges ? nullptr : this->Depth.data();
  settings.depthRange = ranges;
  settings.clipping = frame.clipping;
  settings.vertexColours = frame.vertexColours;
  if (frame.shading == Shading::PreIntegrated && !frame.vertexColours)
  {
    settings.UsePreIntegration(frame.tables->PreIntegration(), frame.interpolation);
  }
  // Batch after batch, back to front, into one image: the tiles keep what earlier batches
  // drew. Decomposition and compositing both use every thread, so they take turns.
  FramePipeline& pipeline = *frame.pipeline;
  this->Compositing.Begin(settings);
  ForEachBatch(
    frame, times,
    [&](std::size_t first, std::size_t count)
    { pipeline.DecomposeFans(first, count, frame.threads); },
    [&]
    {
      const auto start = Clock::now();
      this->Compositing.Composite(pipeline.Fans().data(), pipeline.FanCount(), frame.threads);
      times.composite += SecondsSince(start);
      return true;
    });
}

void CPUBackend::Magnify(
  const BackendFrame& frame, const PixelRegion& region, const PixelRegion& target)
{
  const std::size_t width = static_cast<std::size_t>(region.x1 - region.x0);
  this->Sampled.resize(4 * width * static_cast<std::size_t>(region.y1 - region.y0));
  this->Compositing.Resolve(region, nullptr, this->Sampled.data(), frame.threads);
  const SampledImage image{ this->Sampled.data(), region, frame.imageSize.width,
    frame.imageSize.height };
  MagnifyOver(image, frame.size[0], frame.size[1], target, this->Below.data(), this->Region.data(),
    frame.threads);
}

bool CPUBackend::WriteBack(const BackendFrame& frame, const PixelRegion& region,
  const PixelRegion& target, BackendTimes& times)
{
  // Only the region the volume touched changes (for a sampled image, the viewport pixels the
  // magnification reads it into). It is composited over the colour that was there on the
  // CPU and written with blending off: blending it in OpenGL would round the volume's colour
  // to 8 bits before the blend (llvmpipe blends 8-bit targets in 8-bit arithmetic), a second
  // rounding the OpenGL path does not have.
  if (target.Empty())
  {
    return true;
  }
  auto start = Clock::now();
  const int width = target.x1 - target.x0, height = target.y1 - target.y0;
  this->Region.resize(4 * static_cast<std::size_t>(width) * height);
  if (frame.Sampled())
  {
    this->Magnify(frame, region, target);
    times.viewport += SecondsSince(start);
  }
  else
  {
    this->Compositing.Resolve(region, this->Below.data(), this->Region.data(), frame.threads);
  }
  times.composite += SecondsSince(start);
  start = Clock::now();
  this->Image->SetContext(frame.window);
  this->Image->SetWrapS(vtkTextureObject::ClampToEdge);
  this->Image->SetWrapT(vtkTextureObject::ClampToEdge);
  this->Image->Create2DFromRaw(width, height, 4, VTK_UNSIGNED_CHAR, this->Region.data());
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  times.upload += SecondsSince(start);
  start = Clock::now();
  const int origin[2] = { frame.origin[0] + target.x0, frame.origin[1] + target.y0 };
  const int size[2] = { width, height };
  const bool written =
    this->Target.WriteToWindow(frame.window, this->Image, origin, size, this->ErrorMessage);
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  times.draw += SecondsSince(start);
  return written;
}

void CPUBackend::ReleaseGraphicsResources(vtkWindow* window)
{
  this->HaveImage = false;
  if (window)
  {
    this->Image->ReleaseGraphicsResources(window);
  }
  this->Target.ReleaseGraphicsResources(window);
}

} // namespace mtpt
