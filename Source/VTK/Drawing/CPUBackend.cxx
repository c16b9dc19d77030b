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

bool CPUBackend::SamplesPixelCentresOnly(bool, bool) const
{
  return true; // the compositor samples each pixel once, at its centre
}

int CPUBackend::SampledImageLimit(vtkOpenGLRenderWindow*)
{
  return INT_MAX; // the image lives in the compositor's tiles; only the viewport is uploaded
}

bool CPUBackend::Draw(const BackendFrame& frame, DrawTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  if (!this->PlannedFor(frame, BatchTarget::Fans))
  {
    return false;
  }
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
    // The compositor's image is this frame's from here: never the kept one, should
    // compositing fail partway (an allocation: std::bad_alloc).
    this->HaveImage = false;
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
  key.plan = *frame.plan;
  key.unitDistance = frame.UnitDistance();
  const FrameLighting& lighting = frame.pipeline->LightingOfFrame();
  if (frame.plan->lit)
  {
    key.lighting = lighting.lighting;
    key.normals = lighting.normalsVersion;
  }
  return key;
}

bool CPUBackend::ImageKey::operator==(const ImageKey& o) const
{
  const FramePlan &a = this->plan, &b = o.plan;
  const PerspectiveInterpolation &ia = a.interpolation, &ib = b.interpolation;
  return pipeline == o.pipeline && order == o.order && tables == o.tables &&
    a.batchSize == b.batchSize && a.imageSize == b.imageSize && a.shading == b.shading &&
    a.vertexColours == b.vertexColours && unitDistance == o.unitDistance &&
    ia.perspective == ib.perspective && ia.inverseWScale == ib.inverseWScale &&
    ia.inverseWOffset == ib.inverseWOffset && ia.scaleX == ib.scaleX && ia.shiftX == ib.shiftX &&
    ia.scaleY == ib.scaleY && ia.shiftY == ib.shiftY && a.clipPlanes == b.clipPlanes &&
    a.blendMode == b.blendMode && a.averageRange[0] == b.averageRange[0] &&
    a.averageRange[1] == b.averageRange[1] && a.lit == b.lit && lighting == o.lighting &&
    normals == o.normals;
}

bool CPUBackend::DrawPeel(const BackendFrame& frame, DrawTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  if (!this->PlannedFor(frame, BatchTarget::Fans))
  {
    return false;
  }
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
      static_cast<const float*>(nullptr), image.data(), frame.plan->threads);
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

void CPUBackend::Composite(const BackendFrame& frame, DrawTimes& times, const float* ranges)
{
  const TransferFunctionTables& tables = *frame.tables;
  this->Settings = CompositeSettingsFor(
    *frame.plan, tables.Table(), tables.PreIntegration(), tables.Intensity(), frame.UnitDistance());
  this->Settings.opaqueDepth = ranges ? nullptr : this->Path.OpaqueDepth();
  this->Settings.depthRange = ranges;
  // Batch after batch into one image: the tiles keep what earlier batches drew. Composite
  // blending takes the batches front to back (FramePlan::frontToBack): each tile goes on
  // blending under what it holds, and the cells of later batches behind the pixels made
  // opaque are not decomposed (Compositor::Opaque). Decomposition and compositing both use
  // every thread, so they take turns.
  this->Compositing.Begin(this->Settings);
  const int threads = frame.plan->threads;
  const bool behind = frame.plan->frontToBack;
  Drawn(frame.pipeline->DrawBatches(
          *frame.plan,
          [&](const Batch& batch)
          {
            const auto start = Clock::now();
            if (behind)
            {
              this->Compositing.CompositeBehind(
                batch.fans, batch.count, threads, batch.lights, batch.classes);
            }
            else
            {
              this->Compositing.Composite(
                batch.fans, batch.count, threads, batch.lights, batch.classes);
            }
            times.composite += SecondsSince(start);
            return true;
          },
          &this->Compositing.Opaque()),
    times);
}

void CPUBackend::ReleaseGraphicsResources(vtkWindow* window)
{
  this->HaveImage = false;
  this->Path.ReleaseGraphicsResources(window);
}

} // namespace mtpt
