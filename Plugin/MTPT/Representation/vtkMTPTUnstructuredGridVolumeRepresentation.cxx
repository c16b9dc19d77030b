// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMTPTUnstructuredGridVolumeRepresentation.h"

#include "vtkMultiThreadedProjectedTetrahedraMapper.h"
#include "vtkObjectFactory.h"
#include "vtkPlaneCollection.h"
#include "vtkPVLODVolume.h"
#include "vtkPVView.h"
#include "vtkVolumeProperty.h"

vtkStandardNewMacro(vtkMTPTUnstructuredGridVolumeRepresentation);

//------------------------------------------------------------------------------
vtkMTPTUnstructuredGridVolumeRepresentation::vtkMTPTUnstructuredGridVolumeRepresentation()
{
  // The server-manager proxy's si_class then registers ParaView's own mappers beside it, and
  // the proxy's SelectMapper property (default: this name) keeps this one active.
  this->AddVolumeMapper(GetMapperName(), this->MTPTMapper);
  this->SetActiveVolumeMapper(GetMapperName());
}

//------------------------------------------------------------------------------
vtkMTPTUnstructuredGridVolumeRepresentation::~vtkMTPTUnstructuredGridVolumeRepresentation() =
  default;

//------------------------------------------------------------------------------
const char* vtkMTPTUnstructuredGridVolumeRepresentation::GetMapperName()
{
  return "Multi-threaded projected tetra";
}

//------------------------------------------------------------------------------
vtkMultiThreadedProjectedTetrahedraMapper*
vtkMTPTUnstructuredGridVolumeRepresentation::GetMTPTMapper()
{
  return this->MTPTMapper;
}

//------------------------------------------------------------------------------
// The mapper's setters call Modified() on a change, which is all a render needs: these are
// drawing settings, so the representation's data pipeline does not run again.
void vtkMTPTUnstructuredGridVolumeRepresentation::SetNumberOfThreads(int threads)
{
  this->MTPTMapper->SetNumberOfThreads(threads);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetNumberOfThreads()
{
  return this->MTPTMapper->GetNumberOfThreads();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetMemoryLimitMiB(int mebibytes)
{
  this->MTPTMapper->SetMemoryLimit(static_cast<vtkIdType>(mebibytes) << 20);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetMemoryLimitMiB()
{
  return static_cast<int>(this->MTPTMapper->GetMemoryLimit() >> 20);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetOrderMethod(int method)
{
  this->MTPTMapper->SetOrderMethod(method);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetOrderMethod()
{
  return this->MTPTMapper->GetOrderMethod();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetBackend(int backend)
{
  this->MTPTMapper->SetBackend(backend);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetBackend()
{
  return this->MTPTMapper->GetBackend();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetShadingMode(int mode)
{
  this->MTPTMapper->SetShadingMode(mode);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetShadingMode()
{
  return this->MTPTMapper->GetShadingMode();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetBlendMode(int mode)
{
  this->MTPTMapper->SetBlendMode(mode);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetBlendMode()
{
  return this->MTPTMapper->GetBlendMode();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetAverageIPScalarRange(double low, double high)
{
  this->MTPTMapper->SetAverageIPScalarRange(low, high);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetShade(int shade)
{
  this->Property->SetShade(shade);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetAmbient(double ambient)
{
  this->Property->SetAmbient(ambient);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetDiffuse(double diffuse)
{
  this->Property->SetDiffuse(diffuse);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetSpecular(double specular)
{
  this->Property->SetSpecular(specular);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetSpecularPower(double power)
{
  this->Property->SetSpecularPower(power);
}

// With automatic adjustment on, every render overwrites the mapper's distance (as in VTK's
// ray caster); the distance the property holds is kept here and given to the mapper again
// when the adjustment is turned off, so that the panel's value is the one drawn with.
void vtkMTPTUnstructuredGridVolumeRepresentation::SetImageSampleDistance(double distance)
{
  this->ImageSampleDistance = distance;
  this->MTPTMapper->SetImageSampleDistance(static_cast<float>(distance));
}

double vtkMTPTUnstructuredGridVolumeRepresentation::GetImageSampleDistance()
{
  return this->MTPTMapper->GetImageSampleDistance();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetMinimumImageSampleDistance(double distance)
{
  this->MTPTMapper->SetMinimumImageSampleDistance(static_cast<float>(distance));
}

double vtkMTPTUnstructuredGridVolumeRepresentation::GetMinimumImageSampleDistance()
{
  return this->MTPTMapper->GetMinimumImageSampleDistance();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetMaximumImageSampleDistance(double distance)
{
  this->MTPTMapper->SetMaximumImageSampleDistance(static_cast<float>(distance));
}

double vtkMTPTUnstructuredGridVolumeRepresentation::GetMaximumImageSampleDistance()
{
  return this->MTPTMapper->GetMaximumImageSampleDistance();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetAutoAdjustSampleDistances(int adjust)
{
  this->MTPTMapper->SetAutoAdjustSampleDistances(adjust);
  if (!adjust)
  {
    this->MTPTMapper->SetImageSampleDistance(static_cast<float>(this->ImageSampleDistance));
  }
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetAutoAdjustSampleDistances()
{
  return this->MTPTMapper->GetAutoAdjustSampleDistances();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetAutoAdjustCellFraction(int adjust)
{
  this->MTPTMapper->SetAutoAdjustCellFraction(adjust);
  if (!adjust)
  {
    this->MTPTMapper->SetCellFraction(1.0f); // every cell, as before the adjustment
  }
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetAutoAdjustCellFraction()
{
  return this->MTPTMapper->GetAutoAdjustCellFraction();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetCompositeWithOtherVolumes(int together)
{
  this->MTPTMapper->SetCompositeWithOtherVolumes(together != 0);
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetCompositeWithOtherVolumes()
{
  return this->MTPTMapper->GetCompositeWithOtherVolumes() ? 1 : 0;
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetMinimumCellFraction(double fraction)
{
  this->MTPTMapper->SetMinimumCellFraction(static_cast<float>(fraction));
}

double vtkMTPTUnstructuredGridVolumeRepresentation::GetMinimumCellFraction()
{
  return this->MTPTMapper->GetMinimumCellFraction();
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetClippingPlane(int on)
{
  vtkPlaneCollection* planes = this->MTPTMapper->GetClippingPlanes();
  const bool present = planes && planes->IsItemPresent(this->ClippingPlane);
  if (on && !present)
  {
    this->MTPTMapper->AddClippingPlane(this->ClippingPlane);
  }
  else if (!on && present)
  {
    this->MTPTMapper->RemoveClippingPlane(this->ClippingPlane);
  }
}

int vtkMTPTUnstructuredGridVolumeRepresentation::GetClippingPlane()
{
  vtkPlaneCollection* planes = this->MTPTMapper->GetClippingPlanes();
  return planes && planes->IsItemPresent(this->ClippingPlane) ? 1 : 0;
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetClippingPlaneOrigin(
  double x, double y, double z)
{
  this->ClippingPlane->SetOrigin(x, y, z);
}

void vtkMTPTUnstructuredGridVolumeRepresentation::SetClippingPlaneNormal(
  double x, double y, double z)
{
  this->ClippingPlane->SetNormal(x, y, z);
}

//------------------------------------------------------------------------------
int vtkMTPTUnstructuredGridVolumeRepresentation::ProcessViewRequest(
  vtkInformationRequestKey* requestType, vtkInformation* inInfo, vtkInformation* outInfo)
{
  const int result = this->Superclass::ProcessViewRequest(requestType, inInfo, outInfo);
  if (requestType == vtkPVView::REQUEST_RENDER() && this->GetActor() &&
    this->GetActiveVolumeMapper() == this->MTPTMapper.GetPointer() &&
    this->MTPTMapper->GetAutoAdjustCellFraction())
  {
    // The superclass turns ParaView's level of detail (the outline or surface) on for an
    // interactive render above the LOD threshold; the mapper's own keeps the volume.
    this->GetActor()->SetEnableLOD(0);
  }
  return result;
}

//------------------------------------------------------------------------------
void vtkMTPTUnstructuredGridVolumeRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "MTPTMapper:\n";
  this->MTPTMapper->PrintSelf(os, indent.GetNextIndent());
}
