// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/ImagePath.h"

#include "mtpt/ImageSampling.h"
#include "mtpt/Timing.h"

#include "vtkActor2D.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkPropCollection.h"
#include "vtkRenderer.h"
#include "vtkTextureObject.h"
#include "vtkType.h"
#include "vtkVolume.h"
#include "Basics/OpenGLHeader.h"

namespace mtpt
{

ImagePath::ImagePath()
  : Target(VTK_UNSIGNED_CHAR)
{
}

ImagePath::~ImagePath() = default;

bool ImagePath::Capture(const BackendFrame& frame, DrawTimes& times, std::string& error)
{
  // The window's colour and depth, resolved to one sample per pixel; nothing is written to
  // the window before every read succeeded.
  const auto start = Clock::now();
  if (!this->Target.Capture(frame.window, frame.origin, frame.size, error))
  {
    return false;
  }
  const bool depthRead = this->ReadDepth(frame, error);
  times.upload += SecondsSince(start);
  if (!depthRead)
  {
    this->Target.Restore(frame.window);
  }
  return depthRead;
}

bool ImagePath::MayHaveOpaqueGeometry(vtkRenderer* renderer)
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

bool ImagePath::ReadDepth(const BackendFrame& frame, std::string& error)
{
  if (!MayHaveOpaqueGeometry(frame.renderer))
  {
    this->Depth.clear(); // no occlusion; Read still reports the errors of the capture
    return this->Target.Read(frame.window, 0, 0, 0, 0, nullptr, nullptr, error);
  }
  const bool sampled = frame.Sampled();
  std::vector<float>& viewport = sampled ? this->ViewportDepth : this->Depth;
  viewport.resize(static_cast<std::size_t>(frame.size[0]) * frame.size[1]);
  if (!this->Target.Read(
        frame.window, 0, 0, frame.size[0], frame.size[1], viewport.data(), nullptr, error))
  {
    return false;
  }
  if (sampled)
  {
    // Each sampled pixel is tested against the viewport pixel under its centre.
    const ImageSize& image = frame.Image();
    this->Depth.resize(static_cast<std::size_t>(image.width) * image.height);
    SampleDepth(viewport.data(), frame.size[0], frame.size[1], this->Depth.data(), image.width,
      image.height, frame.plan->threads);
  }
  return true;
}

bool ImagePath::WriteBack(
  const BackendFrame& frame, Compositor& compositor, DrawTimes& times, std::string& error)
{
  // Only the region the volume touched changes (for a sampled image, the viewport pixels the
  // magnification reads it into). It is composited over the colour that was there on the
  // CPU and written with blending off: blending it in OpenGL would round the volume's colour
  // to 8 bits before the blend (llvmpipe blends 8-bit targets in 8-bit arithmetic), a second
  // rounding the OpenGL path does not have.
  auto start = Clock::now();
  const PixelRegion region = compositor.TouchedRegion();
  const ImageSize& image = frame.Image();
  const PixelRegion target = frame.Sampled()
    ? MagnifiedRegion(region, image.width, image.height, frame.size[0], frame.size[1])
    : region;
  const int width = target.x1 - target.x0, height = target.y1 - target.y0;
  bool colourRead = true;
  if (!target.Empty())
  {
    this->Below.resize(4 * static_cast<std::size_t>(width) * height);
    colourRead = this->Target.Read(
      frame.window, target.x0, target.y0, width, height, nullptr, this->Below.data(), error);
  }
  this->Target.Restore(frame.window);
  times.upload += SecondsSince(start);
  if (!colourRead || target.Empty())
  {
    return colourRead;
  }
  start = Clock::now();
  this->Region.resize(4 * static_cast<std::size_t>(width) * height);
  this->Resolve(frame, compositor, region, target);
  if (frame.Sampled())
  {
    times.viewport += SecondsSince(start);
  }
  times.composite += SecondsSince(start);
  return this->Upload(frame, target, times, error);
}

void ImagePath::Resolve(const BackendFrame& frame, Compositor& compositor,
  const PixelRegion& region, const PixelRegion& target)
{
  if (!frame.Sampled())
  {
    compositor.Resolve(region, this->Below.data(), this->Region.data(), frame.plan->threads);
    return;
  }
  const std::size_t width = static_cast<std::size_t>(region.x1 - region.x0);
  this->Sampled.resize(4 * width * static_cast<std::size_t>(region.y1 - region.y0));
  compositor.Resolve(region, nullptr, this->Sampled.data(), frame.plan->threads);
  const SampledImage image{ this->Sampled.data(), region, frame.Image().width,
    frame.Image().height };
  MagnifyOver(image, frame.size[0], frame.size[1], target, this->Below.data(), this->Region.data(),
    frame.plan->threads);
}

bool ImagePath::Upload(
  const BackendFrame& frame, const PixelRegion& target, DrawTimes& times, std::string& error)
{
  auto start = Clock::now();
  const int width = target.x1 - target.x0, height = target.y1 - target.y0;
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
  const bool written = this->Target.WriteToWindow(frame.window, this->Image, origin, size, error);
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  times.draw += SecondsSince(start);
  return written;
}

void ImagePath::ReleaseGraphicsResources(vtkWindow* window)
{
  if (window)
  {
    this->Image->ReleaseGraphicsResources(window);
  }
  this->Target.ReleaseGraphicsResources(window);
}

} // namespace mtpt
