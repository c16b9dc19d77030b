// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OpenGLHeader.h
 * @brief Private glue: OpenGL's functions and constants through the loader VTK uses: GLEW
 * up to VTK 9.3 (vtk_glew.h), glad from VTK 9.4 on (vtk_glad.h). Both come with
 * VTK::RenderingOpenGL2, which the module depends on.
 */
#ifndef mtpt_OpenGLHeader_h
#define mtpt_OpenGLHeader_h

#if __has_include("vtk_glad.h")
#include "vtk_glad.h" // IWYU pragma: export
#else
#include "vtk_glew.h" // IWYU pragma: export
#endif

#endif
