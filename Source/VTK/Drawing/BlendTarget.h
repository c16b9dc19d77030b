// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file BlendTarget.h
 * @brief Private glue: a single-sampled float framebuffer holding a copy of what the
 * window drew in a renderer's viewport, which a backend blends into or reads back, and the
 * way back into the window.
 *
 * Why: VTK's windows are multisampled by default (8 samples asked, 4 granted by Mesa), and
 * a multisampled framebuffer can be neither read with glReadPixels nor blitted into at
 * another size or position. Capture resolves the window's colour and opaque depth into
 * this target (a blit of equal size, which resolves the samples), so both backends see
 * one sample per pixel whatever the window; WriteToWindow draws a texture back over the
 * viewport with a full-screen quad, which writes every sample of a multisampled window
 * (a blit into a multisampled framebuffer is not allowed everywhere). The OpenGL backend
 * blends in the target itself, so thousands of thin layers lose no precision to 8-bit
 * rounding at every blend, as vtkProjectedTetrahedraMapper's float framebuffer.
 *
 * At an image sample distance other than 1 the OpenGL backend blends in a target of the
 * sampled image's size instead (CaptureSampled: transparent colour, the window's depth under
 * each pixel's centre), which BlendOverWindow then composites over the window with linear
 * filtering.
 */
#ifndef mtpt_BlendTarget_h
#define mtpt_BlendTarget_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkNew.h"

#include "mtpt/Records.h"

#include <memory>
#include <string>

VTK_ABI_NAMESPACE_BEGIN
class vtkOpenGLFramebufferObject;
class vtkOpenGLQuadHelper;
class vtkOpenGLRenderWindow;
class vtkShaderProgram;
class vtkTextureObject;
class vtkWindow;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class BlendTarget
{
public:
  /// `colourType`: VTK_FLOAT (blending in the target) or VTK_UNSIGNED_CHAR (reading back).
  explicit BlendTarget(int colourType = 10 /* VTK_FLOAT */);
  ~BlendTarget();

  /**
   * Makes the target the viewport's size, copies the window's colour and depth there into
   * it (resolving multisamples) and leaves it bound for drawing and reading, with the
   * window's framebuffer bindings pushed. Returns false with `error` set when the target
   * cannot be made or the copy fails; the bindings are then restored already.
   */
  bool Capture(
    vtkOpenGLRenderWindow* window, const int origin[2], const int size[2], std::string& error);

  /**
   * For a sampled image: makes the target `sampled` pixels, its colour transparent and its
   * depth the window's depth of the viewport (origin, size) at the centres of its pixels (the
   * viewport pixel under each centre, by a GL_NEAREST blit), and leaves it bound for drawing
   * and reading, with the window's framebuffer bindings pushed, as Capture. The window's
   * depth is first copied at its own size into `viewport` (a multisampled framebuffer can be
   * blitted only at equal size), whose colour is left as it was. Returns false with `error`
   * set when a target cannot be made or a copy fails; the bindings are then restored already.
   */
  bool CaptureSampled(vtkOpenGLRenderWindow* window, const int origin[2], const int size[2],
    const ImageSize& sampled, BlendTarget& viewport, std::string& error);

  /// Pops the bindings Capture pushed: the window's framebuffer is bound again.
  void Restore(vtkOpenGLRenderWindow* window);

  /**
   * Replaces the colour of the rectangle (origin, size) of the framebuffer bound for drawing
   * with `texture` (the rectangle's size, RGBA): no blending, no depth test or write, every
   * sample. Returns false with `error` set when the shader cannot be made or OpenGL fails.
   */
  bool WriteToWindow(vtkOpenGLRenderWindow* window, vtkTextureObject* texture, const int origin[2],
    const int size[2], std::string& error);

  /**
   * Composites `texture` (premultiplied RGBA, any size) over the rectangle (origin, size) of
   * the framebuffer bound for drawing, stretched over it with linear filtering (clamped to
   * the edge): colour = texture + (1 - texture alpha) * framebuffer, the same for alpha; no
   * depth test or write, every sample. Returns false with `error` set when the shader cannot
   * be made or OpenGL fails.
   */
  bool BlendOverWindow(vtkOpenGLRenderWindow* window, vtkTextureObject* texture,
    const int origin[2], const int size[2], std::string& error);

  /**
   * Reads the rectangle (x, y, width, height) of the target (after Capture, before Restore)
   * into `depth` (floats, when not null) and `rgba` (8 bits per channel, when not null),
   * row 0 at the bottom. Returns false with `error` set when OpenGL fails.
   */
  bool Read(vtkOpenGLRenderWindow* window, int x, int y, int width, int height, float* depth,
    unsigned char* rgba, std::string& error);

  /// Clears the colour of the framebuffer bound for drawing to `rgba`: every pixel and
  /// channel, whatever the scissor box and colour mask, which are left as they were.
  static void ClearColour(vtkOpenGLRenderWindow* window, const float rgba[4]);

  /**
   * Makes `quad` a full-screen quad with `fragmentShader` in `window` (once) and readies its
   * program; null when the shader cannot be compiled.
   */
  static vtkShaderProgram* ReadyQuad(std::unique_ptr<vtkOpenGLQuadHelper>& quad,
    vtkOpenGLRenderWindow* window, const char* fragmentShader);

  /**
   * Draws `quad` (its program ready, its uniforms set) over the rectangle (origin, size) of
   * the framebuffer bound for drawing: no depth test or write, every sample; replacing the
   * colour there, or (`blend`) composited over it as premultiplied colour.
   */
  static void DrawQuad(vtkOpenGLRenderWindow* window, vtkOpenGLQuadHelper& quad,
    const int origin[2], const int size[2], bool blend);

  /// The target's colour (RGBA float), valid after a successful Capture.
  vtkTextureObject* Colour();

  /// Frees the framebuffer and the quad; `window` owns them and is current.
  void ReleaseGraphicsResources(vtkWindow* window);

private:
  BlendTarget(const BlendTarget&) = delete;
  void operator=(const BlendTarget&) = delete;

  bool Allocate(vtkOpenGLRenderWindow* window, const int size[2], std::string& error);
  /// A quad of `texture` over (origin, size), replacing (blend off) or blending over.
  bool DrawTexture(vtkOpenGLRenderWindow* window, vtkTextureObject* texture, const int origin[2],
    const int size[2], bool blend, std::string& error);

  vtkNew<vtkOpenGLFramebufferObject> Framebuffer;
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
  int ColourType;
  bool Allocated = false;
  int Size[2] = { 0, 0 };
  int DepthBits = 0;
};

} // namespace mtpt

#endif
