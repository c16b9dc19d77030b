// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/CPUBackend.h"

#include "Drawing/VolumetricPeel.h"
#include "Input/TransferFunctionTables.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/Timing.h"

#include <climits>

namespace mtpt
{

CPUBackend::CPUBackend() = default;
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
  if (!this->Path.Capture(frame, times, this->ErrorMessage))
  {
    return false;
  }
  const ImageKey key = ImageKey::Of(frame);
  times.imageReused = this->HaveImage && key == this->Kept && this->Path.DepthAsKept();
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
    this->Path.KeepDepth(); // read into the other buffer next frame
  }
  const bool written = this->Path.WriteBack(frame, this->Compositing, times, this->ErrorMessage);
  times.viewport += times.upload + times.draw;
  return written;
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
  key.clipPlanes = frame.clipPlanes;
  key.blendMode = frame.blendMode;
  key.averageRange[0] = frame.averageRange[0];
  key.averageRange[1] = frame.averageRange[1];
  key.lit = frame.lighting != nullptr;
  if (key.lit)
  {
    key.lighting = *frame.lighting;
    key.normals = frame.normalsVersion;
  }
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
    a.scaleY == b.scaleY && a.shiftY == b.shiftY && clipPlanes == o.clipPlanes &&
    blendMode == o.blendMode && averageRange[0] == o.averageRange[0] &&
    averageRange[1] == o.averageRange[1] && lit == o.lit && lighting == o.lighting &&
    normals == o.normals;
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
  settings.opaqueDepth = ranges ? nullptr : this->Path.OpaqueDepth();
  settings.depthRange = ranges;
  settings.clipping = frame.clipping;
  settings.clipPlanes = frame.clipPlanes;
  settings.vertexColours = frame.vertexColours;
  if (frame.shading == Shading::PreIntegrated && !frame.vertexColours)
  {
    settings.UsePreIntegration(frame.tables->PreIntegration(), frame.interpolation);
  }
  settings.blendMode = frame.blendMode;
  if (ReducesInAnyOrder(frame.blendMode))
  {
    // Reductions interpolate the scalars as pre-integrated shading does.
    settings.interpolation = frame.interpolation;
    settings.intensity = &frame.tables->Intensity();
    settings.averageRange[0] = frame.averageRange[0];
    settings.averageRange[1] = frame.averageRange[1];
  }
  // Batch after batch, back to front, into one image: the tiles keep what earlier batches
  // drew. Decomposition and compositing both use every thread, so they take turns.
  FramePipeline& pipeline = *frame.pipeline;
  this->Compositing.Begin(settings);
  ForEachBatch(
    frame, times,
    [&](std::size_t first, std::size_t count)
    {
      pipeline.DecomposeFans(first, count, frame.threads);
      if (frame.lighting)
      {
        pipeline.LightWindow(first, count, *frame.lighting, frame.normals, frame.modelView,
          this->Lights, frame.threads);
      }
    },
    [&]
    {
      const auto start = Clock::now();
      this->Compositing.Composite(pipeline.Fans().data(), pipeline.FanCount(), frame.threads,
        frame.lighting ? this->Lights.data() : nullptr);
      times.composite += SecondsSince(start);
      return true;
    });
}

void CPUBackend::ReleaseGraphicsResources(vtkWindow* window)
{
  this->HaveImage = false;
  this->Path.ReleaseGraphicsResources(window);
}

} // namespace mtpt
