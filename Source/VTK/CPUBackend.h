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
 * ReleaseGraphicsResources), the compositor's buffers, and its read-back buffers. The
 * composited image itself is reused by a frame whose ImageKey and opaque depth equal those
 * it was made with (an unchanged view, data, transfer function, window size and opaque
 * geometry): that frame only reads back, resolves the image over the new colour beneath it
 * and writes it, which is what keeps an unchanged frame cheap.
 */
#ifndef mtpt_CPUBackend_h
#define mtpt_CPUBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "BlendTarget.h"
#include "RenderBackend.h"

#include "mtpt/Compositor.h"

#include "vtkNew.h"

#include <cstdint>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkRenderer;
class vtkTextureObject;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class CPUBackend : public RenderBackend
{
public:
  CPUBackend();
  ~CPUBackend() override;

  bool SamplesPixelCentresOnly(vtkOpenGLRenderWindow* window, bool floatFramebuffer) const override;
  bool Draw(const BackendFrame& frame, BackendTimes& times) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

  /// The compositor's work in the last Draw (zero counts when it reused its image).
  const CompositorStats& Stats() const { return this->LastStats; }

private:
  CPUBackend(const CPUBackend&) = delete;
  void operator=(const CPUBackend&) = delete;

  /**
   * Everything the composited image depends on besides the opaque depth. The order's
   * version stands for the view, the projection (and so the interpolation), the data, the
   * culling and the viewport; the tables' version for the transfer functions.
   */
  struct ImageKey
  {
    const FramePipeline* pipeline = nullptr;
    std::uint64_t order = 0, tables = 0;
    std::size_t batch = 0;
    int size[2] = { 0, 0 };
    Shading shading = Shading::VTKCompatible;
    bool vertexColours = false;
    double unitDistance = 0;
    PerspectiveInterpolation interpolation;

    static ImageKey Of(const BackendFrame& frame);
    bool operator==(const ImageKey& other) const;
  };

  /// Whether opaque geometry may have written depth that the volume must respect.
  static bool MayHaveOpaqueGeometry(vtkRenderer* renderer);
  /// The captured depth of the viewport into Depth, or Depth empty where it is the clear value.
  bool ReadDepth(const BackendFrame& frame);
  /// The captured colour of `region` into Below.
  bool ReadColour(const BackendFrame& frame, const PixelRegion& region);
  void Composite(const BackendFrame& frame, BackendTimes& times);
  bool WriteBack(const BackendFrame& frame, const PixelRegion& region, BackendTimes& times);

  Compositor Compositing;
  CompositeSettings Settings;
  CompositorStats LastStats;
  bool HaveImage = false; ///< the compositor holds the complete image of Kept
  ImageKey Kept;
  std::vector<float> KeptDepth; ///< the opaque depth the kept image was composited with
  std::vector<float> Depth;     ///< this frame's opaque depth (empty: nothing opaque)
  BlendTarget Target;
  vtkNew<vtkTextureObject> Image;
  std::vector<std::uint8_t> Below, Region; ///< of the touched region
};

} // namespace mtpt

#endif
