// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RenderBackend.h
 * @brief Private glue: how the sorted tetrahedra of a prepared frame reach the window.
 *
 * The mapper validates its input, plans the frame (mtpt/FramePlan.h), runs the core's frame
 * pipeline (transform, culling, keys, order) and hands the prepared frame to one backend,
 * which has the pipeline decompose the order batch after batch
 * (FramePipeline::DrawBatches) and draws each batch it is given:
 * - OpenGLBackend: uploads the fixed-stride buffers and draws them with OpenGL blending
 *   (the paper's path; right with a GPU);
 * - CPUBackend: composites the same triangles, as fans, with the same per-fragment math on
 *   the CPU and puts the image into the window (right where OpenGL is itself a CPU
 *   rasterizer).
 * Each backend owns its OpenGL objects (they belong to the context of the window it last
 * drew in) and keeps its own record of what they hold, keyed on every input they depend
 * on; see Documentation/architecture.md.
 */
#ifndef mtpt_RenderBackend_h
#define mtpt_RenderBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/FrameStatistics.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

VTK_ABI_NAMESPACE_BEGIN
class vtkOpenGLRenderWindow;
class vtkRenderer;
class vtkWindow;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class TransferFunctionTables;
class VolumetricPeel;

/// What a backend needs to draw one frame that FramePipeline::Prepare has sorted.
struct BackendFrame
{
  vtkRenderer* renderer = nullptr;
  vtkOpenGLRenderWindow* window = nullptr;
  int origin[2] = { 0, 0 }; ///< the renderer's tiled viewport in window pixels
  int size[2] = { 0, 0 };
  /**
   * Every decision of the frame (mtpt/FramePlan.h): shading and blending after every
   * downgrade, the tables read, clipping, the size of the composited image (the viewport's,
   * or fewer or more pixels at an image sample distance, magnified or minified onto the
   * viewport with bilinear filtering; NDC span the viewport either way), the batches.
   */
  const FramePlan* plan = nullptr;
  FramePipeline* pipeline = nullptr;
  const TransferFunctionTables* tables = nullptr;
  /**
   * Depth peeling: this frame is one peel of a pass that peels volumes (VolumetricPeel,
   * which has recorded the ranges asked for); the backend composites the volume over each
   * pixel's two ranges into the peel's colour target (DrawPeel), each fragment clipped with
   * the plan's clipping. Null: an ordinary frame.
   */
  VolumetricPeel* peel = nullptr;
  bool floatFramebuffer = true;    ///< blend in a float target (OpenGL backend)
  bool synchronizedTiming = false; ///< glFinish after upload and draw

  /// The composited image's size.
  const ImageSize& Image() const { return plan->imageSize; }
  /// Whether the image is composited at another size than the viewport's.
  bool Sampled() const { return plan->Sampled(size); }
  /// The unit distance every attenuation is scaled by: the property's, compensated for the
  /// cells the level of detail left out (LevelOfDetail.h).
  double UnitDistance() const;
};

class RenderBackend
{
public:
  virtual ~RenderBackend() = default;

  /**
   * Whether every fragment this backend draws is sampled at a pixel centre of the composited
   * image only, drawing at another size than the viewport's (`sampled`) or not, with the
   * mapper's `floatFramebuffer` setting, so that the pipeline may cull cells whose projection
   * covers no pixel centre of that image (FrameFacts). Ask with the window's framebuffer
   * bound.
   */
  virtual bool SamplesPixelCentresOnly(bool sampled, bool floatFramebuffer) const = 0;

  /**
   * The largest side, in pixels, of an image this backend can composite at another size
   * than the viewport's (FramePlan::imageSize) in `window`; 0 where it cannot, and then
   * draws at the viewport's size. Ask with the window's context current.
   */
  virtual int SampledImageLimit(vtkOpenGLRenderWindow* window) = 0;

  /**
   * Draws the prepared frame over what the renderer drew so far (the colour there, and the
   * depth of its opaque geometry). Returns false, with a message in Error(), when an OpenGL
   * call failed; the window's framebuffer is then left as it was whenever the failure came
   * before the backend wrote to it (the CPU backend checks every read before it writes).
   */
  virtual bool Draw(const BackendFrame& frame, DrawTimes& times) = 0;

  /**
   * Depth peeling (frame.peel): composites the volume over the peel's recorded ranges into
   * its colour target, each fragment's segment clipped to its pixel's range. Writes nothing
   * to the pass's own targets (VolumetricPeel::Answer does). Returns false with a message
   * in Error() when OpenGL failed.
   */
  virtual bool DrawPeel(const BackendFrame& frame, DrawTimes& times) = 0;

  /// Frees the OpenGL objects; `window` is the window whose context owns them, current.
  virtual void ReleaseGraphicsResources(vtkWindow* window) = 0;

  const std::string& Error() const { return this->ErrorMessage; }

protected:
  /// Counts the batches `drawn` gave into `times`; whether none failed.
  static bool Drawn(const BatchesDrawn& drawn, DrawTimes& times);
  /// Whether the frame's batches are `target`'s, which this backend draws; else says why in
  /// Error().
  bool PlannedFor(const BackendFrame& frame, BatchTarget target);

  std::string ErrorMessage;
};

/**
 * The pending OpenGL errors as one string of names ("GL_INVALID_OPERATION, ..."), and the
 * error state cleared; empty when there was none.
 */
std::string TakeOpenGLErrors();

/**
 * Takes the pending OpenGL errors (TakeOpenGLErrors): true when there was none; else sets
 * `error` to "<what> failed (<their names>)" and returns false.
 */
bool OpenGLSucceeded(const std::string& what, std::string& error);

/// Whether the framebuffer bound for drawing is multisampled.
bool DrawFramebufferIsMultisampled();

} // namespace mtpt

#endif
