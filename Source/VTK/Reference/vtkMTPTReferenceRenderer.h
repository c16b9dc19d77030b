// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMTPTReferenceRenderer
 * @brief   The exact emission-absorption image of an unstructured-grid volume, to measure
 *          any volume mapper's error against.
 *
 * Given a vtkRenderer (its active camera, size and background) and a vtkVolume (its property
 * and matrix), computes on the CPU, in double precision and without OpenGL, the image the
 * volume rendering integral gives for every pixel: the scalar linear inside each tetrahedron
 * (point scalars; cell scalars constant per cell), colour and opacity from the property's
 * piecewise-linear transfer functions, extinction = opacity / ScalarOpacityUnitDistance,
 * composited front to back over the renderer's background. See mtpt/ReferenceRenderer.h for
 * the exactness of the integral (about 1e-12 per pixel) and the pixel conventions (rays
 * through pixel centres moved by a few millionths of a pixel).
 *
 * Dependent components (the property's IndependentComponents off) are mapped as the mapper
 * and VTK's PT map them: two components are a colour scalar and an opacity scalar, each
 * through its transfer function and each linear inside a cell; four are the colour and the
 * attenuation themselves (unsigned chars divided by 255), linear inside a cell and clamped
 * to [0, 1]. Both are integrated exactly along each segment (mtpt::ScalarMapping).
 *
 * Inputs are read as vtkMultiThreadedProjectedTetrahedraMapper reads them: the grid (the
 * volume mapper's input unless one is given; the unstructured blocks of a composite input
 * appended into one grid) is split into tetrahedra as the mapper splits
 * it when it holds other 3D cells (cells of lower dimension are left out); the scalars are
 * selected by the volume mapper's scalar mode and array selection (defaults without a volume
 * mapper), the component or magnitude as the colour transfer function's vector mode says;
 * the camera matrices are those the mapper uses (model-view times the volume's matrix, and
 * the projection for the renderer's tiled aspect ratio with depth range [-1, 1]).
 *
 * Transfer functions: converted node for node (exact) when every node has midpoint 0.5 and
 * sharpness 0 (VTK's defaults), the colour function interpolates in RGB with a linear scale,
 * clamping is on and no scalar is repeated. Otherwise both functions are sampled by VTK
 * itself at TransferFunctionSamples points (default 8192) over the union of their node
 * range and the data range, and those samples are used as nodes: exact at the samples,
 * linear between them. ExactTransferFunctions() tells which happened.
 *
 * Only the volume is integrated: other props, gradient or textured backgrounds and the
 * depth of opaque geometry are ignored, and the image is linear RGB (no sRGB conversion,
 * as VTK's windows by default).
 *
 * The static helpers read a rendered window's pixels back as doubles and compare images
 * (RMSE, PSNR and largest channel difference over linear RGB in [0, 1]).
 *
 * @sa vtkMultiThreadedProjectedTetrahedraMapper
 */
#ifndef vtkMTPTReferenceRenderer_h
#define vtkMTPTReferenceRenderer_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkObject.h"
#include "vtkSmartPointer.h"        // for the appended blocks
#include "vtkRenderingMTPTModule.h" // for export macro

VTK_ABI_NAMESPACE_BEGIN
class vtkDoubleArray;
class vtkRenderer;
class vtkUnstructuredGrid;
class vtkUnstructuredGridBase;
class vtkVolume;
class vtkVolumeCollection;
VTK_ABI_NAMESPACE_END

namespace mtpt
{
class MeshAdapter;
struct ReferenceSettings;
struct ScalarsView;
}

class VTKRENDERINGMTPT_EXPORT vtkMTPTReferenceRenderer : public vtkObject
{
public:
  static vtkMTPTReferenceRenderer* New();
  vtkTypeMacro(vtkMTPTReferenceRenderer, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// OpenMP threads for the integration (0, the default: every core). The image is
  /// bit-identical for any count.
  vtkSetClampMacro(NumberOfThreads, int, 0, VTK_INT_MAX);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  ///@{
  /// Samples of each transfer function when they cannot be converted exactly (>= 2).
  vtkSetClampMacro(TransferFunctionSamples, int, 2, VTK_INT_MAX);
  vtkGetMacro(TransferFunctionSamples, int);
  ///@}

  ///@{
  /**
   * Average-intensity blending's scalar range where the volume's mapper has none of its own:
   * vtkUnstructuredGridVolumeMapper declares none, so copy
   * vtkMultiThreadedProjectedTetrahedraMapper's AverageIPScalarRange here; a vtkVolumeMapper's
   * own is used. The blend mode itself is the mapper's.
   */
  vtkSetVector2Macro(AverageIPScalarRange, double);
  vtkGetVectorMacro(AverageIPScalarRange, double, 2);
  ///@}

  /**
   * Computes the reference image of `volume` as `renderer` shows it. `input` is the grid to
   * integrate; null takes the input of the volume's mapper. Returns false, with a
   * vtkErrorMacro saying why, when something is missing or unusable (no renderer, camera,
   * property, input, 3D cells, scalars; a renderer in no window or an empty viewport).
   */
  bool Render(vtkRenderer* renderer, vtkVolume* volume, vtkUnstructuredGridBase* input = nullptr);

  /**
   * Computes the reference image of several volumes as `renderer` shows them (the visible
   * ones of `volumes`, for instance renderer->GetVolumes()), integrated together along each
   * ray in depth order: each cell with its own volume's matrix, scalars (selected by the
   * volume's mapper), colour and opacity functions and unit distance, as the mapper draws
   * volumes together (CompositeWithOtherVolumes). Composite blending, unlit, independent
   * components, the first volume's clipping planes; anything else, and what Render refuses,
   * returns false with a vtkErrorMacro.
   */
  bool RenderVolumes(vtkRenderer* renderer, vtkVolumeCollection* volumes);

  /// The last image: width * height tuples of 3 doubles (linear RGB), row 0 at the bottom.
  vtkDoubleArray* GetImage();

  /// Width and height of the last image.
  vtkGetVector2Macro(Size, int);

  /// Whether the last Render used the transfer-function nodes exactly (false: sampled).
  vtkGetMacro(ExactTransferFunctions, bool);

  /// Seconds the last Render took, and the ray-cell segments it integrated.
  vtkGetMacro(RenderSeconds, double);
  vtkGetMacro(NumberOfSegments, vtkIdType);

  /**
   * Reads `renderer`'s viewport of its window into `rgb` (3 doubles per pixel in [0, 1],
   * row 0 at the bottom), from the back buffer (`front` = 0, what an offscreen window
   * rendered last) or the front buffer. Returns false if there is nothing to read.
   */
  static bool ReadPixels(vtkRenderer* renderer, vtkDoubleArray* rgb, int front = 0);

  /**
   * Compares two RGB images of equal size: result = { RMSE, PSNR in dB (peak 1, infinite for
   * equal images), largest channel difference }. Returns false for mismatched arrays.
   */
  static bool CompareImages(vtkDoubleArray* a, vtkDoubleArray* b, double result[3]);

  /// ReadPixels(renderer) compared with the last image (see CompareImages).
  bool CompareWithRenderer(vtkRenderer* renderer, double result[3], int front = 0);

protected:
  vtkMTPTReferenceRenderer();
  ~vtkMTPTReferenceRenderer() override;

  int NumberOfThreads = 0;
  int TransferFunctionSamples = 8192;
  double AverageIPScalarRange[2] = { VTK_DOUBLE_MIN, VTK_DOUBLE_MAX };
  int Size[2] = { 0, 0 };
  bool ExactTransferFunctions = false;
  double RenderSeconds = 0;
  vtkIdType NumberOfSegments = 0;
  vtkDoubleArray* Image;
  vtkSmartPointer<vtkUnstructuredGrid> Appended; ///< the blocks of a composite input

private:
  vtkMTPTReferenceRenderer(const vtkMTPTReferenceRenderer&) = delete;
  /// Checks what Render needs, takes the volume mapper's input when `input` is null, and
  /// sets the viewport's `size`; false with an error message when something is missing.
  bool CheckScene(
    vtkRenderer* renderer, vtkVolume* volume, vtkUnstructuredGridBase*& input, int size[2]);
  void operator=(const vtkMTPTReferenceRenderer&) = delete;
  /// Integrates the mesh of `adapter` with `settings` into the image of `size`.
  bool Integrate(const mtpt::MeshAdapter& adapter, const mtpt::ScalarsView& view,
    const mtpt::ReferenceSettings& settings, const int size[2]);
};

#endif
