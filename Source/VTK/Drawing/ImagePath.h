// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ImagePath.h
 * @brief Private glue: the CPU backend's way from the window to the compositor and back.
 *
 * One frame goes through it in two steps:
 * - Capture: the renderer's viewport is copied into a single-sampled target (BlendTarget, so
 *   a multisampled window is resolved first) and its opaque depth is read, at the composited
 *   image's size (FramePlan::imageSize): where the image is sampled, each of its pixels
 *   takes the depth of the viewport pixel under its centre (mtpt::SampleDepth), which is
 *   what an OpenGL blit with nearest filtering gives the OpenGL backend.
 * - WriteBack: the region of the image the compositor touched is resolved over the colour
 *   read back beneath it (at another image size, magnified onto the viewport with bilinear
 *   filtering first: mtpt::MagnifyOver), in 8 bits, and written into the window with
 *   blending off. Only the viewport pixels it reaches are read and written.
 *
 * Every OpenGL read is checked before anything is written: a failed read leaves the window
 * as it was and the step returns false with the error.
 */
#ifndef mtpt_ImagePath_h
#define mtpt_ImagePath_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "Drawing/BlendTarget.h"
#include "Drawing/RenderBackend.h"

#include "mtpt/Compositor.h"

#include "vtkNew.h"

#include <cstdint>
#include <string>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkRenderer;
class vtkTextureObject;
class vtkWindow;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class ImagePath
{
public:
  ImagePath();
  ~ImagePath();

  /// Captures the viewport and reads its opaque depth at the composited image's size.
  bool Capture(const BackendFrame& frame, DrawTimes& times, std::string& error);
  /// The opaque depth of the composited image's pixels (row 0 at the bottom), or null where
  /// nothing opaque can occlude the volume.
  const float* OpaqueDepth() const { return this->Depth.empty() ? nullptr : this->Depth.data(); }
  /// Whether this frame's opaque depth equals the one kept with KeepDepth.
  bool DepthAsKept() const { return this->Depth == this->KeptDepth; }
  /// Keeps this frame's opaque depth (the one the compositor's image was made with).
  void KeepDepth() { this->Depth.swap(this->KeptDepth); }
  /// Writes the compositor's image over the captured colour into the window, and ends the
  /// capture (the window's framebuffer bindings are restored, even where it fails).
  bool WriteBack(const BackendFrame& frame, Compositor& compositor, DrawTimes& times,
    std::string& error);
  void ReleaseGraphicsResources(vtkWindow* window);

private:
  ImagePath(const ImagePath&) = delete;
  void operator=(const ImagePath&) = delete;

  /// Whether opaque geometry may have written depth that the volume must respect.
  static bool MayHaveOpaqueGeometry(vtkRenderer* renderer);
  bool ReadDepth(const BackendFrame& frame, std::string& error);
  /// The composited image's `region` over Below into Region, at the viewport's `target`.
  void Resolve(const BackendFrame& frame, Compositor& compositor, const PixelRegion& region,
    const PixelRegion& target);
  bool Upload(const BackendFrame& frame, const PixelRegion& target, DrawTimes& times,
    std::string& error);

  BlendTarget Target;
  vtkNew<vtkTextureObject> Image;
  std::vector<float> Depth;         ///< this frame's opaque depth (empty: nothing opaque)
  std::vector<float> KeptDepth;     ///< the opaque depth KeepDepth kept
  std::vector<float> ViewportDepth; ///< the viewport's, when the image is sampled
  std::vector<float> Sampled;       ///< the touched region of a sampled image, premultiplied
  std::vector<std::uint8_t> Below, Region; ///< of the viewport pixels written
};

} // namespace mtpt

#endif
