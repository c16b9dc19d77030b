// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OpenGLBackend.h
 * @brief Private glue: the paper's way to the screen. Batch after batch, the pipeline
 * decomposes the sorted tetrahedra into its fixed-stride vertex and index buffers, which
 * are uploaded and drawn with one call, blended back to front (VTK's PT blending:
 * glBlendFuncSeparate(SRC_ALPHA, ONE_MINUS_SRC_ALPHA, ONE, ONE_MINUS_SRC_ALPHA), depth test
 * against the opaque geometry, no depth writes), in a float target (BlendTarget) unless
 * that is turned off or unavailable.
 *
 * What it keeps between frames, and what makes it stale:
 * - the vertex and index buffers: FramePipeline::BufferVersion() at upload (any new
 *   decomposition or batch of any frame changes it, whichever backend caused it);
 * - the transfer-function textures: TransferFunctionTables::Version() at upload;
 * - all of them, the shader program and the float target belong to one context: released
 *   in ReleaseGraphicsResources, after which everything is uploaded again.
 *
 * At an image sample distance other than 1 (FramePlan::imageSize differs from the
 * viewport's size) the batches are drawn into a float target of the sampled image's size
 * instead, whose colour starts transparent and whose depth is the window's, under each of
 * its pixels' centres (BlendTarget::CaptureSampled); that image is then composited over the
 * window with linear filtering (BlendTarget::BlendOverWindow).
 */
#ifndef mtpt_OpenGLBackend_h
#define mtpt_OpenGLBackend_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "Drawing/BlendTarget.h"
#include "Drawing/RenderBackend.h"

#include "vtkNew.h"
#include "vtkOpenGLHelper.h"

#include <cstdint>
#include <memory>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkOpenGLBufferObject;
class vtkOpenGLQuadHelper;
class vtkOpenGLVertexBufferObject;
class vtkShaderProgram;
class vtkTextureObject;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class OpenGLBackend : public RenderBackend
{
public:
  OpenGLBackend();
  ~OpenGLBackend() override;

  bool SamplesPixelCentresOnly(bool sampled, bool floatFramebuffer) const override;
  int SampledImageLimit(vtkOpenGLRenderWindow* window) override;
  bool Draw(const BackendFrame& frame, DrawTimes& times) override;
  bool DrawPeel(const BackendFrame& frame, DrawTimes& times) override;
  void ReleaseGraphicsResources(vtkWindow* window) override;

  /// Whether the last Draw blended in a float target (false: in the window's framebuffer).
  bool UsedFloatTarget() const { return this->FloatTargetUsed; }
  /// A warning from the last Draw that did not stop it (no float target); empty if none.
  const std::string& Warning() const { return this->WarningMessage; }

private:
  OpenGLBackend(const OpenGLBackend&) = delete;
  void operator=(const OpenGLBackend&) = delete;

  /// The fragment shader's program, lit (reading the light texture) or not.
  vtkShaderProgram* ReadyProgram(vtkOpenGLRenderWindow* window, bool lit);
  /// Binds the target the batches are drawn into: the sampled target, the float target (when
  /// `floatTarget`) or none (the window's framebuffer), setting SampledTargetUsed and
  /// FloatTargetUsed; a target that cannot be made leaves WarningMessage saying why.
  void BindTarget(const BackendFrame& frame, bool floatTarget);
  /// Unbinds the target and, when the batches were `drawn`, puts what they drew into the
  /// window.
  bool WriteTarget(const BackendFrame& frame, bool drawn, DrawTimes& times);
  void UploadTables(const BackendFrame& frame);
  void SetUniforms(const BackendFrame& frame, vtkShaderProgram* program);
  /// Whether DrawBatches draws into a target of its own (sampled, float or a peel's), from
  /// its origin, rather than into the window's viewport.
  bool DrawsIntoOwnTarget() const
  {
    return this->SampledTargetUsed || this->FloatTargetUsed || this->PeelTargetUsed;
  }
  /// The blend target BindTarget bound (the sampled image's or the float one), or null.
  BlendTarget* BoundTarget()
  {
    return this->SampledTargetUsed ? &this->SampledTarget
                                   : (this->FloatTargetUsed ? &this->Target : nullptr);
  }
  /// The pixels DrawBatches draws into: its own target's, or the window's viewport.
  PixelRegion DrawnPixels(const BackendFrame& frame) const;
  /// Each fragment's eye ray (depth peeling, clipping planes) and the clipping planes.
  void SetClippingUniforms(const BackendFrame& frame, vtkShaderProgram* program);
  bool DrawBatches(const BackendFrame& frame, vtkShaderProgram* program, DrawTimes& times);
  /// Blend modes other than composite: the fragments reduced in a float target of their own
  /// (cleared to the mode's neutral value, with the window's depth), then mapped to colour
  /// over the window's viewport (ResolveReduced).
  bool DrawReduced(const BackendFrame& frame, vtkShaderProgram* program, DrawTimes& times);
  bool ResolveReduced(const BackendFrame& frame, vtkTextureObject* reduced);
  /// The batch's slots into the vertex and index buffers; nothing when they hold them.
  void Upload(const BackendFrame& frame, const Batch& batch, DrawTimes& times);
  void DrawUploaded(vtkShaderProgram* program);
  /// Shading: the lighting of the batch's slots (Batch::lights) into the buffer texture the
  /// lit fragment shader reads per slot; nothing when it holds them already.
  void UploadLights(const BackendFrame& frame, const Batch& batch, DrawTimes& times);
  /// UploadLights, then the texture bound for `program` (DrawUploaded unbinds it).
  void BindLights(
    const BackendFrame& frame, vtkShaderProgram* program, const Batch& batch, DrawTimes& times);

  vtkNew<vtkOpenGLVertexBufferObject> VertexBuffer;
  vtkOpenGLHelper Triangles;
  vtkNew<vtkTextureObject> TransferFunction;
  vtkNew<vtkTextureObject> IntegralsHigh, IntegralsLow; // pre-integrated shading
  vtkNew<vtkTextureObject> IntensityPrefix;             // average and additive blending
  std::unique_ptr<vtkOpenGLQuadHelper> ReduceQuad;      // blend modes: reduced to colour
  vtkNew<vtkOpenGLBufferObject> LightBuffer;            // shading: factors per slot
  vtkNew<vtkTextureObject> LightTexture;                // ... read as a buffer texture
  BlendTarget Target;
  BlendTarget SampledTarget; ///< at an image sample distance other than 1

  std::uint64_t UploadedBuffers = 0; ///< Batch::version in the buffers
  std::uint64_t UploadedTables = 0;  ///< TransferFunctionTables::Version() in the textures
  std::uint64_t UploadedLights = 0;  ///< Batch::lightsVersion in LightTexture
  bool ProgramLit = false;           ///< Triangles.Program is the lit variant
  bool FloatTargetFailed = false;    ///< no float target in this context: do not retry
  bool FloatTargetUsed = false;
  bool PeelTargetUsed = false;      ///< DrawBatches draws into the peel's colour target
  bool SampledTargetFailed = false; ///< no sampled target in this context: do not retry
  bool SampledTargetUsed = false;
  int MaxTargetSize = 0; ///< of this context: the largest texture and viewport (0: not asked)
  std::string WarningMessage;
};

} // namespace mtpt

#endif
