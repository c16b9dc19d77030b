// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/OpenGLBackend.h"

#include "Drawing/VolumetricPeel.h"
#include "Input/TransferFunctionTables.h"
#include "vtkMTPTReduceFS.h"
#include "vtkMTPTSegmentShared.h"
#include "vtkMTPTTetrahedraFS.h"
#include "vtkMTPTTetrahedraVS.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/Timing.h"

#include "vtkOpenGLBufferObject.h"
#include "vtkOpenGLIndexBufferObject.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkOpenGLVertexArrayObject.h"
#include "vtkOpenGLVertexBufferObject.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "Basics/OpenGLHeader.h"

#include <algorithm>
#include <climits>
#include <cstddef>
#include <string>
#include <vector>

namespace mtpt
{

namespace
{

/**
 * Texels in a row of the tables' textures. A table of more entries (volumes of several
 * properties drawn together, TransferFunctionTables) takes several rows, entry i at texel
 * (i % TableRowWidth, i / TableRowWidth), read texel by texel; one of at most this many
 * entries is one row, which the hardware's filtering may read too.
 */
constexpr int TableRowWidth = 4096;

/// A float RGBA texture of the `entries` RGBA values in rows (TableRowWidth), clamped, with
/// the given filter.
void MakeTableTexture(vtkTextureObject* texture, vtkOpenGLRenderWindow* window, int entries,
  const float* values, bool linear)
{
  const int width = std::min(entries, TableRowWidth);
  const int rows = (entries + width - 1) / width;
  std::vector<float> padded;
  if (rows * width != entries)
  {
    padded.assign(4 * static_cast<std::size_t>(rows) * width, 0.0f);
    std::copy_n(values, 4 * static_cast<std::size_t>(entries), padded.begin());
    values = padded.data();
  }
  texture->SetContext(window);
  texture->SetWrapS(vtkTextureObject::ClampToEdge);
  texture->SetWrapT(vtkTextureObject::ClampToEdge);
  const int filter = linear ? vtkTextureObject::Linear : vtkTextureObject::Nearest;
  texture->SetMinificationFilter(filter);
  texture->SetMagnificationFilter(filter);
  texture->Create2DFromRaw(width, rows, 4, VTK_FLOAT, const_cast<float*>(values));
}

/**
 * The blending of the tetrahedra's fragments: VTK's PT's back-to-front "over" of
 * non-premultiplied colour; in the blend modes other than composite, GL_MAX (maximum, and
 * minimum as the negated scalar) or sums (average, additive) of the reduced values.
 */
void SetBlending(const FramePlan& plan, vtkOpenGLState* state)
{
  state->vtkglEnable(GL_BLEND);
  if (!ReducesInAnyOrder(plan.blendMode))
  {
    state->vtkglBlendEquationSeparate(GL_FUNC_ADD, GL_FUNC_ADD);
    state->vtkglBlendFuncSeparate(
      GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    return;
  }
  const bool extreme =
    plan.blendMode == BlendMode::MaximumIntensity || plan.blendMode == BlendMode::MinimumIntensity;
  const GLenum equation = extreme ? GL_MAX : GL_FUNC_ADD;
  state->vtkglBlendEquationSeparate(equation, equation);
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE, GL_ONE, GL_ONE);
}

/// Runs its function when the scope ends, however it ends: OpenGL state a frame changed is put
/// back even when the pipeline throws (an allocation that fails, std::bad_alloc).
template <typename Function>
struct AtScopeEnd
{
  Function function;
  ~AtScopeEnd() { this->function(); }
};
template <typename Function>
AtScopeEnd(Function) -> AtScopeEnd<Function>;

} // namespace

OpenGLBackend::OpenGLBackend() = default;
OpenGLBackend::~OpenGLBackend() = default;

bool OpenGLBackend::SamplesPixelCentresOnly(bool sampled, bool floatFramebuffer) const
{
  // The sampled and the float target are single-sampled; without them the window's own
  // framebuffer is drawn.
  return (sampled && !this->SampledTargetFailed) ||
    (floatFramebuffer && !this->FloatTargetFailed) || !DrawFramebufferIsMultisampled();
}

int OpenGLBackend::SampledImageLimit(vtkOpenGLRenderWindow*)
{
  if (this->SampledTargetFailed)
  {
    return 0;
  }
  if (this->MaxTargetSize == 0)
  {
    GLint texture = 0, viewport[2] = { 0, 0 };
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &texture);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
    this->MaxTargetSize = std::max(1, std::min({ texture, viewport[0], viewport[1] }));
  }
  return this->MaxTargetSize;
}

vtkShaderProgram* OpenGLBackend::ReadyProgram(vtkOpenGLRenderWindow* window, bool lit)
{
  vtkShaderProgram* program = this->Triangles.Program;
  if (program && this->ProgramLit == lit)
  {
    window->GetShaderCache()->ReadyShaderProgram(program);
    return program;
  }
  // The fragment shader computes segments with the core's constants and series. Only the lit
  // variant declares the light texture: an unlit frame binds no buffer texture at all.
  std::string fragment = vtkMTPTTetrahedraFS;
  vtkShaderProgram::Substitute(fragment, "//MTPT::SegmentShared", vtkMTPTSegmentShared);
  vtkShaderProgram::Substitute(fragment, "//MTPT::Lit", lit ? "#define MTPT_LIT" : "");
  program = window->GetShaderCache()->ReadyShaderProgram(vtkMTPTTetrahedraVS, fragment.c_str(), "");
  if (program)
  {
    this->Triangles.Program = program;
    this->ProgramLit = lit;
    this->Triangles.VAO->ShaderProgramChanged();
    this->Triangles.ShaderSourceTime.Modified();
  }
  return program;
}

void OpenGLBackend::UploadTables(const BackendFrame& frame)
{
  const TransferFunctionTables& tables = *frame.tables;
  if (this->UploadedTables == tables.Version() && this->TransferFunction->GetHandle() != 0)
  {
    return;
  }
  const TransferFunctionTable table = tables.Table();
  MakeTableTexture(this->TransferFunction, frame.window, table.size, table.table, true);
  // The prefix integrals as float high + low parts, so that differences of nearby entries
  // keep their precision in the shader: a texture of each.
  const std::vector<float>& split = tables.PreIntegration().integralsSplit;
  std::vector<float> high(4 * static_cast<std::size_t>(table.size)), low(high.size());
  for (std::size_t e = 0; e < high.size() / 4 && 8 * e + 8 <= split.size(); ++e)
  {
    std::copy_n(split.begin() + 8 * e, 4, high.begin() + 4 * e);
    std::copy_n(split.begin() + 8 * e + 4, 4, low.begin() + 4 * e);
  }
  MakeTableTexture(this->IntegralsHigh, frame.window, table.size, high.data(), false);
  MakeTableTexture(this->IntegralsLow, frame.window, table.size, low.data(), false);
  // W of the intensity integral, high and low parts in red and green.
  const IntensityTable& intensity = tables.Intensity();
  std::vector<float> packed(4 * intensity.prefixHigh.size(), 0.0f);
  for (std::size_t i = 0; i < intensity.prefixHigh.size(); ++i)
  {
    packed[4 * i] = intensity.prefixHigh[i];
    packed[4 * i + 1] = intensity.prefixLow[i];
  }
  MakeTableTexture(this->IntensityPrefix, frame.window, table.size, packed.data(), false);
  this->UploadedTables = tables.Version();
}

void OpenGLBackend::SetUniforms(const BackendFrame& frame, vtkShaderProgram* program)
{
  const FramePlan& plan = *frame.plan;
  const bool reduce = ReducesInAnyOrder(plan.blendMode);
  const TransferFunctionTable table = frame.tables->Table();
  program->SetUniformi("transferFunction", this->TransferFunction->GetTextureUnit());
  program->SetUniformi("shadingMode", static_cast<int>(plan.values));
  program->SetUniformi("tableSize", table.size);
  program->SetUniformi("tableWidth", std::min(table.size, TableRowWidth));
  program->SetUniformi("blendMode", reduce ? static_cast<int>(plan.blendMode) : 0);
  program->SetUniformi("clampEntries", reduce ? 0 : 1);
  if (reduce)
  {
    program->SetUniformi("intensityPrefix", this->IntensityPrefix->GetTextureUnit());
    double range[2];
    AverageRangeEntries(table, plan.averageRange, AverageRangeBeyond, range);
    const float averageRange[2] = { static_cast<float>(range[0]), static_cast<float>(range[1]) };
    program->SetUniform2f("averageRange", averageRange);
  }
  if (plan.preIntegrationTable)
  {
    program->SetUniformi("integralsHigh", this->IntegralsHigh->GetTextureUnit());
    program->SetUniformi("integralsLow", this->IntegralsLow->GetTextureUnit());
  }
  // Texel centres: scalar `low` at 0.5/N, `high` at (N-0.5)/N.
  const double n = table.size, low = table.low, high = table.high;
  const double scale = (n - 1.0) / n / (high - low);
  program->SetUniformf("scalarScale", static_cast<float>(scale));
  program->SetUniformf("scalarShift", static_cast<float>(0.5 / n - low * scale));
  const double entryScale = (n - 1.0) / (high - low);
  program->SetUniformf("entryScale", static_cast<float>(entryScale));
  program->SetUniformf("entryShift", static_cast<float>(-low * entryScale));
  const PerspectiveInterpolation& view = plan.interpolation;
  program->SetUniformi("perspectiveExact", plan.perspectiveExact ? 1 : 0);
  program->SetUniformf("inverseDepthScale", static_cast<float>(view.inverseWScale));
  program->SetUniformf("inverseDepthOffset", static_cast<float>(view.inverseWOffset));
  const float rayScale[2] = { static_cast<float>(view.scaleX), static_cast<float>(view.scaleY) };
  const float rayShift[2] = { static_cast<float>(view.shiftX), static_cast<float>(view.shiftY) };
  program->SetUniform2f("rayScale", rayScale);
  program->SetUniform2f("rayShift", rayShift);
  program->SetUniformf("inverseUnitDistance", static_cast<float>(1.0 / frame.UnitDistance()));
  program->SetUniformi("peelRanges", frame.peel ? 1 : 0);
  // Unused, the peel's samplers still name a unit: the transfer function's, of their own type
  // (samplers of different types on one unit fail the draw, and the light texture may get
  // the unit they would otherwise default to).
  const int transferUnit = this->TransferFunction->GetTextureUnit();
  program->SetUniformi(
    "peelFront", frame.peel ? frame.peel->Ranges(0)->GetTextureUnit() : transferUnit);
  program->SetUniformi(
    "peelBack", frame.peel ? frame.peel->Ranges(1)->GetTextureUnit() : transferUnit);
  this->SetClippingUniforms(frame, program);
}

PixelRegion OpenGLBackend::DrawnPixels(const BackendFrame& frame) const
{
  if (!this->DrawsIntoOwnTarget())
  {
    return { frame.origin[0], frame.origin[1], frame.origin[0] + frame.size[0],
      frame.origin[1] + frame.size[1] };
  }
  const ImageSize size =
    this->SampledTargetUsed ? frame.Image() : ImageSize{ frame.size[0], frame.size[1] };
  return { 0, 0, size.width, size.height };
}

void OpenGLBackend::SetClippingUniforms(const BackendFrame& frame, vtkShaderProgram* program)
{
  // The eye ray of each fragment, for depth peeling's ranges and the clipping planes: from
  // its pixel in the target drawn into (the window's viewport, or a target of its own).
  const DepthClipping& clipping = frame.plan->clipping;
  program->SetUniformi("depthPerspective", clipping.perspective ? 1 : 0);
  program->SetUniformf("depthA", static_cast<float>(clipping.a));
  program->SetUniformf("depthB", static_cast<float>(clipping.b));
  const PixelRegion drawn = this->DrawnPixels(frame);
  const float origin[2] = { static_cast<float>(drawn.x0), static_cast<float>(drawn.y0) };
  const float size[2] = { static_cast<float>(drawn.x1 - drawn.x0),
    static_cast<float>(drawn.y1 - drawn.y0) };
  program->SetUniform2f("viewportOrigin", origin);
  program->SetUniform2f("viewportSize", size);
  const float orthoScale[2] = { static_cast<float>(clipping.scaleX),
    static_cast<float>(clipping.scaleY) };
  const float orthoShift[2] = { static_cast<float>(clipping.shiftX),
    static_cast<float>(clipping.shiftY) };
  program->SetUniform2f("orthoScale", orthoScale);
  program->SetUniform2f("orthoShift", orthoShift);
  const ClipPlanes& planes = frame.plan->clipPlanes;
  float values[ClipPlanes::Max][4] = {};
  for (int i = 0; i < planes.count; ++i)
  {
    for (int k = 0; k < 4; ++k)
    {
      values[i][k] = static_cast<float>(planes.plane[i][k]);
    }
  }
  program->SetUniformi("clipPlaneCount", planes.count);
  program->SetUniform4fv("clipPlanes", ClipPlanes::Max, values);
}

bool OpenGLBackend::DrawPeel(const BackendFrame& frame, DrawTimes& times)
{
  this->ErrorMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  if (!this->PlannedFor(frame, BatchTarget::Slots))
  {
    return false;
  }
  vtkShaderProgram* program = this->ReadyProgram(frame.window, frame.plan->lit);
  if (!program)
  {
    this->ErrorMessage = "could not compile the MTPT shaders";
    return false;
  }
  this->UploadTables(frame);
  if (!frame.peel->BindColourTarget(frame.window, this->ErrorMessage))
  {
    return false;
  }
  this->FloatTargetUsed = this->SampledTargetUsed = false;
  this->PeelTargetUsed = true;
  frame.peel->Ranges(0)->Activate();
  frame.peel->Ranges(1)->Activate();
  AtScopeEnd unbind{ [&]
    {
      frame.peel->Ranges(0)->Deactivate();
      frame.peel->Ranges(1)->Deactivate();
      this->PeelTargetUsed = false;
      frame.peel->UnbindColourTarget(frame.window);
    } };
  return this->DrawBatches(frame, program, times);
}

bool OpenGLBackend::Draw(const BackendFrame& frame, DrawTimes& times)
{
  this->ErrorMessage.clear();
  this->WarningMessage.clear();
  TakeOpenGLErrors(); // errors left by others are not this backend's to report
  if (!this->PlannedFor(frame, BatchTarget::Slots))
  {
    return false;
  }
  vtkOpenGLRenderWindow* window = frame.window;
  vtkShaderProgram* program = this->ReadyProgram(window, frame.plan->lit);
  if (!program)
  {
    this->ErrorMessage = "could not compile the MTPT shaders";
    return false;
  }
  this->UploadTables(frame);
  if (ReducesInAnyOrder(frame.plan->blendMode))
  {
    return this->DrawReduced(frame, program, times);
  }
  this->BindTarget(frame, frame.floatFramebuffer);
  bool drawn = false;
  try
  {
    drawn = this->DrawBatches(frame, program, times);
  }
  catch (...)
  {
    // The window's framebuffer again, not the target's, for whatever VTK draws next.
    if (BlendTarget* target = this->BoundTarget())
    {
      target->Restore(window);
    }
    throw;
  }
  return this->WriteTarget(frame, drawn, times) && drawn;
}

bool OpenGLBackend::DrawReduced(
  const BackendFrame& frame, vtkShaderProgram* program, DrawTimes& times)
{
  vtkOpenGLRenderWindow* window = frame.window;
  this->BindTarget(frame, true);
  BlendTarget* target = this->BoundTarget();
  if (!target)
  {
    this->ErrorMessage = "blend modes other than composite need a float target, which this "
                         "context cannot make" +
      (this->WarningMessage.empty() ? "" : " (" + this->WarningMessage + ")");
    this->WarningMessage.clear();
    return false;
  }
  // The target keeps the window's depth; its colour starts at the mode's neutral value.
  const bool extreme = frame.plan->blendMode == BlendMode::MaximumIntensity ||
    frame.plan->blendMode == BlendMode::MinimumIntensity;
  const float neutral[4] = { extreme ? -1e30f : 0.0f, 0.0f, 0.0f, 0.0f };
  BlendTarget::ClearColour(window, neutral);
  bool drawn = false;
  {
    AtScopeEnd restore{ [&] { target->Restore(window); } };
    drawn = this->DrawBatches(frame, program, times);
  }
  const auto start = Clock::now();
  const bool resolved = drawn && this->ResolveReduced(frame, target->Colour());
  const double seconds = SecondsSince(start);
  times.draw += seconds;
  times.viewport += seconds;
  return resolved;
}

bool OpenGLBackend::ResolveReduced(const BackendFrame& frame, vtkTextureObject* reduced)
{
  vtkShaderProgram* program =
    BlendTarget::ReadyQuad(this->ReduceQuad, frame.window, vtkMTPTReduceFS);
  if (!program)
  {
    this->ErrorMessage = "could not compile the shader that maps the blend mode's values to "
                         "colour";
    return false;
  }
  reduced->Activate(); // read texel by texel: its filtering does not matter
  this->TransferFunction->Activate();
  program->SetUniformi("reduced", reduced->GetTextureUnit());
  program->SetUniformi("transferFunction", this->TransferFunction->GetTextureUnit());
  program->SetUniformi("blendMode", static_cast<int>(frame.plan->blendMode));
  program->SetUniformi("tableSize", frame.tables->Table().size);
  program->SetUniformf("inverseUnitDistance", static_cast<float>(1.0 / frame.UnitDistance()));
  BlendTarget::DrawQuad(frame.window, *this->ReduceQuad, frame.origin, frame.size, true);
  this->TransferFunction->Deactivate();
  reduced->Deactivate();
  return OpenGLSucceeded("mapping the blend mode's values to colour", this->ErrorMessage);
}

void OpenGLBackend::BindTarget(const BackendFrame& frame, bool floatTarget)
{
  vtkOpenGLRenderWindow* window = frame.window;
  this->FloatTargetUsed = this->SampledTargetUsed = false;
  std::string error;
  if (frame.Sampled() && !this->SampledTargetFailed)
  {
    this->SampledTargetUsed = this->SampledTarget.CaptureSampled(
      window, frame.origin, frame.size, frame.Image(), this->Target, error);
    if (!this->SampledTargetUsed)
    {
      // In this context: not tried again every frame (SampledImageLimit says 0 from now
      // on). This frame's cells were culled against the sampled image's pixel centres, so
      // drawn at the viewport's size it may miss a few of the smallest.
      this->SampledTargetFailed = true;
      this->WarningMessage = error + "; drawing at the viewport's size";
    }
  }
  if (!this->SampledTargetUsed && floatTarget && !this->FloatTargetFailed)
  {
    this->FloatTargetUsed = this->Target.Capture(window, frame.origin, frame.size, error);
    if (!this->FloatTargetUsed)
    {
      this->FloatTargetFailed = true; // in this context: not tried again every frame
      this->WarningMessage = error + "; blending in the window's own framebuffer";
    }
  }
}

bool OpenGLBackend::WriteTarget(const BackendFrame& frame, bool drawn, DrawTimes& times)
{
  const auto start = Clock::now();
  bool written = true;
  if (this->SampledTargetUsed)
  {
    this->SampledTarget.Restore(frame.window);
    written = drawn &&
      this->SampledTarget.BlendOverWindow(
        frame.window, this->SampledTarget.Colour(), frame.origin, frame.size, this->ErrorMessage);
  }
  else if (this->FloatTargetUsed)
  {
    this->Target.Restore(frame.window);
    written = drawn &&
      this->Target.WriteToWindow(
        frame.window, this->Target.Colour(), frame.origin, frame.size, this->ErrorMessage);
  }
  const double seconds = SecondsSince(start);
  times.draw += seconds;
  times.viewport += seconds;
  return written;
}

bool OpenGLBackend::DrawBatches(
  const BackendFrame& frame, vtkShaderProgram* program, DrawTimes& times)
{
  vtkOpenGLState* state = frame.window->GetState();
  vtkOpenGLState::ScopedglDepthMask depthMask(state);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFunction(state);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable cull(state, GL_CULL_FACE);
  vtkOpenGLState::ScopedglViewport viewport(state);
  vtkOpenGLState::ScopedglScissor scissor(state);
  if (this->DrawsIntoOwnTarget())
  {
    const PixelRegion drawn = this->DrawnPixels(frame);
    state->vtkglViewport(0, 0, drawn.x1, drawn.y1);
    state->vtkglScissor(0, 0, drawn.x1, drawn.y1);
  }
  // A peeling pass may have left another blend equation (GL_MAX).
  GLint equation[2] = { GL_FUNC_ADD, GL_FUNC_ADD };
  glGetIntegerv(GL_BLEND_EQUATION_RGB, &equation[0]);
  glGetIntegerv(GL_BLEND_EQUATION_ALPHA, &equation[1]);
  // Depth test against opaque geometry without depth writes. A peel's ranges end at the
  // opaque depth already, and its target has no depth.
  state->vtkglDepthMask(GL_FALSE);
  if (this->PeelTargetUsed)
  {
    state->vtkglDisable(GL_DEPTH_TEST);
  }
  else
  {
    state->vtkglEnable(GL_DEPTH_TEST);
  }
  state->vtkglDisable(GL_CULL_FACE);
  SetBlending(*frame.plan, state);
  this->TransferFunction->Activate();
  this->IntegralsHigh->Activate();
  this->IntegralsLow->Activate();
  this->IntensityPrefix->Activate();
  AtScopeEnd deactivate{ [&]
    {
      this->TransferFunction->Deactivate();
      this->IntegralsHigh->Deactivate();
      this->IntegralsLow->Deactivate();
      this->IntensityPrefix->Deactivate();
      state->vtkglBlendEquationSeparate(
        static_cast<GLenum>(equation[0]), static_cast<GLenum>(equation[1]));
    } };
  this->SetUniforms(frame, program);

  // Batch after batch, as the pipeline decomposes them: upload, draw. Draw calls return
  // before the rasterizer is done, so the next batch's decomposition overlaps the previous
  // batch's drawing.
  const bool drawn = Drawn(frame.pipeline->DrawBatches(*frame.plan,
                             [&](const Batch& batch)
                             {
                               this->Upload(frame, batch, times);
                               if (frame.plan->lit)
                               {
                                 this->BindLights(frame, program, batch, times);
                               }
                               const auto start = Clock::now();
                               this->DrawUploaded(program);
                               if (frame.synchronizedTiming)
                               {
                                 glFinish();
                               }
                               times.draw += SecondsSince(start);
                               return OpenGLSucceeded("drawing the tetrahedra", this->ErrorMessage);
                             }),
    times);
  return drawn;
}

void OpenGLBackend::Upload(const BackendFrame& frame, const Batch& batch, DrawTimes& times)
{
  if (batch.version == this->UploadedBuffers)
  {
    return; // the buffers hold this decomposition already
  }
  const auto start = Clock::now();
  const std::size_t count = batch.count;
  this->VertexBuffer->SetStride(static_cast<unsigned int>(sizeof(TetVertex)));
  this->VertexBuffer->Upload(reinterpret_cast<const float*>(batch.vertices),
    count * VerticesPerTetrahedron * FloatsPerVertex, vtkOpenGLBufferObject::ArrayBuffer);
  this->Triangles.IBO->Upload(
    batch.indices, count * IndicesPerTetrahedron, vtkOpenGLBufferObject::ElementArrayBuffer);
  this->Triangles.IBO->IndexCount = count * IndicesPerTetrahedron;
  if (frame.synchronizedTiming)
  {
    glFinish();
  }
  this->UploadedBuffers = batch.version;
  times.upload += SecondsSince(start);
}

void OpenGLBackend::BindLights(
  const BackendFrame& frame, vtkShaderProgram* program, const Batch& batch, DrawTimes& times)
{
  this->UploadLights(frame, batch, times);
  this->LightTexture->Activate();
  program->SetUniformi("lightFactors", this->LightTexture->GetTextureUnit());
}

void OpenGLBackend::UploadLights(const BackendFrame& frame, const Batch& batch, DrawTimes& times)
{
  if (this->LightTexture->GetHandle() != 0 && batch.lightsVersion == this->UploadedLights)
  {
    return; // the texture holds these slots lit so already (a frame that moved nothing)
  }
  const auto start = Clock::now();
  // A texture buffer is never empty.
  const LightFactors unlit = Unlit();
  const LightFactors* lights = batch.count > 0 ? batch.lights : &unlit;
  const std::size_t count = std::max<std::size_t>(1, batch.count);
  this->LightBuffer->SetType(vtkOpenGLBufferObject::TextureBuffer);
  this->LightBuffer->Upload(reinterpret_cast<const float*>(lights),
    count * sizeof(LightFactors) / sizeof(float), vtkOpenGLBufferObject::TextureBuffer);
  this->LightTexture->SetContext(frame.window);
  this->LightTexture->CreateTextureBuffer(
    static_cast<unsigned int>(2 * count), 4, VTK_FLOAT, this->LightBuffer);
  this->UploadedLights = batch.lightsVersion;
  times.upload += SecondsSince(start);
}

void OpenGLBackend::DrawUploaded(vtkShaderProgram* program)
{
  this->VertexBuffer->Bind();
  this->Triangles.VAO->Bind();
  if (this->Triangles.ShaderSourceTime > this->Triangles.AttributeUpdateTime)
  {
    // The layout of mtpt::TetVertex.
    const auto stride = sizeof(TetVertex);
    this->Triangles.VAO->AddAttributeArray(program, this->VertexBuffer, "vertexNDC",
      offsetof(TetVertex, x), stride, VTK_FLOAT, 3, false);
    this->Triangles.VAO->AddAttributeArray(program, this->VertexBuffer, "scalarFrontBack",
      offsetof(TetVertex, scalarFront), stride, VTK_FLOAT, 2, false);
    // The same bytes as four normalized 16-bit channels (mtpt::StoreVertexColour).
    this->Triangles.VAO->AddAttributeArray(program, this->VertexBuffer, "vertexColour",
      offsetof(TetVertex, scalarFront), stride, VTK_UNSIGNED_SHORT, 4, true);
    this->Triangles.VAO->AddAttributeArray(program, this->VertexBuffer, "thickness",
      offsetof(TetVertex, thickness), stride, VTK_FLOAT, 1, false);
    this->Triangles.AttributeUpdateTime.Modified();
  }
  this->Triangles.IBO->Bind();
  // GLsizei is 32-bit: draw in chunks of whole tetrahedra below that limit.
  const std::size_t indices = this->Triangles.IBO->IndexCount;
  const std::size_t chunk =
    (static_cast<std::size_t>(INT_MAX) / IndicesPerTetrahedron) * IndicesPerTetrahedron;
  for (std::size_t offset = 0; offset < indices; offset += chunk)
  {
    const std::size_t size = std::min(chunk, indices - offset);
    // gl_PrimitiveID counts from 0 in each call: the lighting's slots from this one's first.
    if (this->ProgramLit)
    {
      program->SetUniformi("lightSlotBase", static_cast<int>(offset / IndicesPerTetrahedron));
    }
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(size), GL_UNSIGNED_INT,
      reinterpret_cast<const void*>(offset * sizeof(std::uint32_t)));
  }
  this->Triangles.IBO->Release();
  this->Triangles.VAO->Release();
  this->VertexBuffer->Release();
  if (this->ProgramLit)
  {
    this->LightTexture->Deactivate(); // bound by BindLights
  }
}

void OpenGLBackend::ReleaseGraphicsResources(vtkWindow* window)
{
  this->VertexBuffer->ReleaseGraphicsResources();
  this->LightBuffer->ReleaseGraphicsResources();
  this->Triangles.ReleaseGraphicsResources(window);
  if (window)
  {
    this->TransferFunction->ReleaseGraphicsResources(window);
    this->IntegralsHigh->ReleaseGraphicsResources(window);
    this->IntegralsLow->ReleaseGraphicsResources(window);
    this->IntensityPrefix->ReleaseGraphicsResources(window);
    this->LightTexture->ReleaseGraphicsResources(window);
    if (this->ReduceQuad)
    {
      this->ReduceQuad->ReleaseGraphicsResources(window);
    }
  }
  this->ReduceQuad.reset();
  this->Target.ReleaseGraphicsResources(window);
  this->SampledTarget.ReleaseGraphicsResources(window);
  this->UploadedBuffers = this->UploadedTables = this->UploadedLights = 0;
  this->FloatTargetFailed = this->SampledTargetFailed = false;
  this->MaxTargetSize = 0;
}

} // namespace mtpt
