// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/BlendTarget.h"

#include "Drawing/RenderBackend.h"
#include "vtkMTPTCompositeFS.h"

#include "vtkOpenGLFramebufferObject.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "Basics/OpenGLHeader.h"

#include <cstdlib>
#include <cstring>

namespace mtpt
{

namespace
{

/// Testing only: MTPT_TESTING_FAULT=cpu-read-back makes the CPU backend's read-back fail
/// with a real OpenGL error, to exercise the path a failing driver takes (see the robustness
/// and install tests).
bool ReadBackFaultInjected()
{
  const char* fault = std::getenv("MTPT_TESTING_FAULT");
  return fault && std::strcmp(fault, "cpu-read-back") == 0;
}

} // namespace

BlendTarget::BlendTarget(int colourType)
  : ColourType(colourType)
{
}
BlendTarget::~BlendTarget() = default;

vtkTextureObject* BlendTarget::Colour()
{
  return this->Framebuffer->GetColorAttachmentAsTextureObject(0);
}

bool BlendTarget::Allocate(vtkOpenGLRenderWindow* window, const int size[2], std::string& error)
{
  // The depth format must equal the window's for the depth copy (a blit converts no depth).
  const int depthBits = window->GetDepthBufferSize() > 0 ? window->GetDepthBufferSize() : 24;
  if (this->Allocated && depthBits == this->DepthBits)
  {
    if (size[0] != this->Size[0] || size[1] != this->Size[1])
    {
      this->Framebuffer->Bind();
      this->Framebuffer->Resize(size[0], size[1]);
      this->Size[0] = size[0];
      this->Size[1] = size[1];
    }
    return true;
  }
  if (this->Allocated)
  {
    this->Framebuffer->ReleaseGraphicsResources(window);
  }
  this->Framebuffer->SetContext(window);
  const bool made = this->Framebuffer->PopulateFramebuffer(size[0], size[1], /*textures*/ true,
    /*colour attachments*/ 1, this->ColourType, /*depth*/ true, depthBits, /*samples*/ 0);
  const char* description = nullptr;
  if (!made ||
    !vtkOpenGLFramebufferObject::GetFrameBufferStatus(
      vtkOpenGLFramebufferObject::GetDrawMode(), description))
  {
    error = std::string("no single-sampled framebuffer (") +
      (description ? description : "allocation failed") + ")";
    this->Allocated = false;
    return false;
  }
  this->Allocated = true;
  this->DepthBits = depthBits;
  this->Size[0] = size[0];
  this->Size[1] = size[1];
  return true;
}

bool BlendTarget::Capture(
  vtkOpenGLRenderWindow* window, const int origin[2], const int size[2], std::string& error)
{
  vtkOpenGLState* state = window->GetState();
  // Read from what the renderer draws into (its draw binding), whatever is bound for reading.
  int windowFramebuffer = 0;
  state->vtkglGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &windowFramebuffer);
  state->PushFramebufferBindings();
  if (!this->Allocate(window, size, error))
  {
    state->PopFramebufferBindings();
    return false;
  }
  state->vtkglBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<unsigned int>(windowFramebuffer));
  if (windowFramebuffer == 0)
  {
    state->vtkglReadBuffer(GL_BACK);
  }
  this->Framebuffer->Bind(vtkOpenGLFramebufferObject::GetDrawMode());
  this->Framebuffer->ActivateDrawBuffer(0);
  // Equal sizes: the one blit a multisampled source allows; it resolves the samples.
  state->vtkglBlitFramebuffer(origin[0], origin[1], origin[0] + size[0], origin[1] + size[1], 0, 0,
    size[0], size[1], GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  this->Framebuffer->Bind(vtkOpenGLFramebufferObject::GetReadMode());
  this->Framebuffer->ActivateReadBuffer(0);
  if (!OpenGLSucceeded("copying the window's colour and depth into a float framebuffer", error))
  {
    state->PopFramebufferBindings();
    return false;
  }
  return true;
}

bool BlendTarget::CaptureSampled(vtkOpenGLRenderWindow* window, const int origin[2],
  const int size[2], const ImageSize& sampled, BlendTarget& viewport, std::string& error)
{
  const int sampledSize[2] = { sampled.width, sampled.height };
  vtkOpenGLState* state = window->GetState();
  int windowFramebuffer = 0;
  state->vtkglGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &windowFramebuffer);
  state->PushFramebufferBindings();
  if (!viewport.Allocate(window, size, error) || !this->Allocate(window, sampledSize, error))
  {
    state->PopFramebufferBindings();
    return false;
  }
  {
    // Blits are scissored, and the renderer's scissor box is its viewport's.
    vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
    state->vtkglDisable(GL_SCISSOR_TEST);
    state->vtkglBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<unsigned int>(windowFramebuffer));
    if (windowFramebuffer == 0)
    {
      state->vtkglReadBuffer(GL_BACK);
    }
    // The depth at its own size first (the one blit a multisampled source allows), then
    // scaled: GL_NEAREST reads the pixel under each destination pixel's centre.
    viewport.Framebuffer->Bind(vtkOpenGLFramebufferObject::GetDrawMode());
    state->vtkglBlitFramebuffer(origin[0], origin[1], origin[0] + size[0], origin[1] + size[1], 0,
      0, size[0], size[1], GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    viewport.Framebuffer->Bind(vtkOpenGLFramebufferObject::GetReadMode());
    this->Framebuffer->Bind(vtkOpenGLFramebufferObject::GetDrawMode());
    this->Framebuffer->ActivateDrawBuffer(0);
    state->vtkglBlitFramebuffer(0, 0, size[0], size[1], 0, 0, sampled.width, sampled.height,
      GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  }
  const float transparent[4] = { 0.0f, 0.0f, 0.0f, 0.0f };
  ClearColour(window, transparent);
  this->Framebuffer->Bind(vtkOpenGLFramebufferObject::GetReadMode());
  this->Framebuffer->ActivateReadBuffer(0);
  if (!OpenGLSucceeded("copying the window's depth into a sampled framebuffer", error))
  {
    state->PopFramebufferBindings();
    return false;
  }
  return true;
}

void BlendTarget::Restore(vtkOpenGLRenderWindow* window)
{
  window->GetState()->PopFramebufferBindings();
}

bool BlendTarget::WriteToWindow(vtkOpenGLRenderWindow* window, vtkTextureObject* texture,
  const int origin[2], const int size[2], std::string& error)
{
  // Nearest filtering: texture coordinates at pixel centres hit texel centres exactly.
  texture->SetMinificationFilter(vtkTextureObject::Nearest);
  texture->SetMagnificationFilter(vtkTextureObject::Nearest);
  return this->DrawTexture(window, texture, origin, size, false, error);
}

bool BlendTarget::BlendOverWindow(vtkOpenGLRenderWindow* window, vtkTextureObject* texture,
  const int origin[2], const int size[2], std::string& error)
{
  // Texture coordinate (X + 0.5) / width at pixel X: linear filtering is the bilinear
  // magnification of mtpt::MagnifyOver.
  texture->SetMinificationFilter(vtkTextureObject::Linear);
  texture->SetMagnificationFilter(vtkTextureObject::Linear);
  texture->SetWrapS(vtkTextureObject::ClampToEdge);
  texture->SetWrapT(vtkTextureObject::ClampToEdge);
  return this->DrawTexture(window, texture, origin, size, true, error);
}

void BlendTarget::ClearColour(vtkOpenGLRenderWindow* window, const float rgba[4])
{
  // Clears are scissored, and the renderer's scissor box is its viewport's.
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
  vtkOpenGLState::ScopedglClearColor clearColour(state);
  vtkOpenGLState::ScopedglColorMask colourMask(state);
  state->vtkglDisable(GL_SCISSOR_TEST);
  state->vtkglClearColor(rgba[0], rgba[1], rgba[2], rgba[3]);
  state->vtkglColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  state->vtkglClear(GL_COLOR_BUFFER_BIT);
}

vtkShaderProgram* BlendTarget::ReadyQuad(std::unique_ptr<vtkOpenGLQuadHelper>& quad,
  vtkOpenGLRenderWindow* window, const char* fragmentShader)
{
  if (!quad)
  {
    quad = std::make_unique<vtkOpenGLQuadHelper>(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), fragmentShader, "");
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(quad->Program);
  }
  return quad->Program && quad->Program->GetCompiled() ? quad->Program : nullptr;
}

void BlendTarget::DrawQuad(vtkOpenGLRenderWindow* window, vtkOpenGLQuadHelper& quad,
  const int origin[2], const int size[2], bool blend)
{
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglDepthMask depthMask(state);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglEnableDisable blending(state, GL_BLEND);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFunction(state);
  vtkOpenGLState::ScopedglViewport viewport(state);
  state->vtkglDepthMask(GL_FALSE);
  state->vtkglDisable(GL_DEPTH_TEST);
  if (blend)
  {
    // Premultiplied "over".
    state->vtkglEnable(GL_BLEND);
    state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  }
  else
  {
    state->vtkglDisable(GL_BLEND);
  }
  state->vtkglViewport(origin[0], origin[1], size[0], size[1]);
  quad.Render();
}

bool BlendTarget::DrawTexture(vtkOpenGLRenderWindow* window, vtkTextureObject* texture,
  const int origin[2], const int size[2], bool blend, std::string& error)
{
  vtkShaderProgram* program = ReadyQuad(this->Quad, window, vtkMTPTCompositeFS);
  if (!program)
  {
    error = "could not compile the shader that writes the image into the window";
    return false;
  }
  // Without blending the texture already holds what was drawn below it.
  texture->Activate();
  program->SetUniformi("image", texture->GetTextureUnit());
  DrawQuad(window, *this->Quad, origin, size, blend);
  texture->Deactivate();
  return OpenGLSucceeded("writing the image into the window", error);
}

bool BlendTarget::Read(vtkOpenGLRenderWindow* window, int x, int y, int width, int height,
  float* depth, unsigned char* rgba, std::string& error)
{
  // Through VTK's state cache: VTK sets the alignment it needs only when its cached value
  // differs, so a change behind its back makes its next read overflow.
  window->GetState()->vtkglPixelStorei(GL_PACK_ALIGNMENT, 4);
  // After the state call: VTK's state cache checks for and clears OpenGL errors when it
  // changes a setting, so the injected error is raised where a failing read would raise it.
  if (ReadBackFaultInjected())
  {
    glReadPixels(0, 0, 1, 1, GL_RGBA, GL_DEPTH_COMPONENT, nullptr); // an invalid read
  }
  if (depth)
  {
    glReadPixels(x, y, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
  }
  if (rgba)
  {
    glReadPixels(x, y, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
  }
  return OpenGLSucceeded("reading the window's colour and depth back", error);
}

void BlendTarget::ReleaseGraphicsResources(vtkWindow* window)
{
  if (window)
  {
    this->Framebuffer->ReleaseGraphicsResources(window);
    if (this->Quad)
    {
      this->Quad->ReleaseGraphicsResources(window);
    }
  }
  this->Quad.reset();
  this->Allocated = false;
  this->Size[0] = this->Size[1] = 0;
}

} // namespace mtpt
