// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file VolumeInput.h
 * @brief Private glue: what a frame reads from a VTK scene, written once for the mapper and
 * the reference renderer so that both see the same scalars, camera and opacity scale.
 */
#ifndef mtpt_VolumeInput_h
#define mtpt_VolumeInput_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/Lighting.h"
#include "mtpt/MeshView.h"
#include "mtpt/Shading.h"

#include <string>

VTK_ABI_NAMESPACE_BEGIN
class vtkAbstractMapper;
class vtkAbstractVolumeMapper;
class vtkDataArray;
class vtkRenderer;
class vtkUnstructuredGridBase;
class vtkVolume;
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

/// ScalarSelection::component of dependent components: every component is used.
constexpr int AllComponents = -2;

/// The scalars a volume colours by, chosen by VTK's rules (see SelectScalars).
struct ScalarSelection
{
  vtkDataArray* array = nullptr; ///< null: nothing usable (Error says why)
  bool cellData = false;         ///< one value per cell rather than per point
  /// The component used; -1: the magnitude; AllComponents: dependent components (2 or 4).
  int component = -1;
  std::string error; ///< why no array was selected; empty when one was
  /// `error` is a warning, as VTK's PT gives it (dependent components of an unsupported
  /// count): nothing is drawn, but nothing is wrong with the scene either.
  bool errorIsWarning = false;
  std::string warning; ///< a request that could not be honoured as made
};

/// Values per tuple of a selection: 1, or the array's components with dependent components.
int ChannelsOf(const ScalarSelection& selection);

/**
 * The scalars of `input` that `mapper` (null: VTK's defaults) selects with its scalar mode
 * and array selection (point or cell data, by name or id), as every VTK mapper selects
 * them, and the component to use: the colour transfer function's vector component in
 * COMPONENT vector mode, component 0 for a gray transfer function, otherwise the magnitude
 * (single-component arrays: the value). A component the array does not have is replaced
 * by the nearest one with a warning. No array, or one shorter than the points or cells it
 * should cover, is an error naming the selection (a misspelt array name is the usual
 * cause).
 *
 * Dependent components (the property's IndependentComponents off), as VTK's PT maps them:
 * two components are a colour scalar and an opacity scalar, four are the colour and opacity
 * themselves (component = AllComponents); any other count is VTK's warning
 * (errorIsWarning) and nothing is drawn.
 */
ScalarSelection SelectScalars(
  vtkUnstructuredGridBase* input, vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property);

/**
 * The matrices of a frame of `volume` in `renderer`, as the mapper draws it: model-view =
 * the active camera's view transform times the volume's matrix (the view transform alone
 * for a null `volume`); projection = the camera's for the renderer's tiled aspect ratio
 * with OpenGL's depth range.
 */
void ViewMatrices(
  vtkRenderer* renderer, vtkVolume* volume, Matrix4& modelView, Matrix4& projection);

/**
 * The mapper's clipping planes (vtkAbstractMapper::ClippingPlanes, world coordinates: each
 * vtkPlane keeps the side its normal points to) in the eye coordinates of `renderer`'s
 * active camera, the first ClipPlanes::Max of them; `ignored` receives how many more there
 * are.
 */
ClipPlanes EyeClipPlanes(vtkAbstractMapper* mapper, vtkRenderer* renderer, int& ignored);

/**
 * The lighting of `property`'s component 0 by `renderer`'s lights that are switched on, in
 * the eye coordinates of its active camera, as VTK's GPU ray caster reads them: colours times
 * intensity, directions from position to focal point, the renderer's two-sided lighting,
 * and its "default lighting" (Lighting::headlight) for a single headlight of intensity 1.
 * The first Lighting::MaxLights lights; `ignored` receives how many more there are.
 */
Lighting VolumeLighting(vtkRenderer* renderer, vtkVolumeProperty* property, int& ignored);

/**
 * The property's ScalarOpacityUnitDistance, or 1 when it is not positive (then `warning`
 * says so; VTK's own mappers divide by it unchecked).
 */
double UnitDistance(vtkVolumeProperty* property, std::string* warning = nullptr);

} // namespace mtpt

#endif
