// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CPUBackend.h
 * @brief Private glue: the way to the screen where OpenGL is itself a CPU rasterizer.
 *
 * Captures the viewport and its opaque depth (ImagePath), has the pipeline decompose the
 * sorted tetrahedra into fans (no OpenGL slot buffers), composites them on the CPU with the
 * per-fragment math of the OpenGL path (mtpt::Compositor) at the composited image's size
 * (FramePlan::imageSize), and writes back only the region the volume touched, composited
 * over the colour that was there (ImagePath again: at another image size, magnified first).
 * A failed read leaves the window untouched and Draw returns false, so the mapper can fall
 * back to the OpenGL backend instead of drawing garbage.
 *
 * What it keeps between frames: the image path's target, texture and buffers (one context;
 * released in ReleaseGraphicsResources) and the compositor's buffers. The composited image
 * itself is reused by a frame whose ImageKey and opaque depth equal those it was made with
 * (an unchanged view, data, transfer function, window size and opaque geometry): that frame
 * only reads back, resolves the image over the new colour beneath it and writes it, which
 * is what keeps an unchanged frame cheap.
 */
#ifndef mtpt_CPUBackend_h
#define mtpt_CPUBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "Drawing/ImagePath.h"
#include "Drawing/RenderBackend.h"

#include "mtpt/Compositor.h"

#include <cstdint>
#include <vector>

namespace mtpt
{

class CPUBackend : public RenderBackend
{
public:
  CPUBackend();
  ~CPUBackend() override;

  bool SamplesPixelCentresOnly(bool sampled, bool floatFramebuffer) const override;
  int SampledImageLimit(vtkOpenGLRenderWindow* window) override;
  bool Draw(const BackendFrame& frame, DrawTimes& times) override;
  bool DrawPeel(const BackendFrame& frame, DrawTimes& times) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

  /// The compositor's work in the last Draw (zero counts when it reused its image).
  const CompositorStats& Stats() const { return this->LastStats; }

private:
  CPUBackend(const CPUBackend&) = delete;
  void operator=(const CPUBackend&) = delete;

  /**
   * Everything the composited image depends on besides the opaque depth. The order's
   * version stands for the view, the projection (and so the interpolation), the data, the
   * culling and the viewport; the tables' version for the transfer functions; the plan for
   * the shading, blending, clipping, the composited image's size and the batches.
   */
  struct ImageKey
  {
    const FramePipeline* pipeline = nullptr;
    std::uint64_t order = 0, tables = 0;
    FramePlan plan;          ///< what the image depends on of it (operator==)
    double unitDistance = 0; ///< with the level of detail's compensation
    Lighting lighting;       ///< lit plans: the lights and the normals' version
    std::uint64_t normals = 0;

    static ImageKey Of(const BackendFrame& frame);
    bool operator==(const ImageKey& other) const;
  };


  /// The frame's image; with `ranges` (depth peeling) each fragment clipped to its pixel's.
  void Composite(const BackendFrame& frame, DrawTimes& times, const float* ranges = nullptr);

  Compositor Compositing;
  CompositeSettings Settings;
  CompositorStats LastStats;
  bool HaveImage = false; ///< the compositor holds the complete image of Kept
  ImageKey Kept; ///< with the opaque depth the image path kept (ImagePath::KeepDepth)
  ImagePath Path;
  std::vector<float> PeelRanges[2], PeelColours[2]; ///< depth peeling: front, back
};

} // namespace mtpt

#endif
