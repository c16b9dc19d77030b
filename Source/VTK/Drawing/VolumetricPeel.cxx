// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/VolumetricPeel.h"

#include "Drawing/RenderBackend.h"
#include "vtkMTPTPeelFS.h"

#include "vtkAbstractVolumeMapper.h"
#include "vtkInformation.h"
#include "vtkInformationObjectBaseVectorKey.h"
#include "vtkOpenGLFramebufferObject.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderPass.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "vtkVolume.h"
#include "Basics/OpenGLHeader.h"

namespace mtpt
{

namespace
{

/**
 * Binds `target` for drawing into both its attachments. vtkOpenGLState caches draw buffers
 * per binding and skips a glDrawBuffers that matches its cache, which after binding another
 * framebuffer may be the previous one's: a freshly bound target would then draw into its
 * first attachment only. The draw buffers are therefore set in OpenGL as well.
 */
void BindBothAttachments(vtkOpenGLFramebufferObject* target)
{
  target->Bind(vtkOpenGLFramebufferObject::GetDrawMode());
  target->ActivateDrawBuffers(2);
  const GLenum buffers[2] = { GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1 };
  glDrawBuffers(2, buffers);
}

/// The tag the pass replaces with its per-pixel code: still there, the pass took no part.
const char* const CallSite = "//VTK::CallWorker::Impl";

/// vtkMTPTPeelFS with the pass's substitutions (pre and post, as a mapper applies them).
std::string PassShader(
  vtkOpenGLRenderPass* pass, vtkAbstractVolumeMapper* mapper, vtkVolume* volume)
{
  std::string vertex, geometry, fragment = vtkMTPTPeelFS;
  if (!pass->PreReplaceShaderValues(vertex, geometry, fragment, mapper, volume) ||
    !pass->PostReplaceShaderValues(vertex, geometry, fragment, mapper, volume))
  {
    return std::string();
  }
  return fragment;
}

} // namespace

VolumetricPeel::VolumetricPeel() = default;
VolumetricPeel::~VolumetricPeel() = default;

vtkOpenGLRenderPass* VolumetricPeel::ActivePass(vtkVolume* volume, vtkAbstractVolumeMapper* mapper)
{
  vtkInformation* info = volume ? volume->GetPropertyKeys() : nullptr;
  if (!info || !info->Has(vtkOpenGLRenderPass::RenderPasses()))
  {
    return nullptr;
  }
  const int passes = info->Length(vtkOpenGLRenderPass::RenderPasses());
  for (int i = 0; i < passes; ++i)
  {
    auto* pass =
      vtkOpenGLRenderPass::SafeDownCast(info->Get(vtkOpenGLRenderPass::RenderPasses(), i));
    if (!pass)
    {
      continue;
    }
    const std::string fragment = PassShader(pass, mapper, volume);
    if (!fragment.empty() && fragment.find(CallSite) == std::string::npos)
    {
      return pass;
    }
  }
  return nullptr;
}

vtkOpenGLQuadHelper* VolumetricPeel::Quad(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
  vtkAbstractVolumeMapper* mapper, vtkVolume* volume)
{
  const std::string fragment = PassShader(pass, mapper, volume);
  if (fragment.empty())
  {
    return nullptr;
  }
  std::unique_ptr<vtkOpenGLQuadHelper>& quad = this->Quads[fragment];
  if (!quad)
  {
    quad = std::make_unique<vtkOpenGLQuadHelper>(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), fragment.c_str(), "");
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(quad->Program);
  }
  return quad->Program && quad->Program->GetCompiled() ? quad.get() : nullptr;
}

bool VolumetricPeel::Allocate(
  vtkOpenGLRenderWindow* window, vtkOpenGLFramebufferObject* target, std::string& error)
{
  const int* size = this->Size;
  if (target->GetFBOIndex() != 0)
  {
    int current[2];
    target->GetLastSize(current);
    if (current[0] != size[0] || current[1] != size[1])
    {
      target->Bind();
      target->Resize(size[0], size[1]);
    }
    return true;
  }
  target->SetContext(window);
  const char* description = nullptr;
  if (!target->PopulateFramebuffer(size[0], size[1], /*textures*/ true, /*colour attachments*/ 2,
        VTK_FLOAT, /*depth*/ false, 0, /*samples*/ 0) ||
    !vtkOpenGLFramebufferObject::GetFrameBufferStatus(
      vtkOpenGLFramebufferObject::GetDrawMode(), description))
  {
    error = std::string("no two-target float framebuffer for the peel (") +
      (description ? description : "allocation failed") + ")";
    return false;
  }
  return true;
}

bool VolumetricPeel::RunQuad(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
  vtkAbstractVolumeMapper* mapper, vtkVolume* volume, int answer, std::string& error)
{
  vtkOpenGLQuadHelper* quad = this->Quad(window, pass, mapper, volume);
  if (!quad)
  {
    error = "could not compile the depth-peeling program";
    return false;
  }
  vtkShaderProgram* program = quad->Program;
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable cull(state, GL_CULL_FACE);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  state->vtkglDisable(GL_CULL_FACE);
  state->vtkglDisable(GL_DEPTH_TEST);
  // The pass sets the uniforms of its own code (its depth textures).
  pass->SetShaderParameters(program, mapper, volume, quad->VAO);
  program->SetUniformi("answer", answer);
  const float inverseSize[2] = { 1.0f / this->Size[0], 1.0f / this->Size[1] };
  program->SetUniform2f("in_inverseWindowSize", inverseSize);
  program->SetUniformf("g_opacityThreshold", 1.0f); // no early termination
  std::vector<vtkTextureObject*> textures;
  auto bind = [&](const char* name, vtkTextureObject* texture)
  {
    if (program->IsUniformUsed(name))
    {
      texture->Activate();
      program->SetUniformi(name, texture->GetTextureUnit());
      textures.push_back(texture);
    }
  };
  if (answer == 0)
  {
    // Recording: the pass's previous front colour reads as transparent, so that its front
    // output is the front range itself.
    bind("lastFrontColorTex", this->Transparent);
  }
  else
  {
    bind("recordedFront", this->Ranges(0));
    bind("recordedBack", this->Ranges(1));
    bind("frontColour",
      this->UploadedColours ? this->FrontUpload.Get()
                            : this->ColourTarget->GetColorAttachmentAsTextureObject(0));
    bind("backColour",
      this->UploadedColours ? this->BackUpload.Get()
                            : this->ColourTarget->GetColorAttachmentAsTextureObject(1));
  }
  quad->Render();
  for (vtkTextureObject* texture : textures)
  {
    texture->Deactivate();
  }
  return OpenGLSucceeded(std::string(answer == 0 ? "recording" : "answering") +
      " the depth-peeling pass's ranges",
    error);
}

bool VolumetricPeel::RecordRanges(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
  vtkAbstractVolumeMapper* mapper, vtkVolume* volume, const int size[2], std::string& error)
{
  TakeOpenGLErrors(); // errors left by others are not the peel's to report
  this->Size[0] = size[0];
  this->Size[1] = size[1];
  if (this->Transparent->GetHandle() == 0)
  {
    const float zero[4] = { 0, 0, 0, 0 };
    this->Transparent->SetContext(window);
    this->Transparent->Create2DFromRaw(1, 1, 4, VTK_FLOAT, const_cast<float*>(zero));
  }
  vtkOpenGLState* state = window->GetState();
  state->PushFramebufferBindings();
  bool recorded = this->Allocate(window, this->RangeTarget, error);
  if (recorded)
  {
    vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
    vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
    vtkOpenGLState::ScopedglClearColor clearColour(state);
    vtkOpenGLState::ScopedglColorMask colourMask(state);
    state->vtkglDisable(GL_BLEND);
    state->vtkglDisable(GL_SCISSOR_TEST);
    state->vtkglColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    BindBothAttachments(this->RangeTarget);
    state->vtkglClearColor(0.0f, 0.0f, 0.0f, 0.0f);
    state->vtkglClear(GL_COLOR_BUFFER_BIT);
    recorded = this->RunQuad(window, pass, mapper, volume, 0, error);
  }
  state->PopFramebufferBindings();
  return recorded;
}

vtkTextureObject* VolumetricPeel::Ranges(int which)
{
  // The pass's code writes the back range to output 0 and the front range to output 1.
  return this->RangeTarget->GetColorAttachmentAsTextureObject(which == 0 ? 1 : 0);
}

bool VolumetricPeel::ReadRanges(vtkOpenGLRenderWindow* window, std::vector<float>& front,
  std::vector<float>& back, std::string& error)
{
  const std::size_t pixels = static_cast<std::size_t>(this->Size[0]) * this->Size[1];
  std::vector<float> recorded(4 * pixels);
  vtkOpenGLState* state = window->GetState();
  state->PushReadFramebufferBinding();
  this->RangeTarget->Bind(vtkOpenGLFramebufferObject::GetReadMode());
  for (int which = 0; which < 2; ++which)
  {
    std::vector<float>& ranges = which == 0 ? front : back;
    this->RangeTarget->ActivateReadBuffer(which == 0 ? 1 : 0);
    // Through VTK's state cache, as BlendTarget::Read: a change behind its back leaves VTK's
    // cached alignment stale for its own next read. (Float RGBA rows are 4-byte aligned.)
    state->vtkglPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, this->Size[0], this->Size[1], GL_RGBA, GL_FLOAT, recorded.data());
    ranges.resize(2 * pixels);
    for (std::size_t i = 0; i < pixels; ++i)
    {
      const bool asked = recorded[4 * i + 2] > 0.5f;
      ranges[2 * i] = asked ? recorded[4 * i] : 1.0f;
      ranges[2 * i + 1] = asked ? recorded[4 * i + 1] : 0.0f;
    }
  }
  state->PopReadFramebufferBinding();
  return OpenGLSucceeded("reading the depth-peeling pass's ranges back", error);
}

bool VolumetricPeel::BindColourTarget(vtkOpenGLRenderWindow* window, std::string& error)
{
  vtkOpenGLState* state = window->GetState();
  state->PushFramebufferBindings();
  if (!this->Allocate(window, this->ColourTarget, error))
  {
    state->PopFramebufferBindings();
    return false;
  }
  BindBothAttachments(this->ColourTarget);
  vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
  vtkOpenGLState::ScopedglClearColor clearColour(state);
  vtkOpenGLState::ScopedglColorMask colourMask(state);
  state->vtkglDisable(GL_SCISSOR_TEST);
  state->vtkglColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  state->vtkglClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  state->vtkglClear(GL_COLOR_BUFFER_BIT);
  this->UploadedColours = false;
  return true;
}

void VolumetricPeel::UnbindColourTarget(vtkOpenGLRenderWindow* window)
{
  window->GetState()->PopFramebufferBindings();
}

bool VolumetricPeel::UploadColours(
  vtkOpenGLRenderWindow* window, const float* front, const float* back, std::string& error)
{
  for (vtkTextureObject* texture : { this->FrontUpload.Get(), this->BackUpload.Get() })
  {
    texture->SetContext(window);
    texture->Create2DFromRaw(this->Size[0], this->Size[1], 4, VTK_FLOAT,
      const_cast<float*>(texture == this->FrontUpload.Get() ? front : back));
  }
  this->UploadedColours = true;
  return OpenGLSucceeded("uploading the volume's peel", error);
}

bool VolumetricPeel::Answer(vtkOpenGLRenderWindow* window, vtkOpenGLRenderPass* pass,
  vtkAbstractVolumeMapper* mapper, vtkVolume* volume, std::string& error)
{
  // Into the pass's targets, with its blending and viewport: as its own volume code would.
  return this->RunQuad(window, pass, mapper, volume, 1, error);
}

void VolumetricPeel::ReleaseGraphicsResources(vtkWindow* window)
{
  for (auto& quad : this->Quads)
  {
    quad.second->ReleaseGraphicsResources(window);
  }
  this->Quads.clear();
  this->RangeTarget->ReleaseGraphicsResources(window);
  this->ColourTarget->ReleaseGraphicsResources(window);
  if (window)
  {
    this->Transparent->ReleaseGraphicsResources(window);
    this->FrontUpload->ReleaseGraphicsResources(window);
    this->BackUpload->ReleaseGraphicsResources(window);
  }
}

} // namespace mtpt
