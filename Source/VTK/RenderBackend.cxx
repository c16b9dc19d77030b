// SPDX-License-Identifier: BSD-3-Clause
#include "RenderBackend.h"

#include "OpenGLHeader.h"

#include <string>

namespace mtpt
{

namespace
{

const char* ErrorName(GLenum error)
{
  switch (error)
  {
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    default:
      return "unknown OpenGL error";
  }
}

} // namespace

std::string TakeOpenGLErrors()
{
  std::string names;
  // Bounded: a lost context may report an error for ever.
  for (int i = 0; i < 16; ++i)
  {
    const GLenum error = glGetError();
    if (error == GL_NO_ERROR)
    {
      break;
    }
    names += (names.empty() ? "" : ", ") + std::string(ErrorName(error));
  }
  return names;
}

bool DrawFramebufferIsMultisampled()
{
  GLint sampleBuffers = 0;
  glGetIntegerv(GL_SAMPLE_BUFFERS, &sampleBuffers);
  return sampleBuffers > 0;
}

} // namespace mtpt
