// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMTPTReferenceRenderer.h"

#include "vtkMTPTMeshAdapter.h"
#include "vtkMTPTTetrahedralizer.h"

#include "mtpt/ReferenceRenderer.h"

#include "vtkAbstractVolumeMapper.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkUnstructuredGridVolumeMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

vtkStandardNewMacro(vtkMTPTReferenceRenderer);

namespace
{

/// True when the piecewise function is exactly the polyline through its nodes, clamped.
bool IsPolyline(vtkPiecewiseFunction* f)
{
  if (!f->GetClamping())
  {
    return false;
  }
  double previous = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[4];
    f->GetNodeValue(i, node);
    if (node[2] != 0.5 || node[3] != 0.0 || !(node[0] > previous))
    {
      return false;
    }
    previous = node[0];
  }
  return true;
}

/// True when the colour function is exactly the RGB polyline through its nodes, clamped.
bool IsPolyline(vtkColorTransferFunction* f)
{
  if (!f->GetClamping() || f->GetColorSpace() != VTK_CTF_RGB || f->GetScale() != VTK_CTF_LINEAR)
  {
    return false;
  }
  double previous = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[6];
    f->GetNodeValue(i, node);
    if (node[4] != 0.5 || node[5] != 0.0 || !(node[0] > previous))
    {
      return false;
    }
    previous = node[0];
  }
  return true;
}

void NodeRange(vtkPiecewiseFunction* f, double range[2])
{
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[4];
    f->GetNodeValue(i, node);
    range[0] = std::min(range[0], node[0]);
    range[1] = std::max(range[1], node[0]);
  }
}

void NodeRange(vtkColorTransferFunction* f, double range[2])
{
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[6];
    f->GetNodeValue(i, node);
    range[0] = std::min(range[0], node[0]);
    range[1] = std::max(range[1], node[0]);
  }
}

} // namespace

vtkMTPTReferenceRenderer::vtkMTPTReferenceRenderer()
  : Image(vtkDoubleArray::New())
{
  this->Image->SetNumberOfComponents(3);
  this->Image->SetName("ReferenceRGB");
}

vtkMTPTReferenceRenderer::~vtkMTPTReferenceRenderer()
{
  this->Image->Delete();
}

vtkDoubleArray* vtkMTPTReferenceRenderer::GetImage()
{
  return this->Image;
}

bool vtkMTPTReferenceRenderer::Render(
  vtkRenderer* renderer, vtkVolume* volume, vtkUnstructuredGridBase* input)
{
  this->Image->SetNumberOfTuples(0);
  this->Size[0] = this->Size[1] = 0;
  this->RenderSeconds = 0;
  this->NumberOfSegments = 0;
  if (!renderer || !renderer->GetActiveCamera())
  {
    vtkErrorMacro(<< "no renderer or no active camera");
    return false;
  }
  if (!volume || !volume->GetProperty())
  {
    vtkErrorMacro(<< "no volume or no volume property");
    return false;
  }
  auto* volumeMapper = vtkAbstractVolumeMapper::SafeDownCast(volume->GetMapper());
  if (!input)
  {
    auto* gridMapper = vtkUnstructuredGridVolumeMapper::SafeDownCast(volumeMapper);
    input = gridMapper ? gridMapper->GetInput() : nullptr;
  }
  if (!input || input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "no input grid: give one, or a volume whose mapper is a "
                     "vtkUnstructuredGridVolumeMapper with an input that has cells");
    return false;
  }
  if (!renderer->GetRenderWindow())
  {
    vtkErrorMacro(<< "the renderer is in no render window: its viewport has no size");
    return false;
  }
  int width = 0, height = 0, x0 = 0, y0 = 0;
  renderer->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width <= 0 || height <= 0)
  {
    vtkErrorMacro(<< "the renderer's viewport is empty (" << width << " x " << height
                  << "): add it to a render window with a size");
    return false;
  }

  // Mesh and scalars exactly as the mapper reads them: other cell types split into
  // tetrahedra the same way, then the same views.
  mtpt::vtkMTPTTetrahedralizer tetrahedralizer;
  input = tetrahedralizer.Update(input);
  if (input->GetNumberOfCells() == 0)
  {
    vtkErrorMacro(<< "the input has no 3D cells to integrate");
    return false;
  }
  mtpt::vtkMTPTMeshAdapter adapter;
  if (!adapter.Update(input))
  {
    vtkErrorMacro(<< "cannot integrate the input: " << adapter.Error());
    return false;
  }
  int cellFlag = 0;
  vtkDataArray* scalars = volumeMapper
    ? vtkAbstractMapper::GetScalars(input, volumeMapper->GetScalarMode(),
        volumeMapper->GetArrayAccessMode(), volumeMapper->GetArrayId(),
        volumeMapper->GetArrayName(), cellFlag)
    : vtkAbstractMapper::GetScalars(
        input, VTK_SCALAR_MODE_DEFAULT, VTK_GET_ARRAY_BY_ID, -1, nullptr, cellFlag);
  if (!scalars)
  {
    vtkErrorMacro(<< "the input has no scalars to integrate (point or cell scalars, or the "
                     "array the volume mapper selects)");
    return false;
  }
  const vtkIdType needed = cellFlag ? input->GetNumberOfCells() : input->GetNumberOfPoints();
  if (scalars->GetNumberOfTuples() < needed)
  {
    vtkErrorMacro(<< "the scalar array has " << scalars->GetNumberOfTuples() << " tuples for "
                  << needed << (cellFlag ? " cells" : " points"));
    return false;
  }
  vtkVolumeProperty* property = volume->GetProperty();
  const bool gray = property->GetColorChannels(0) == 1;
  int component = -1; // magnitude
  if (gray)
  {
    component = 0;
  }
  else if (property->GetRGBTransferFunction(0)->GetVectorMode() == vtkScalarsToColors::COMPONENT)
  {
    component = property->GetRGBTransferFunction(0)->GetVectorComponent();
  }
  double dataRange[2];
  vtkIdType nonFinite = 0;
  const float* values = adapter.Scalars(scalars, component, dataRange, nonFinite);

  // Transfer functions: nodes when exact, VTK's own samples otherwise.
  mtpt::ReferenceSettings settings;
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  vtkPiecewiseFunction* grayFunction = gray ? property->GetGrayTransferFunction(0) : nullptr;
  vtkColorTransferFunction* rgbFunction = gray ? nullptr : property->GetRGBTransferFunction(0);
  this->ExactTransferFunctions =
    IsPolyline(opacity) && (gray ? IsPolyline(grayFunction) : IsPolyline(rgbFunction));
  if (this->ExactTransferFunctions)
  {
    for (int i = 0; i < opacity->GetSize(); ++i)
    {
      double node[4];
      opacity->GetNodeValue(i, node);
      settings.opacity.push_back({ node[0], node[1] });
    }
    if (gray)
    {
      for (int i = 0; i < grayFunction->GetSize(); ++i)
      {
        double node[4];
        grayFunction->GetNodeValue(i, node);
        settings.color.push_back({ node[0], node[1], node[1], node[1] });
      }
    }
    else
    {
      for (int i = 0; i < rgbFunction->GetSize(); ++i)
      {
        double node[6];
        rgbFunction->GetNodeValue(i, node);
        settings.color.push_back({ node[0], node[1], node[2], node[3] });
      }
    }
  }
  else
  {
    double range[2] = { dataRange[0], dataRange[1] };
    NodeRange(opacity, range);
    if (gray)
    {
      NodeRange(grayFunction, range);
    }
    else
    {
      NodeRange(rgbFunction, range);
    }
    if (!(range[1] > range[0]))
    {
      range[1] = range[0] + 1.0;
    }
    const int n = this->TransferFunctionSamples;
    std::vector<double> alpha(n), colour(3 * static_cast<std::size_t>(n));
    opacity->GetTable(range[0], range[1], n, alpha.data());
    if (gray)
    {
      grayFunction->GetTable(range[0], range[1], n, colour.data());
      for (int i = n - 1; i >= 0; --i)
      {
        colour[3 * i] = colour[3 * i + 1] = colour[3 * i + 2] = colour[i];
      }
    }
    else
    {
      rgbFunction->GetTable(range[0], range[1], n, colour.data());
    }
    for (int i = 0; i < n; ++i)
    {
      const double s = range[0] + (range[1] - range[0]) * i / (n - 1);
      settings.opacity.push_back({ s, alpha[i] });
      settings.color.push_back({ s, colour[3 * i], colour[3 * i + 1], colour[3 * i + 2] });
    }
  }

  // The mapper's camera: eye = view * volume matrix; projection for the tiled aspect with
  // the OpenGL depth range (vtkMultiThreadedProjectedTetrahedraMapper::Render).
  mtpt::ViewMatrices(renderer, volume, settings.modelView, settings.projection);
  settings.width = width;
  settings.height = height;
  const double unitDistance = property->GetScalarOpacityUnitDistance(0);
  settings.unitDistance = unitDistance > 0 ? unitDistance : 1.0;
  renderer->GetBackground(settings.background);

  const mtpt::ScalarsView view{ values,
    cellFlag ? mtpt::ScalarsView::Association::Cells : mtpt::ScalarsView::Association::Points };
  std::vector<double> rgb;
  std::string error;
  mtpt::ReferenceStats stats;
  if (!mtpt::RenderReference(adapter.Points(), adapter.Cells(), view, settings, rgb,
        this->NumberOfThreads, &error, &stats))
  {
    vtkErrorMacro(<< "cannot compute the reference image: " << error);
    return false;
  }
  this->Image->SetNumberOfComponents(3);
  this->Image->SetNumberOfTuples(static_cast<vtkIdType>(width) * height);
  std::copy(rgb.begin(), rgb.end(), this->Image->GetPointer(0));
  this->Image->Modified();
  this->Size[0] = width;
  this->Size[1] = height;
  this->RenderSeconds = stats.seconds;
  this->NumberOfSegments = static_cast<vtkIdType>(stats.segments);
  this->Modified();
  return true;
}

bool vtkMTPTReferenceRenderer::ReadPixels(vtkRenderer* renderer, vtkDoubleArray* rgb, int front)
{
  if (!renderer || !rgb || !renderer->GetRenderWindow())
  {
    return false;
  }
  int width = 0, height = 0, x0 = 0, y0 = 0;
  renderer->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width <= 0 || height <= 0)
  {
    return false;
  }
  vtkNew<vtkFloatArray> rgba;
  if (!renderer->GetRenderWindow()->GetRGBAPixelData(
        x0, y0, x0 + width - 1, y0 + height - 1, front, rgba) ||
    rgba->GetNumberOfTuples() != static_cast<vtkIdType>(width) * height)
  {
    return false;
  }
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(rgba->GetNumberOfTuples());
  for (vtkIdType i = 0; i < rgba->GetNumberOfTuples(); ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      rgb->SetValue(3 * i + k, rgba->GetValue(4 * i + k));
    }
  }
  return true;
}

bool vtkMTPTReferenceRenderer::CompareImages(vtkDoubleArray* a, vtkDoubleArray* b, double result[3])
{
  if (!a || !b || a->GetNumberOfComponents() != 3 || b->GetNumberOfComponents() != 3 ||
    a->GetNumberOfTuples() != b->GetNumberOfTuples() || a->GetNumberOfTuples() == 0)
  {
    return false;
  }
  const mtpt::ImageError e = mtpt::CompareImages(
    a->GetPointer(0), b->GetPointer(0), static_cast<std::size_t>(a->GetNumberOfTuples()));
  result[0] = e.rmse;
  result[1] = e.psnr;
  result[2] = e.maxAbs;
  return true;
}

bool vtkMTPTReferenceRenderer::CompareWithRenderer(
  vtkRenderer* renderer, double result[3], int front)
{
  vtkNew<vtkDoubleArray> pixels;
  if (!ReadPixels(renderer, pixels, front))
  {
    vtkErrorMacro(<< "could not read the renderer's pixels back");
    return false;
  }
  if (!CompareImages(pixels, this->Image, result))
  {
    vtkErrorMacro(<< "the window's image (" << pixels->GetNumberOfTuples()
                  << " pixels) does not match the reference (" << this->Size[0] << " x "
                  << this->Size[1] << ")");
    return false;
  }
  return true;
}

void vtkMTPTReferenceRenderer::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "TransferFunctionSamples: " << this->TransferFunctionSamples << "\n";
  os << indent << "Size: " << this->Size[0] << " x " << this->Size[1] << "\n";
  os << indent << "ExactTransferFunctions: " << this->ExactTransferFunctions << "\n";
  os << indent << "RenderSeconds: " << this->RenderSeconds << "\n";
  os << indent << "NumberOfSegments: " << this->NumberOfSegments << "\n";
}
