// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/RenderBackend.h"

#include "mtpt/FramePipeline.h"

#include "Basics/OpenGLHeader.h"

#include <algorithm>

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

bool OpenGLSucceeded(const std::string& what, std::string& error)
{
  const std::string failed = TakeOpenGLErrors();
  if (failed.empty())
  {
    return true;
  }
  error = what + " failed (" + failed + ")";
  return false;
}

bool DrawFramebufferIsMultisampled()
{
  GLint sampleBuffers = 0;
  glGetIntegerv(GL_SAMPLE_BUFFERS, &sampleBuffers);
  return sampleBuffers > 0;
}

double BackendFrame::UnitDistance() const
{
  return plan->unitDistance / pipeline->Stats().attenuationScale;
}

bool RenderBackend::PlannedFor(const BackendFrame& frame, BatchTarget target)
{
  if (frame.plan->target == target)
  {
    return true;
  }
  this->ErrorMessage = target == BatchTarget::Fans
    ? "the frame was planned for OpenGL's slots, not the CPU compositor's fans"
    : "the frame was planned for the CPU compositor's fans, not OpenGL's slots";
  return false;
}

bool RenderBackend::Drawn(const BatchesDrawn& drawn, DrawTimes& times)
{
  times.batches += drawn.batches;
  times.stopped = times.stopped || drawn.stopped;
  return !drawn.failed;
}

} // namespace mtpt
