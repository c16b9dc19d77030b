// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CPUBackend.h
 * @brief Private glue: the way to the screen where OpenGL is itself a CPU rasterizer.
 *
 * Reads back the colour and the opaque depth the renderer drew in its viewport (through
 * BlendTarget, so multisampled windows are resolved first), has the pipeline decompose the
 * sorted tetrahedra into fans (no OpenGL slot buffers), composites them on the CPU with the
 * per-fragment math of the OpenGL path (mtpt::Compositor), and writes back only the region
 * the volume touched, composited over the colour that was there. Every OpenGL read is
 * checked before anything is written: a failed read leaves the window untouched and Draw
 * returns false, so the mapper can fall back to the OpenGL backend instead of drawing
 * garbage.
 *
 * What it keeps between frames: the image texture and the target (one context; released in
 * ReleaseGraphicsResources), the compositor's buffers, and its read-back buffers.
 */
#ifndef mtpt_CPUBackend_h
#define mtpt_CPUBackend_h

#include "BlendTarget.h"
#include "RenderBackend.h"

#include "mtpt/Compositor.h"

#include "vtkNew.h"

#include <cstdint>
#include <vector>

class vtkTextureObject;

namespace mtpt
{

class CPUBackend : public RenderBackend
{
public:
  CPUBackend();
  ~CPUBackend() override;

  bool SamplesPixelCentresOnly(
    vtkOpenGLRenderWindow* window, bool floatFramebuffer) const override;
  bool Draw(const BackendFrame& frame, BackendTimes& times) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

  /// The compositor's work in the last Draw.
  const CompositorStats& Stats() const { return this->Compositing.Stats(); }

private:
  CPUBackend(const CPUBackend&) = delete;
  void operator=(const CPUBackend&) = delete;

  bool ReadBack(const BackendFrame& frame, BackendTimes& times);
  void Composite(const BackendFrame& frame, BackendTimes& times);
  bool WriteBack(const BackendFrame& frame, BackendTimes& times);

  Compositor Compositing;
  CompositeSettings Settings;
  BlendTarget Target;
  vtkNew<vtkTextureObject> Image;
  std::vector<float> Depth;
  std::vector<std::uint8_t> Below, Region;
};

} // namespace mtpt

#endif
