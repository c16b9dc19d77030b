// SPDX-License-Identifier: BSD-3-Clause
#include "CPUBackend.h"

#include "TransferFunctionTables.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/Timing.h"

#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLState.h"
#include "vtkTextureObject.h"
#include "vtk_glew.h"

#include <algorithm>
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

CPUBackend::CPUBackend() = default;
CPUBackend::~CPUBackend() = default;

bool CPUBackend::SamplesPixelCentresOnly(vtkOpenGLRenderWindow*, bool) const
{
  return true; // the compositor samples each pixel once, at its centre
}

bool CPUBackend::Draw(const BackendFrame& frame, BackendTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  if (!this->ReadBack(frame, times))
  {
    return false; // nothing was written
  }
  this->Composite(frame, times);
  return this->WriteBack(frame, times);
}

bool CPUBackend::ReadBack(const BackendFrame& frame, BackendTimes& times)
{
  const auto start = Clock::now();
  if (!this->Target.Capture(frame.window, frame.origin, frame.size, this->ErrorMessage))
  {
    return false;
  }
  const std::size_t pixels = static_cast<std::size_t>(frame.size[0]) * frame.size[1];
  this->Depth.resize(pixels);
  this->Below.resize(4 * pixels);
  vtkOpenGLState* state = frame.window->GetState();
  state->vtkglPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(
    0, 0, frame.size[0], frame.size[1], GL_DEPTH_COMPONENT, GL_FLOAT, this->Depth.data());
  glReadPixels(0, 0, frame.size[0], frame.size[1], GL_RGBA, GL_FLOAT, this->Below.data());
  if (ReadBackFaultInjected())
  {
    glReadPixels(0, 0, frame.size[0], frame.size[1], GL_RGBA, GL_DEPTH_COMPONENT, nullptr);
  }
  const std::string failed = TakeOpenGLErrors();
  this->Target.Restore(frame.window);
  times.upload += SecondsSince(start);
  if (!failed.empty())
  {
    this->ErrorMessage = "reading the window's colour and depth back failed (" + failed + ")";
    return false;
  }
  return true;
}

void CPUBackend::Composite(const BackendFrame& frame, BackendTimes& times)
{
  CompositeSettings settings;
  settings.width = frame.size[0];
  settings.height = frame.size[1];
  settings.transferFunction = frame.tables->Table();
  settings.unitDistance = frame.unitDistance;
  settings.opaqueDepth = this->Depth.data();
  if (frame.shading == Shading::PreIntegrated)
  {
    settings.UsePreIntegration(frame.tables->PreIntegration(), frame.interpolation);
  }
  // Batch after batch, back to front, into one image. Decomposition and compositing both
  // use every thread, so they run one after the other.
  FramePipeline& pipeline = *frame.pipeline;
  const std::size_t total = pipeline.SortedCount();
  const std::size_t batch = std::max<std::size_t>(1, frame.batchSize);
  for (std::size_t first = 0; first < total; first += batch)
  {
    auto start = Clock::now();
    pipeline.DecomposeBatch(first, batch, frame.threads);
    times.decompose += SecondsSince(start);
    start = Clock::now();
    this->Compositing.Composite(pipeline.Vertices().data(), pipeline.Indices().data(),
      pipeline.TetrahedronCount(), settings, this->Rgba, frame.threads);
    times.composite += SecondsSince(start);
    ++times.batches;
    settings.accumulate = true;
    const std::size_t done = std::min(total, first + batch);
    if (done < total && frame.afterBatch &&
      !frame.afterBatch(static_cast<double>(done) / static_cast<double>(total)))
    {
      times.stopped = true;
      break;
    }
  }
}

bool CPUBackend::WriteBack(const BackendFrame& frame, BackendTimes& times)
{
  // Composite over the colour drawn so far here, in float, and write the result with
  // blending off: blending the image in OpenGL would round it to 8 bits before the blend on
  // an 8-bit framebuffer (llvmpipe blends unorm8 targets in 8-bit arithmetic), a second
  // rounding the OpenGL path does not have.
  auto start = Clock::now();
  float* image = this->Rgba.data();
  const float* below = this->Below.data();
  for (std::size_t i = 0; i < this->Rgba.size(); i += 4)
  {
    const float keep = 1.0f - image[i + 3];
    for (int c = 0; c < 4; ++c)
    {
      image[i + c] += keep * below[i + c];
    }
  }
  this->Image->SetContext(frame.window);
  this->Image->SetWrapS(vtkTextureObject::ClampToEdge);
  this->Image->SetWrapT(vtkTextureObject::ClampToEdge);
  this->Image->SetMinificationFilter(vtkTextureObject::Nearest);
  this->Image->SetMagnificationFilter(vtkTextureObject::Nearest);
  this->Image->Create2DFromRaw(frame.size[0], frame.size[1], 4, VTK_FLOAT, image);
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  times.upload += SecondsSince(start);
  start = Clock::now();
  const bool written = this->Target.WriteToWindow(
    frame.window, this->Image, frame.origin, frame.size, this->ErrorMessage);
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  times.draw += SecondsSince(start);
  return written;
}

void CPUBackend::ReleaseGraphicsResources(vtkWindow* window)
{
  if (window)
  {
    this->Image->ReleaseGraphicsResources(window);
  }
  this->Target.ReleaseGraphicsResources(window);
}

} // namespace mtpt
