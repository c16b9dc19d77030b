// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file vtkMTPTVTKCompatibility.h
 * @brief What MTPT needs to build against every VTK from 9.1 to the current release.
 *
 * - VTK_ABI_NAMESPACE_BEGIN / END: VTK 9.3 and newer can be built with its classes in an
 *   ABI namespace, and a forward declaration of a VTK class outside it names another class.
 *   MTPT wraps its forward declarations of VTK classes in these macros; before 9.3 they are
 *   empty.
 * - VTK_VERSION_NUMBER and VTK_VERSION_CHECK, for the few API differences the sources
 *   handle by version (see Documentation/vtk-versions.md).
 */
#ifndef vtkMTPTVTKCompatibility_h
#define vtkMTPTVTKCompatibility_h

#include "vtkVersionMacros.h" // VTK_VERSION_NUMBER, VTK_VERSION_CHECK

#if VTK_VERSION_NUMBER >= VTK_VERSION_CHECK(9, 3, 0)
#include "vtkABINamespace.h"
#endif
#ifndef VTK_ABI_NAMESPACE_BEGIN
#define VTK_ABI_NAMESPACE_BEGIN
#define VTK_ABI_NAMESPACE_END
#endif

#endif
