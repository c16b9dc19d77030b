// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMTPTUnstructuredGridVolumeRepresentation
 * @brief   ParaView's unstructured-grid volume representation, drawn by
 *          vtkMultiThreadedProjectedTetrahedraMapper.
 *
 * ParaView's volume representation for unstructured grids keeps a fixed list of mappers
 * ("Projected tetra", "Z sweep", "Bunyk ray cast", "Resample To Image") that a plugin cannot
 * extend. This subclass registers one more, under MapperName ("Multi-threaded projected
 * tetra"), and makes it the active one; everything else (input preparation, LOD, ordered
 * compositing in parallel, transfer functions, scalar selection) is the superclass's. The
 * plugin's server-manager XML offers it as its own representation type with the same label,
 * sharing the properties of the stock "Volume" representation, and adds the mapper's
 * settings, which this class forwards to the mapper.
 *
 * While the view moves, ParaView's own level of detail replaces a volume above the view's
 * LOD threshold by its outline or surface. With the mapper's cell level of detail on
 * (AutoAdjustCellFraction, the default) this representation keeps drawing the volume
 * instead: the mapper draws a fraction of the cells to keep the rate the view asks for.
 *
 * @sa vtkUnstructuredGridVolumeRepresentation vtkMultiThreadedProjectedTetrahedraMapper
 */
#ifndef vtkMTPTUnstructuredGridVolumeRepresentation_h
#define vtkMTPTUnstructuredGridVolumeRepresentation_h

#include "vtkNew.h"                      // for vtkNew
#include "vtkPlane.h"                    // for vtkPlane
#include "vtkRepresentationMTPTModule.h" // for export macro
#include "vtkUnstructuredGridVolumeRepresentation.h"

class vtkMultiThreadedProjectedTetrahedraMapper; // MTPT's own: not in VTK's ABI namespace

class VTKREPRESENTATIONMTPT_EXPORT vtkMTPTUnstructuredGridVolumeRepresentation
  : public vtkUnstructuredGridVolumeRepresentation
{
public:
  static vtkMTPTUnstructuredGridVolumeRepresentation* New();
  vtkTypeMacro(
    vtkMTPTUnstructuredGridVolumeRepresentation, vtkUnstructuredGridVolumeRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The name under which the mapper is registered (the value of SelectMapper).
  static const char* GetMapperName();

  ///@{
  /// Forwarded to vtkMultiThreadedProjectedTetrahedraMapper (see its setters for meaning).
  void SetNumberOfThreads(int threads);
  int GetNumberOfThreads();
  void SetOrderMethod(int method);
  int GetOrderMethod();
  void SetBackend(int backend);
  int GetBackend();
  void SetShadingMode(int mode);
  int GetShadingMode();
  /// The mapper's memory limit in MiB (SetMemoryLimit; 0: the memory available).
  void SetMemoryLimitMiB(int mebibytes);
  int GetMemoryLimitMiB();
  /// vtkMultiThreadedProjectedTetrahedraMapper's blend mode (0 to 4) and the average's range.
  void SetBlendMode(int mode);
  int GetBlendMode();
  void SetAverageIPScalarRange(double low, double high);
  /// Shading (Documentation/shading.md), forwarded to the volume's property: the stock
  /// unstructured-grid volume representation offers none of these.
  void SetShade(int shade);
  void SetAmbient(double ambient);
  void SetDiffuse(double diffuse);
  void SetSpecular(double specular);
  void SetSpecularPower(double power);
  void SetImageSampleDistance(double distance);
  double GetImageSampleDistance();
  void SetMinimumImageSampleDistance(double distance);
  double GetMinimumImageSampleDistance();
  void SetMaximumImageSampleDistance(double distance);
  double GetMaximumImageSampleDistance();
  void SetAutoAdjustSampleDistances(int adjust);
  int GetAutoAdjustSampleDistances();
  void SetAutoAdjustCellFraction(int adjust);
  int GetAutoAdjustCellFraction();
  void SetMinimumCellFraction(double fraction);
  double GetMinimumCellFraction();
  void SetCompositeWithOtherVolumes(int together);
  int GetCompositeWithOtherVolumes();
  ///@}

  ///@{
  /// One clipping plane on the mapper (vtkAbstractMapper::AddClippingPlane), in world
  /// coordinates, keeping the side the normal points to; off by default.
  void SetClippingPlane(int on);
  int GetClippingPlane();
  void SetClippingPlaneOrigin(double x, double y, double z);
  void SetClippingPlaneNormal(double x, double y, double z);
  ///@}

  /// As the superclass; a render keeps the volume while the view moves when the mapper's
  /// cell level of detail is on (see the class comment).
  int ProcessViewRequest(vtkInformationRequestKey* requestType, vtkInformation* inInfo,
    vtkInformation* outInfo) override;

  /// The mapper this representation draws with.
  vtkMultiThreadedProjectedTetrahedraMapper* GetMTPTMapper();

protected:
  vtkMTPTUnstructuredGridVolumeRepresentation();
  ~vtkMTPTUnstructuredGridVolumeRepresentation() override;

  vtkNew<vtkMultiThreadedProjectedTetrahedraMapper> MTPTMapper;
  vtkNew<vtkPlane> ClippingPlane;
  /// The Image Sample Distance property's value, given to the mapper again when automatic
  /// adjustment (which overwrites the mapper's) is turned off.
  double ImageSampleDistance = 1.0;

private:
  vtkMTPTUnstructuredGridVolumeRepresentation(
    const vtkMTPTUnstructuredGridVolumeRepresentation&) = delete;
  void operator=(const vtkMTPTUnstructuredGridVolumeRepresentation&) = delete;
};

#endif
