// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RenderBackend.h
 * @brief Private glue: how the sorted tetrahedra of a prepared frame reach the window.
 *
 * The mapper validates its input, runs the core's frame pipeline (transform, culling, keys,
 * order) and hands the prepared frame to one backend:
 * - OpenGLBackend: decomposes batch after batch into the fixed-stride buffers, uploads them
 *   and draws them with OpenGL blending (the paper's path; right with a GPU);
 * - CPUBackend: composites the same triangles with the same per-fragment math on the CPU
 *   and puts the image into the window (right where OpenGL is itself a CPU rasterizer).
 * Each backend owns its OpenGL objects (they belong to the context of the window it last
 * drew in) and keeps its own record of what they hold, keyed on every input they depend
 * on; see Documentation/architecture.md.
 */
#ifndef mtpt_RenderBackend_h
#define mtpt_RenderBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/Lighting.h"
#include "mtpt/MeshView.h"
#include "mtpt/Records.h"
#include "mtpt/Shading.h"

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

class FramePipeline;
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
   * The size of the image the volume is composited at (the mapper's ImageSampleDistance,
   * mtpt/ImageSampling.h): `size` at distance 1, else fewer (or more) pixels, magnified (or
   * minified) onto the viewport with bilinear filtering. NDC span the viewport either way.
   */
  ImageSize imageSize;
  FramePipeline* pipeline = nullptr;
  const TransferFunctionTables* tables = nullptr;
  Shading shading = Shading::VTKCompatible;
  /// Dependent components: the pipeline's records hold colours (FrameInput::colours), shaded
  /// VTK-compatibly whatever `shading` says; the tables are not read.
  bool vertexColours = false;
  PerspectiveInterpolation interpolation; ///< of this frame's projection
  /**
   * Depth peeling: this frame is one peel of a pass that peels volumes (VolumetricPeel,
   * which has recorded the ranges asked for); the backend composites the volume over each
   * pixel's two ranges into the peel's colour target (DrawPeel), each fragment clipped with
   * `clipping`. Null: an ordinary frame.
   */
  VolumetricPeel* peel = nullptr;
  DepthClipping clipping;          ///< of this frame's projection
  /// The mapper's clipping planes in eye coordinates: each fragment's segment is cut to the
  /// part they keep (mtpt::ClipPlanes).
  ClipPlanes clipPlanes;
  /// How fragments become pixels (mtpt::BlendMode); a mode other than Composite reduces
  /// them in any order (the pipeline then sorted nothing), with the scalars, not colours.
  BlendMode blendMode = BlendMode::Composite;
  double averageRange[2] = { -1e300, 1e300 }; ///< AverageIPScalarRange, scalar units
  /**
   * Shading (mtpt/Lighting.h; composite blending only): the lights and coefficients, each
   * cell's normal (3 floats per cell, model coordinates; `normalsVersion` changes with them)
   * and the frame's model-view matrix. Null `lighting`: unlit.
   */
  const Lighting* lighting = nullptr;
  const float* normals = nullptr;
  std::uint64_t normalsVersion = 0;
  Matrix4 modelView = IdentityMatrix();
  double unitDistance = 1.0;       ///< ScalarOpacityUnitDistance, positive
  std::size_t batchSize = 1;       ///< tetrahedra decomposed per batch (>= 1)
  int threads = 0;                 ///< OpenMP threads (<= 0: the default)
  bool floatFramebuffer = true;    ///< blend in a float target (OpenGL backend)
  bool synchronizedTiming = false; ///< glFinish after upload and draw
  /**
   * Called after each batch with the fraction of the sorted tetrahedra drawn so far;
   * returning false stops the frame there (what was drawn stays). Empty: never stops.
   */
  std::function<bool(double)> afterBatch;

  /// Whether the image is composited at another size than the viewport's.
  bool Sampled() const { return imageSize.width != size[0] || imageSize.height != size[1]; }
};

/// Seconds spent by the last Draw, and how it ended.
struct BackendTimes
{
  double upload = 0;    ///< OpenGL: buffer upload; CPU: read-back of depth and colour, image upload
  double draw = 0;      ///< OpenGL: the draw calls; CPU: the quad that writes the image
  double composite = 0; ///< CPU: compositing on the CPU (and magnifying a sampled image)
  /// Of the above, the work that follows the viewport alone, whatever the cells and the
  /// image sample distance (CPU: read-back, magnification, image upload and write-back;
  /// OpenGL: writing an off-screen target back), for the level of detail's budget rule.
  double viewport = 0;
  double decompose = 0; ///< decomposition of the batches (included in the pipeline's times)
  int batches = 0;      ///< batches drawn
  bool stopped = false; ///< afterBatch stopped the frame
  bool imageReused = false; ///< CPU: the previous frame's composited image served
};

class RenderBackend
{
public:
  virtual ~RenderBackend() = default;

  /**
   * Whether every fragment this backend draws for `frame` (its window, floatFramebuffer and
   * image size) is sampled at a pixel centre of the composited image only, so that the
   * pipeline may cull cells whose projection covers no pixel centre of that image. Ask with
   * the window's framebuffer bound.
   */
  virtual bool SamplesPixelCentresOnly(const BackendFrame& frame) const = 0;

  /**
   * The largest side, in pixels, of an image this backend can composite at another size
   * than the viewport's (BackendFrame::imageSize) in `window`; 0 where it cannot, and then
   * draws at the viewport's size. Ask with the window's context current.
   */
  virtual int SampledImageLimit(vtkOpenGLRenderWindow* window) = 0;

  /**
   * Draws the prepared frame over what the renderer drew so far (the colour there, and the
   * depth of its opaque geometry). Returns false, with a message in Error(), when an OpenGL
   * call failed; the window's framebuffer is then left as it was whenever the failure came
   * before the backend wrote to it (the CPU backend checks every read before it writes).
   */
  virtual bool Draw(const BackendFrame& frame, BackendTimes& times) = 0;

  /**
   * Depth peeling (frame.peel): composites the volume over the peel's recorded ranges into
   * its colour target, each fragment's segment clipped to its pixel's range. Writes nothing
   * to the pass's own targets (VolumetricPeel::Answer does). Returns false with a message
   * in Error() when OpenGL failed.
   */
  virtual bool DrawPeel(const BackendFrame& frame, BackendTimes& times) = 0;

  /// Frees the OpenGL objects; `window` is the window whose context owns them, current.
  virtual void ReleaseGraphicsResources(vtkWindow* window) = 0;

  const std::string& Error() const { return this->ErrorMessage; }

protected:
  /**
   * The batch loop of both backends: for each window of frame.batchSize tetrahedra of the
   * order, back to front, `decompose(first, count)` has the pipeline decompose it (its time
   * goes to times.decompose) and `draw()` draws it, returning false when it failed (the loop
   * stops, and so does this function's result). After each batch but the last,
   * frame.afterBatch may stop the frame (times.stopped).
   */
  static bool ForEachBatch(const BackendFrame& frame, BackendTimes& times,
    const std::function<void(std::size_t first, std::size_t count)>& decompose,
    const std::function<bool()>& draw);

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
