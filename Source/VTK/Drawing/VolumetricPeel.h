// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file VolumetricPeel.h
 * @brief Private glue: the mapper's part in a depth-peeling pass's volumetric peels, so that
 * translucent surfaces and the volume blend in depth order (vtkDualDepthPeelingPass with the
 * renderer's UseDepthPeelingForVolumes; Documentation/algorithm.md, "Translucent geometry
 * and depth peeling").
 *
 * Such a pass draws the volumes inside its peel loop and tells them, through the shader code
 * it substitutes into a volume's fragment shader (vtkOpenGLRenderPass::
 * PreReplaceShaderValues, the interface VTK's GPU ray caster takes part by), which depth
 * ranges of each pixel a peel needs: castRay(zStart, zEnd) must return the volume's
 * premultiplied colour between those window depths. A peel of this mapper goes in three
 * steps:
 * 1. RecordRanges: a full-viewport quad runs the pass's code with castRay returning the
 *    range it is asked for; two float targets receive each pixel's front and back range
 *    (x start, y end, z 1 where asked; 0 elsewhere).
 * 2. The backend composites the volume over each pixel's two ranges into ColourTarget()
 *    (attachment 0 the front range, 1 the back range), each fragment's segment clipped to
 *    the range (the OpenGL backend in its fragment shader, the CPU backend from the ranges
 *    read back with ReadRanges).
 * 3. Answer: the quad runs the pass's code again, now with castRay returning the composite
 *    of the range asked for, into the pass's own targets with the pass's blending.
 * The pass's targets, blending and viewport are left as the pass set them.
 *
 * What it keeps: the targets (resized to the peel's viewport) and one quad program per
 * variant of the pass's code (a pass substitutes different code at each stage of a frame);
 * all in the context of the window, freed in ReleaseGraphicsResources.
 */
#ifndef mtpt_VolumetricPeel_h
#define mtpt_VolumetricPeel_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkNew.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkAbstractVolumeMapper;
class vtkOpenGLFramebufferObject;
class vtkOpenGLQuadHelper;
class vtkOpenGLRenderPass;
class vtkOpenGLRenderWindow;
class vtkTextureObject;
class vtkVolume;
class vtkWindow;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class VolumetricPeel
{
public:
  VolumetricPeel();
  ~VolumetricPeel();

  /**
   * The render pass that is peeling volumes and drawing `volume` now: the first of the
   * passes in its property keys (vtkOpenGLRenderPass::RenderPasses()) whose volumetric
   * shader code takes this mapper's part. Null when none is (no depth peeling for volumes).
   */
  static vtkOpenGLRenderPass* ActivePass(vtkVolume* volume, vtkAbstractVolumeMapper* mapper);

  /// Step 1: the ranges the pass asks for at each pixel of the `size` viewport it draws.
  bool RecordRanges(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
    vtkAbstractVolumeMapper* mapper, vtkVolume* volume, const int size[2], std::string& error);

  /// The recorded ranges as the compositor takes them: per pixel near then far window depth
  /// (near > far where none was asked), of the front and of the back range.
  bool ReadRanges(vtkOpenGLRenderWindow* window, std::vector<float>& front,
    std::vector<float>& back, std::string& error);

  /// The recorded ranges (step 2, OpenGL backend): 0 front, 1 back.
  vtkTextureObject* Ranges(int which);

  /// Step 2's target, the peel's size, two float RGBA attachments (0 front, 1 back range),
  /// cleared; bound for drawing by BindColourTarget, with the window's bindings pushed.
  bool BindColourTarget(vtkOpenGLRenderWindow* window, std::string& error);
  void UnbindColourTarget(vtkOpenGLRenderWindow* window);
  /// Step 2 from the CPU: the two images (premultiplied RGBA floats, the peel's size).
  bool UploadColours(
    vtkOpenGLRenderWindow* window, const float* front, const float* back, std::string& error);

  /// Step 3: the pass's outputs from the composites of step 2.
  bool Answer(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
    vtkAbstractVolumeMapper* mapper, vtkVolume* volume, std::string& error);

  /// Frees the targets and programs; `window` owns them and is current.
  void ReleaseGraphicsResources(vtkWindow* window);

private:
  VolumetricPeel(const VolumetricPeel&) = delete;
  void operator=(const VolumetricPeel&) = delete;

  /// The quad running the pass's code (substituted into vtkMTPTPeelFS), compiled once per
  /// variant of that code.
  vtkOpenGLQuadHelper* Quad(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
    vtkAbstractVolumeMapper* mapper, vtkVolume* volume);
  /// A two-attachment float target of the peel's size.
  bool Allocate(
    vtkOpenGLRenderWindow* window, vtkOpenGLFramebufferObject* target, std::string& error);
  /// Runs the quad with `answer` into what is bound for drawing.
  bool RunQuad(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
    vtkAbstractVolumeMapper* mapper, vtkVolume* volume, int answer, std::string& error);

  vtkNew<vtkOpenGLFramebufferObject> RangeTarget, ColourTarget;
  vtkNew<vtkTextureObject> Transparent; ///< 1x1, read as the pass's previous front colour
  vtkNew<vtkTextureObject> FrontUpload, BackUpload; ///< step 2 from the CPU
  std::map<std::string, std::unique_ptr<vtkOpenGLQuadHelper>> Quads;
  int Size[2] = { 0, 0 };
  bool UploadedColours = false; ///< step 2 came from the CPU (else ColourTarget holds it)
};

} // namespace mtpt

#endif
