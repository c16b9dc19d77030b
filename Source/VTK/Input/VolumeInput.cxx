// SPDX-License-Identifier: BSD-3-Clause
#include "Input/VolumeInput.h"

#include "vtkAbstractVolumeMapper.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkLight.h"
#include "vtkLightCollection.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkPlane.h"
#include "vtkPlaneCollection.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <sstream>

namespace mtpt
{

namespace
{

/// " (selected: the point array named 'x', which the input does not have)" for field-data
/// selections; empty for the default and the active-scalars modes.
std::string DescribeSelection(int scalarMode, int accessMode, int arrayId, const char* name)
{
  const bool pointField = scalarMode == VTK_SCALAR_MODE_USE_POINT_FIELD_DATA;
  if (!pointField && scalarMode != VTK_SCALAR_MODE_USE_CELL_FIELD_DATA)
  {
    return {};
  }
  std::ostringstream selection;
  selection << " (selected: the " << (pointField ? "point" : "cell") << " array ";
  if (accessMode == VTK_GET_ARRAY_BY_NAME)
  {
    selection << "named '" << (name ? name : "") << "'";
  }
  else
  {
    selection << "number " << arrayId;
  }
  selection << ", which the input does not have)";
  return selection.str();
}

/// The component the property asks for (-1: magnitude), checked against the array.
void ChooseComponent(vtkVolumeProperty* property, ScalarSelection& selected)
{
  const int components = selected.array->GetNumberOfComponents();
  bool byComponent = false;
  int wanted = 0;
  if (property && property->GetColorChannels(0) == 1)
  {
    byComponent = true; // a gray transfer function maps the first component
  }
  else if (property &&
    property->GetRGBTransferFunction(0)->GetVectorMode() == vtkScalarsToColors::COMPONENT)
  {
    byComponent = true;
    wanted = property->GetRGBTransferFunction(0)->GetVectorComponent();
  }
  if (components == 1 || !byComponent)
  {
    selected.component = components == 1 ? 0 : -1;
    return;
  }
  if (wanted < 0 || wanted >= components)
  {
    const int used = wanted < 0 ? 0 : components - 1;
    std::ostringstream warning;
    const char* name = selected.array->GetName();
    warning << "the colour transfer function selects component " << wanted << " of the array '"
            << (name ? name : "") << "', which has components 0 to " << components - 1
            << "; using component " << used;
    selected.warning = warning.str();
    wanted = used;
  }
  selected.component = wanted;
}

} // namespace

ScalarSelection SelectScalars(
  vtkUnstructuredGridBase* input, vtkAbstractVolumeMapper* mapper, vtkVolumeProperty* property)
{
  const int mode = mapper ? mapper->GetScalarMode() : VTK_SCALAR_MODE_DEFAULT;
  const int access = mapper ? mapper->GetArrayAccessMode() : VTK_GET_ARRAY_BY_ID;
  const int id = mapper ? mapper->GetArrayId() : -1;
  const char* name = mapper ? mapper->GetArrayName() : nullptr;
  ScalarSelection selected;
  int cellFlag = 0;
  selected.array = vtkAbstractMapper::GetScalars(input, mode, access, id, name, cellFlag);
  if (!selected.array)
  {
    selected.error = "the input has no scalars to map" + DescribeSelection(mode, access, id, name) +
      ": give it point or cell scalars, or select an existing array with "
      "SelectScalarArray() and SetScalarMode()";
    return selected;
  }
  selected.cellData = cellFlag != 0;
  const vtkIdType needed = cellFlag ? input->GetNumberOfCells() : input->GetNumberOfPoints();
  if (selected.array->GetNumberOfTuples() < needed)
  {
    std::ostringstream error;
    const char* arrayName = selected.array->GetName();
    error << "the scalar array '" << (arrayName ? arrayName : "") << "' has "
          << selected.array->GetNumberOfTuples() << " tuples for " << needed
          << (cellFlag ? " cells" : " points");
    selected.error = error.str();
    selected.array = nullptr;
    return selected;
  }
  if (property && !property->GetIndependentComponents())
  {
    const int components = selected.array->GetNumberOfComponents();
    if (components == 2 || components == 4)
    {
      selected.component = AllComponents;
      return selected;
    }
    std::ostringstream warning;
    const char* arrayName = selected.array->GetName();
    warning << "dependent components (IndependentComponents off) map 2 components (colour "
               "scalar, opacity scalar) or 4 (RGBA); the scalar array '"
            << (arrayName ? arrayName : "") << "' has " << components
            << ": nothing is drawn (turn IndependentComponents on to map one component)";
    selected.error = warning.str();
    selected.errorIsWarning = true;
    selected.array = nullptr;
    return selected;
  }
  ChooseComponent(property, selected);
  return selected;
}

int ChannelsOf(const ScalarSelection& selection)
{
  return selection.component == AllComponents && selection.array
    ? selection.array->GetNumberOfComponents()
    : 1;
}

void ViewMatrices(vtkRenderer* renderer, vtkVolume* volume, Matrix4& modelView, Matrix4& projection)
{
  auto copy = [](vtkMatrix4x4* m, Matrix4& out)
  {
    for (int r = 0; r < 4; ++r)
    {
      for (int c = 0; c < 4; ++c)
      {
        out[4 * r + c] = m->GetElement(r, c);
      }
    }
  };
  vtkCamera* camera = renderer->GetActiveCamera();
  if (volume)
  {
    vtkNew<vtkMatrix4x4> eye;
    vtkMatrix4x4::Multiply4x4(camera->GetModelViewTransformMatrix(), volume->GetMatrix(), eye);
    copy(eye, modelView);
  }
  else
  {
    copy(camera->GetModelViewTransformMatrix(), modelView);
  }
  copy(
    camera->GetProjectionTransformMatrix(renderer->GetTiledAspectRatio(), -1.0, 1.0), projection);
}

ClipPlanes EyeClipPlanes(vtkAbstractMapper* mapper, vtkRenderer* renderer, int& ignored)
{
  ClipPlanes planes;
  ignored = 0;
  vtkPlaneCollection* collection = mapper->GetClippingPlanes();
  if (!collection || collection->GetNumberOfItems() == 0)
  {
    return planes;
  }
  // A world plane (n, -n . o) as a row vector times the inverse of the view matrix.
  vtkNew<vtkMatrix4x4> toWorld;
  vtkMatrix4x4::Invert(renderer->GetActiveCamera()->GetModelViewTransformMatrix(), toWorld);
  vtkCollectionSimpleIterator it;
  collection->InitTraversal(it);
  while (vtkPlane* plane = collection->GetNextPlane(it))
  {
    if (planes.count == ClipPlanes::Max)
    {
      ++ignored;
      continue;
    }
    double n[3], o[3];
    plane->GetNormal(n);
    plane->GetOrigin(o);
    const double world[4] = { n[0], n[1], n[2], -(n[0] * o[0] + n[1] * o[1] + n[2] * o[2]) };
    double* eye = planes.plane[planes.count++];
    for (int c = 0; c < 4; ++c)
    {
      eye[c] = 0.0;
      for (int r = 0; r < 4; ++r)
      {
        eye[c] += world[r] * toWorld->GetElement(r, c);
      }
    }
  }
  return planes;
}

double UnitDistance(vtkVolumeProperty* property, std::string* warning)
{
  const double unitDistance = property->GetScalarOpacityUnitDistance(0);
  if (unitDistance > 0)
  {
    return unitDistance;
  }
  if (warning)
  {
    std::ostringstream message;
    message << "the volume property's ScalarOpacityUnitDistance is " << unitDistance
            << "; it must be positive, using 1";
    *warning = message.str();
  }
  return 1.0;
}

Lighting VolumeLighting(vtkRenderer* renderer, vtkVolumeProperty* property, int& ignored)
{
  Lighting lighting;
  lighting.ambient = property->GetAmbient(0);
  lighting.diffuse = property->GetDiffuse(0);
  lighting.specular = property->GetSpecular(0);
  lighting.specularPower = property->GetSpecularPower(0);
  lighting.twoSided = renderer->GetTwoSidedLighting() != 0;
  lighting.count = 0;
  ignored = 0;
  vtkMatrix4x4* view = renderer->GetActiveCamera()->GetModelViewTransformMatrix();
  vtkLightCollection* lights = renderer->GetLights();
  vtkCollectionSimpleIterator it;
  lights->InitTraversal(it);
  bool headlightOnly = true;
  int on = 0;
  while (vtkLight* light = lights->GetNextLight(it))
  {
    if (!(light->GetSwitch() > 0))
    {
      continue;
    }
    const double intensity = light->GetIntensity();
    headlightOnly = headlightOnly && on == 0 && intensity == 1.0 && light->LightTypeIsHeadlight();
    ++on;
    if (lighting.count == Lighting::MaxLights)
    {
      ++ignored;
      continue;
    }
    Light& l = lighting.lights[lighting.count++];
    double position[4], focal[4], eyePosition[4], eyeFocal[4];
    light->GetTransformedPosition(position);
    light->GetTransformedFocalPoint(focal);
    position[3] = focal[3] = 1;
    view->MultiplyPoint(position, eyePosition);
    view->MultiplyPoint(focal, eyeFocal);
    for (int k = 0; k < 3; ++k)
    {
      l.ambient[k] = light->GetAmbientColor()[k] * intensity;
      l.diffuse[k] = light->GetDiffuseColor()[k] * intensity;
      l.specular[k] = light->GetSpecularColor()[k] * intensity;
      l.position[k] = eyePosition[k];
      l.direction[k] = eyeFocal[k] - eyePosition[k];
      l.attenuation[k] = light->GetAttenuationValues()[k];
    }
    if (!Normalize3(l.direction)) // a light at its focal point: down the view axis
    {
      l.direction[0] = l.direction[1] = 0;
      l.direction[2] = -1;
    }
    l.positional = light->GetPositional() != 0;
    l.coneAngle = light->GetConeAngle();
    l.exponent = light->GetExponent();
  }
  lighting.headlight = on == 1 && headlightOnly;
  return lighting;
}

} // namespace mtpt
