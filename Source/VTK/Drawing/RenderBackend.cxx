// SPDX-License-Identifier: BSD-3-Clause
#include "Drawing/RenderBackend.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/Timing.h"

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

bool RenderBackend::ForEachBatch(const BackendFrame& frame, BackendTimes& times,
  const std::function<void(std::size_t first, std::size_t count)>& decompose,
  const std::function<bool()>& draw)
{
  const std::size_t total = frame.pipeline->SortedCount();
  const std::size_t batch = std::max<std::size_t>(1, frame.batchSize);
  for (std::size_t first = 0; first < total; first += batch)
  {
    const auto start = Clock::now();
    decompose(first, batch);
    times.decompose += SecondsSince(start);
    ++times.batches;
    if (!draw())
    {
      return false;
    }
    const std::size_t done = std::min(total, first + batch);
    if (done < total && frame.afterBatch &&
      !frame.afterBatch(static_cast<double>(done) / static_cast<double>(total)))
    {
      times.stopped = true;
      break;
    }
  }
  return true;
}

} // namespace mtpt
