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
 *
 * At an image sample distance other than 1 (BackendFrame::imageSize differs from the
 * viewport's size) the image is composited at its own size, against the opaque depth of the
 * viewport pixel under each of its pixels' centres (mtpt::SampleDepth), and magnified onto
 * the viewport with bilinear filtering over the colour read back beneath it, on the CPU
 * (mtpt::MagnifyOver): the volume's colour is still rounded to 8 bits once. Only the
 * viewport pixels the filter reads the touched region into are read back and written.
 */
#ifndef mtpt_CPUBackend_h
#define mtpt_CPUBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "Drawing/BlendTarget.h"
#include "Drawing/RenderBackend.h"

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

  bool SamplesPixelCentresOnly(const BackendFrame& frame) const override;
  int SampledImageLimit(vtkOpenGLRenderWindow* window) override;
  bool Draw(const BackendFrame& frame, BackendTimes& times) override;
  bool DrawPeel(const BackendFrame& frame, BackendTimes& times) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

  /// The compositor's work in the last Draw (zero counts when it reused its image).
  const CompositorStats& Stats() const { return this->LastStats; }

private:
  CPUBackend(const CPUBackend&) = delete;
  void operator=(const CPUBackend&) = delete;

  /**
   * Everything the composited image depends on besides the opaque depth. The order's
   * version stands for the view, the projection (and so the interpolation), the data, the
   * culling and the viewport; the tables' version for the transfer functions. `size` is the
   * composited image's (BackendFrame::imageSize), which the image sample distance sets.
   */
  struct ImageKey
  {
    const FramePipeline* pipeline = nullptr;
    std::uint64_t order = 0, tables = 0;
    std::size_t batch = 0;
    ImageSize size;
    Shading shading = Shading::VTKCompatible;
    bool vertexColours = false;
    double unitDistance = 0;
    PerspectiveInterpolation interpolation;

    static ImageKey Of(const BackendFrame& frame);
    bool operator==(const ImageKey& other) const;
  };

  /// Whether opaque geometry may have written depth that the volume must respect.
  static bool MayHaveOpaqueGeometry(vtkRenderer* renderer);
  /// The captured depth of the viewport into Depth (for a sampled image: under its pixels'
  /// centres), or Depth empty where it is the clear value.
  bool ReadDepth(const BackendFrame& frame);
  /// The captured colour of `region` (viewport pixels) into Below.
  bool ReadColour(const BackendFrame& frame, const PixelRegion& region);
  /// The frame's image; with `ranges` (depth peeling) each fragment clipped to its pixel's.
  void Composite(const BackendFrame& frame, BackendTimes& times, const float* ranges = nullptr);
  /// Writes the viewport pixels of `target`: the image's `region` composited (and for a
  /// sampled image magnified) over Below.
  bool WriteBack(const BackendFrame& frame, const PixelRegion& region, const PixelRegion& target,
    BackendTimes& times);
  /// The image's `region` magnified onto the viewport's `target` over Below, into Region.
  void Magnify(const BackendFrame& frame, const PixelRegion& region, const PixelRegion& target);

  Compositor Compositing;
  CompositeSettings Settings;
  CompositorStats LastStats;
  bool HaveImage = false; ///< the compositor holds the complete image of Kept
  ImageKey Kept;
  std::vector<float> KeptDepth; ///< the opaque depth the kept image was composited with
  std::vector<float> Depth;     ///< this frame's opaque depth (empty: nothing opaque)
  std::vector<float> PeelRanges[2], PeelColours[2]; ///< depth peeling: front, back
  std::vector<float> ViewportDepth;                 ///< of the viewport, when the image is sampled
  std::vector<float> Sampled; ///< the touched region of a sampled image, premultiplied
  BlendTarget Target;
  vtkNew<vtkTextureObject> Image;
  std::vector<std::uint8_t> Below, Region; ///< of the touched region
};

} // namespace mtpt

#endif
