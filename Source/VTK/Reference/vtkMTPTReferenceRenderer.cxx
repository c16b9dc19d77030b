// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMTPTReferenceRenderer.h"

#include "Input/MeshAdapter.h"
#include "Input/MeshSource.h"
#include "Input/Tetrahedralizer.h"
#include "Input/VolumeInput.h"

#include "mtpt/Gradients.h"
#include "mtpt/ReferenceRenderer.h"

#include "vtkAbstractVolumeMapper.h"
#include "vtkActor.h"
#include "vtkActorCollection.h"
#include "vtkCellArray.h"
#include "vtkMapper.h"
#include "vtkPolyData.h"
#include "vtkProperty.h"
#include "vtkTriangleFilter.h"
#include "vtkAppendFilter.h"
#include "vtkCamera.h"
#include "vtkDataObjectTree.h"
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
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridBase.h"
#include "vtkUnstructuredGridVolumeMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeCollection.h"
#include "vtkCellData.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkVolumeMapper.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

vtkStandardNewMacro(vtkMTPTReferenceRenderer);

namespace
{

/**
 * Whether every node of `f` (N values: its scalar, its values, then midpoint and sharpness)
 * has VTK's default midpoint 0.5 and sharpness 0, and the scalars strictly increase: then
 * the function is the polyline through its nodes.
 */
template <int N, typename Function>
bool PolylineNodes(Function* f)
{
  double previous = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[N];
    f->GetNodeValue(i, node);
    if (node[N - 2] != 0.5 || node[N - 1] != 0.0 || !(node[0] > previous))
    {
      return false;
    }
    previous = node[0];
  }
  return true;
}

/// True when the piecewise function is exactly the polyline through its nodes, clamped.
bool IsPolyline(vtkPiecewiseFunction* f)
{
  return f->GetClamping() && PolylineNodes<4>(f);
}

/// True when the colour function is exactly the RGB polyline through its nodes, clamped.
bool IsPolyline(vtkColorTransferFunction* f)
{
  return f->GetClamping() && f->GetColorSpace() == VTK_CTF_RGB &&
    f->GetScale() == VTK_CTF_LINEAR && PolylineNodes<6>(f);
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

namespace
{

/// The transfer functions of `property` as the reference's piecewise-linear nodes: node for
/// node when that is exact, VTK's own samples over `dataRange` and the nodes otherwise.
/// Returns whether the conversion was exact.
bool ConvertTransferFunctions(vtkVolumeProperty* property, const double dataRange[2], int samples,
  mtpt::ReferenceSettings& settings)
{
  const bool gray = property->GetColorChannels(0) == 1;
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  vtkPiecewiseFunction* grayFunction = gray ? property->GetGrayTransferFunction(0) : nullptr;
  vtkColorTransferFunction* rgbFunction = gray ? nullptr : property->GetRGBTransferFunction(0);
  if (IsPolyline(opacity) && (gray ? IsPolyline(grayFunction) : IsPolyline(rgbFunction)))
  {
    for (int i = 0; i < opacity->GetSize(); ++i)
    {
      double node[4];
      opacity->GetNodeValue(i, node);
      settings.opacity.push_back({ node[0], node[1] });
    }
    const int colours = gray ? grayFunction->GetSize() : rgbFunction->GetSize();
    for (int i = 0; i < colours; ++i)
    {
      double node[6];
      if (gray)
      {
        grayFunction->GetNodeValue(i, node);
        node[2] = node[3] = node[1];
      }
      else
      {
        rgbFunction->GetNodeValue(i, node);
      }
      settings.color.push_back({ node[0], node[1], node[2], node[3] });
    }
    return true;
  }
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
  std::vector<double> alpha(samples), colour(3 * static_cast<std::size_t>(samples));
  opacity->GetTable(range[0], range[1], samples, alpha.data());
  if (gray)
  {
    grayFunction->GetTable(range[0], range[1], samples, colour.data());
    for (int i = samples - 1; i >= 0; --i)
    {
      colour[3 * i] = colour[3 * i + 1] = colour[3 * i + 2] = colour[i];
    }
  }
  else
  {
    rgbFunction->GetTable(range[0], range[1], samples, colour.data());
  }
  for (int i = 0; i < samples; ++i)
  {
    const double s = range[0] + (range[1] - range[0]) * i / (samples - 1);
    settings.opacity.push_back({ s, alpha[i] });
    settings.color.push_back({ s, colour[3 * i], colour[3 * i + 1], colour[3 * i + 2] });
  }
  return false;
}

} // namespace

namespace
{

/**
 * The view of `volume` in `renderer` as the mapper draws it: the matrices, the image size,
 * the background and the mapper's clipping planes; returns how many planes are ignored.
 */
int SetView(
  vtkRenderer* renderer, vtkVolume* volume, const int size[2], mtpt::ReferenceSettings& settings)
{
  mtpt::ViewMatrices(renderer, volume, settings.modelView, settings.projection);
  settings.width = size[0];
  settings.height = size[1];
  renderer->GetBackground(settings.background);
  int ignored = 0;
  settings.clipPlanes = mtpt::EyeClipPlanes(volume->GetMapper(), renderer, ignored);
  return ignored;
}

/**
 * The blend mode of `mapper` into `settings`, with the average's range (a vtkVolumeMapper's
 * own, else `averageRange`); false when the mode is none the reference integrates (then
 * composite).
 */
bool SetBlending(vtkAbstractMapper* mapper, const double dataRange[2],
  const double averageRange[2], mtpt::ReferenceSettings& settings)
{
  // The mapper's blend mode (vtkVolumeMapper's values), x normalized over the data's range
  // as the mappers' tables span it (a constant field: a range of width 1).
  int mode = 0;
  std::copy(averageRange, averageRange + 2, settings.averageRange);
  if (auto* volumeMapper = vtkVolumeMapper::SafeDownCast(mapper))
  {
    mode = volumeMapper->GetBlendMode();
    volumeMapper->GetAverageIPScalarRange(settings.averageRange);
  }
  else if (auto* gridMapper = vtkUnstructuredGridVolumeMapper::SafeDownCast(mapper))
  {
    mode = gridMapper->GetBlendMode();
  }
  const bool known = mode >= 0 && mode <= static_cast<int>(mtpt::BlendMode::Additive);
  settings.blendMode = known ? static_cast<mtpt::BlendMode>(mode) : mtpt::BlendMode::Composite;
  settings.scalarRange[0] = dataRange[0];
  settings.scalarRange[1] = dataRange[1] > dataRange[0] ? dataRange[1] : dataRange[0] + 1.0;
  return known;
}

/**
 * Shading, as the mapper lights the cells (mtpt/Lighting.h): the same normals (into `normals`,
 * which `settings` then refers to) and the renderer's lights; nothing where the mapper draws
 * unlit (shading off, dependent components, cell scalars, blend modes other than composite).
 */
void SetShading(vtkRenderer* renderer, vtkVolumeProperty* property,
  const mtpt::MeshAdapter& adapter, const mtpt::ScalarsView& scalars, int threads,
  std::vector<float>& normals, mtpt::ReferenceSettings& settings)
{
  if (!property->GetShade(0) || settings.mapping != mtpt::ScalarMapping::TransferFunctions ||
    scalars.association != mtpt::ScalarsView::Association::Points ||
    settings.blendMode != mtpt::BlendMode::Composite)
  {
    return;
  }
  std::vector<float> gradients;
  mtpt::PointGradients(adapter.Points(), adapter.Cells(), scalars, gradients, threads);
  mtpt::CellNormals(adapter.Cells(), adapter.Points().count, gradients, normals, threads);
  int ignored = 0;
  settings.lighting = mtpt::VolumeLighting(renderer, property, ignored);
  settings.normals = normals.data();
}

/// How `channels` values per tuple become colour and opacity (VTK's PT's mappings).
mtpt::ScalarMapping MappingOf(int channels)
{
  return channels == 1
    ? mtpt::ScalarMapping::TransferFunctions
    : (channels == 2 ? mtpt::ScalarMapping::ColourAndOpacityScalars : mtpt::ScalarMapping::Colours);
}

/**
 * The renderer's visible translucent actors (opacity strictly between 0 and 1) that draw
 * polygonal data, as triangles in eye coordinates with the flat colour VTK draws them with
 * when lighting is off: ambient * ambient colour + diffuse * diffuse colour, clamped.
 * Returns the number of such actors whose lighting is on (not modelled).
 */
int TranslucentTriangles(vtkRenderer* renderer, std::vector<mtpt::ReferenceTriangle>& triangles)
{
  int lit = 0;
  vtkMatrix4x4* view = renderer->GetActiveCamera()->GetModelViewTransformMatrix();
  vtkActorCollection* actors = renderer->GetActors();
  vtkCollectionSimpleIterator it;
  actors->InitTraversal(it);
  while (vtkActor* actor = actors->GetNextActor(it))
  {
    vtkProperty* p = actor->GetProperty();
    auto* poly = vtkPolyData::SafeDownCast(
      actor->GetMapper() ? actor->GetMapper()->GetInput() : nullptr);
    const double opacity = p->GetOpacity();
    if (!actor->GetVisibility() || !poly || !(opacity > 0.0 && opacity < 1.0))
    {
      continue;
    }
    lit += p->GetLighting() ? 1 : 0;
    vtkNew<vtkTriangleFilter> split;
    split->SetInputData(poly);
    split->PassVertsOff();
    split->PassLinesOff();
    split->Update();
    vtkNew<vtkMatrix4x4> toEye;
    vtkMatrix4x4::Multiply4x4(view, actor->GetMatrix(), toEye);
    double ambient[3], diffuse[3];
    p->GetAmbientColor(ambient);
    p->GetDiffuseColor(diffuse);
    mtpt::ReferenceTriangle t{};
    for (int c = 0; c < 3; ++c)
    {
      t.rgb[c] = std::min(1.0, p->GetAmbient() * ambient[c] + p->GetDiffuse() * diffuse[c]);
    }
    t.opacity = opacity;
    vtkPolyData* out = split->GetOutput();
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    vtkCellArray* polys = out->GetPolys();
    for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
    {
      for (int k = 0; k < 3 && n == 3; ++k)
      {
        double model[4] = { 0, 0, 0, 1 }, eye[4];
        out->GetPoint(ids[k], model);
        model[3] = 1.0;
        toEye->MultiplyPoint(model, eye);
        for (int d = 0; d < 3; ++d)
        {
          t.eye[k][d] = eye[d] / eye[3];
        }
      }
      if (n == 3)
      {
        triangles.push_back(t);
      }
    }
  }
  return lit;
}

} // namespace

bool vtkMTPTReferenceRenderer::CheckScene(
  vtkRenderer* renderer, vtkVolume* volume, vtkUnstructuredGridBase*& input, int size[2])
{
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
  if (!input)
  {
    auto* gridMapper = vtkUnstructuredGridVolumeMapper::SafeDownCast(volume->GetMapper());
    vtkDataObject* data = gridMapper ? gridMapper->GetInputDataObject(0, 0) : nullptr;
    input = vtkUnstructuredGridBase::SafeDownCast(data);
    if (!input && vtkDataObjectTree::SafeDownCast(data))
    {
      // A composite input: its unstructured blocks as one grid (the integral does not
      // depend on how the cells are grouped).
      vtkNew<vtkAppendFilter> append;
      for (const auto& grid : mtpt::MeshSource::Grids(data))
      {
        append->AddInputData(grid.first);
      }
      if (append->GetNumberOfInputConnections(0) > 0)
      {
        append->Update();
        this->Appended = vtkSmartPointer<vtkUnstructuredGrid>::New();
        this->Appended->ShallowCopy(append->GetOutput());
        input = this->Appended;
      }
    }
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
  int x0 = 0, y0 = 0;
  renderer->GetTiledSizeAndOrigin(&size[0], &size[1], &x0, &y0);
  if (size[0] <= 0 || size[1] <= 0)
  {
    vtkErrorMacro(<< "the renderer's viewport is empty (" << size[0] << " x " << size[1]
                  << "): add it to a render window with a size");
    return false;
  }
  return true;
}

bool vtkMTPTReferenceRenderer::Render(
  vtkRenderer* renderer, vtkVolume* volume, vtkUnstructuredGridBase* input)
{
  this->Image->SetNumberOfTuples(0);
  this->Size[0] = this->Size[1] = 0;
  this->RenderSeconds = 0;
  this->NumberOfSegments = 0;
  int size[2] = { 0, 0 };
  if (!this->CheckScene(renderer, volume, input, size))
  {
    return false;
  }
  // Mesh and scalars exactly as the mapper reads them: other cell types split into
  // tetrahedra the same way, then the same views and the same scalar selection.
  mtpt::Tetrahedralizer tetrahedralizer;
  input = tetrahedralizer.Update(input);
  mtpt::MeshAdapter adapter;
  if (input->GetNumberOfCells() == 0 || !adapter.Update(input))
  {
    vtkErrorMacro(<< "cannot integrate the input: "
                  << (input->GetNumberOfCells() == 0 ? "it has no 3D cells" : adapter.Error()));
    return false;
  }
  vtkVolumeProperty* property = volume->GetProperty();
  const mtpt::ScalarSelection selected = mtpt::SelectScalars(
    input, vtkAbstractVolumeMapper::SafeDownCast(volume->GetMapper()), property);
  if (!selected.array)
  {
    vtkErrorMacro(<< "cannot integrate the input: " << selected.error);
    return false;
  }
  double dataRange[2];
  vtkIdType nonFinite = 0;
  const float* values = adapter.Scalars(selected.array, selected.component, dataRange, nonFinite);
  mtpt::ReferenceSettings settings;
  this->ExactTransferFunctions =
    ConvertTransferFunctions(property, dataRange, this->TransferFunctionSamples, settings);
  if (const int ignored = SetView(renderer, volume, size, settings))
  {
    vtkWarningMacro(<< "clipping with the first " << mtpt::ClipPlanes::Max << " clipping "
                    << "planes; " << ignored << " more are ignored, as the mapper does");
  }
  if (const int lit = TranslucentTriangles(renderer, settings.triangles))
  {
    vtkWarningMacro(<< lit << " translucent actor(s) have lighting on; the reference draws "
                    << "them with their flat colour (lighting off)");
  }
  settings.unitDistance = mtpt::UnitDistance(property);
  if (!SetBlending(volume->GetMapper(), dataRange, this->AverageIPScalarRange, settings))
  {
    vtkWarningMacro(<< "the mapper's blend mode is none the reference integrates (0 to 4); "
                    << "integrating with composite blending");
  }
  // Dependent components: the mapping of VTK's PT, integrated exactly (ScalarMapping).
  settings.mapping = MappingOf(mtpt::ChannelsOf(selected));
  const mtpt::ScalarsView view{ values,
    selected.cellData ? mtpt::ScalarsView::Association::Cells
                      : mtpt::ScalarsView::Association::Points };
  std::vector<float> normals;
  SetShading(renderer, property, adapter, view, this->NumberOfThreads, normals, settings);
  return this->Integrate(adapter, view, settings, size);
}

namespace
{
/// One volume of several for the reference: its tetrahedra in world coordinates with its
/// scalars, and its transfer functions' nodes over their and the data's range.
struct PlacedVolume
{
  vtkSmartPointer<vtkUnstructuredGrid> grid; ///< world points, scalars "value" (double)
  mtpt::ReferenceSettings functions;          ///< its color and opacity nodes only
  double low = 0, high = 1;                   ///< the range the nodes and data span
  double unitDistance = 1;
  bool cellData = false;
  bool exact = true; ///< its functions converted node for node
};

/// `nodes` extended to [low, high] with its end values (a scalar beyond the nodes reads the
/// nearest end, as the transfer functions clamp).
template <typename Node>
void Extend(std::vector<Node>& nodes, double low, double high)
{
  if (nodes.empty())
  {
    return;
  }
  std::sort(nodes.begin(), nodes.end(),
    [](const Node& a, const Node& b) { return a.scalar < b.scalar; });
  if (low < nodes.front().scalar)
  {
    Node first = nodes.front();
    first.scalar = low;
    nodes.insert(nodes.begin(), first);
  }
  if (high > nodes.back().scalar)
  {
    Node last = nodes.back();
    last.scalar = high;
    nodes.push_back(last);
  }
}

/// The visible volumes of `volumes`, in order.
std::vector<vtkVolume*> VisibleVolumes(vtkVolumeCollection* volumes)
{
  std::vector<vtkVolume*> visible;
  vtkCollectionSimpleIterator it;
  volumes->InitTraversal(it);
  while (vtkVolume* volume = volumes->GetNextVolume(it))
  {
    if (volume->GetVisibility())
    {
      visible.push_back(volume);
    }
  }
  return visible;
}

/// Whether the mapper of `volume` blends by composite (VTK's mappers keep the mode apart).
bool Composites(vtkVolume* volume)
{
  if (auto* mapper = vtkVolumeMapper::SafeDownCast(volume->GetMapper()))
  {
    return mapper->GetBlendMode() == vtkVolumeMapper::COMPOSITE_BLEND;
  }
  auto* grid = vtkUnstructuredGridVolumeMapper::SafeDownCast(volume->GetMapper());
  return !grid || grid->GetBlendMode() == 0;
}

/// `tetrahedra` with its points taken to world coordinates by `matrix` and `values` (per
/// point, or per cell with `cellData`) as its only scalars, "value".
vtkSmartPointer<vtkUnstructuredGrid> WorldGrid(
  vtkUnstructuredGridBase* tetrahedra, vtkMatrix4x4* matrix, const float* values, bool cellData)
{
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(tetrahedra);
  vtkNew<vtkPoints> world;
  world->SetDataTypeToDouble();
  world->SetNumberOfPoints(tetrahedra->GetNumberOfPoints());
  for (vtkIdType i = 0; i < tetrahedra->GetNumberOfPoints(); ++i)
  {
    double point[4] = { 0, 0, 0, 1 };
    tetrahedra->GetPoint(i, point);
    matrix->MultiplyPoint(point, point);
    world->SetPoint(i, point[0] / point[3], point[1] / point[3], point[2] / point[3]);
  }
  grid->SetPoints(world);
  const vtkIdType tuples =
    cellData ? tetrahedra->GetNumberOfCells() : tetrahedra->GetNumberOfPoints();
  vtkNew<vtkDoubleArray> value;
  value->SetName("value");
  value->SetNumberOfTuples(tuples);
  for (vtkIdType i = 0; i < tuples; ++i)
  {
    value->SetValue(i, values[i]);
  }
  grid->GetPointData()->Initialize();
  grid->GetCellData()->Initialize();
  (cellData ? static_cast<vtkDataSetAttributes*>(grid->GetCellData()) : grid->GetPointData())
    ->SetScalars(value);
  return grid;
}

/// `volume` (of grid `input`) as the reference of several volumes takes it; false, with
/// `error` saying why, when it cannot.
bool PlaceVolume(vtkVolume* volume, vtkUnstructuredGridBase* input, int samples, PlacedVolume& p,
  std::string& error)
{
  vtkVolumeProperty* property = volume->GetProperty();
  if (property->GetShade(0) || !property->GetIndependentComponents() || !Composites(volume))
  {
    error = "several volumes are integrated with composite blending, unlit, of independent "
            "components; use Render for one volume otherwise";
    return false;
  }
  mtpt::Tetrahedralizer tetrahedralizer;
  vtkUnstructuredGridBase* tetrahedra = tetrahedralizer.Update(input);
  mtpt::MeshAdapter adapter;
  if (tetrahedra->GetNumberOfCells() == 0 || !adapter.Update(tetrahedra))
  {
    error = tetrahedra->GetNumberOfCells() == 0 ? "it has no 3D cells" : adapter.Error();
    return false;
  }
  auto* mapper = vtkAbstractVolumeMapper::SafeDownCast(volume->GetMapper());
  const mtpt::ScalarSelection selected = mtpt::SelectScalars(tetrahedra, mapper, property);
  if (!selected.array)
  {
    error = selected.error;
    return false;
  }
  double dataRange[2];
  vtkIdType nonFinite = 0;
  const float* values = adapter.Scalars(selected.array, selected.component, dataRange, nonFinite);
  p.exact = ConvertTransferFunctions(property, dataRange, samples, p.functions);
  p.low = dataRange[0];
  p.high = dataRange[1];
  for (const auto& node : p.functions.color)
  {
    p.low = std::min(p.low, node.scalar);
    p.high = std::max(p.high, node.scalar);
  }
  for (const auto& node : p.functions.opacity)
  {
    p.low = std::min(p.low, node.scalar);
    p.high = std::max(p.high, node.scalar);
  }
  Extend(p.functions.color, p.low, p.high);
  Extend(p.functions.opacity, p.low, p.high);
  p.unitDistance = mtpt::UnitDistance(property);
  p.cellData = selected.cellData;
  p.grid = WorldGrid(tetrahedra, volume->GetMatrix(), values, selected.cellData);
  return true;
}

/**
 * The volumes as one mesh (`all`) and one pair of functions (`settings`' color and opacity):
 * volume k's scalars moved into a stretch of their own, its functions moved alike and its
 * opacity scaled to the smallest unit distance, so that one pair serves every cell exactly
 * (a cell's scalars stay inside its volume's stretch). Returns that unit distance.
 */
double JoinVolumes(
  std::vector<PlacedVolume>& placed, mtpt::ReferenceSettings& settings, vtkUnstructuredGrid* all)
{
  double width = 0, unit = placed.front().unitDistance;
  for (const PlacedVolume& p : placed)
  {
    width = std::max(width, p.high - p.low);
    unit = std::min(unit, p.unitDistance);
  }
  const double stride = 2.0 * width + 1.0;
  vtkNew<vtkAppendFilter> append;
  for (std::size_t k = 0; k < placed.size(); ++k)
  {
    PlacedVolume& p = placed[k];
    const double shift = stride * static_cast<double>(k) - p.low;
    for (mtpt::ColorNode node : p.functions.color)
    {
      node.scalar += shift;
      settings.color.push_back(node);
    }
    for (mtpt::OpacityNode node : p.functions.opacity)
    {
      node.scalar += shift;
      node.opacity *= unit / p.unitDistance;
      settings.opacity.push_back(node);
    }
    vtkDataArray* value =
      p.cellData ? p.grid->GetCellData()->GetScalars() : p.grid->GetPointData()->GetScalars();
    for (vtkIdType i = 0; i < value->GetNumberOfTuples(); ++i)
    {
      value->SetTuple1(i, value->GetTuple1(i) + shift);
    }
    append->AddInputData(p.grid);
  }
  append->Update();
  all->ShallowCopy(append->GetOutput());
  return unit;
}
} // namespace

bool vtkMTPTReferenceRenderer::RenderVolumes(vtkRenderer* renderer, vtkVolumeCollection* volumes)
{
  this->Image->SetNumberOfTuples(0);
  this->Size[0] = this->Size[1] = 0;
  this->RenderSeconds = 0;
  this->NumberOfSegments = 0;
  const std::vector<vtkVolume*> visible =
    volumes ? VisibleVolumes(volumes) : std::vector<vtkVolume*>();
  if (visible.empty())
  {
    vtkErrorMacro(<< "no visible volume to integrate");
    return false;
  }
  int size[2] = { 0, 0 };
  std::vector<PlacedVolume> placed(visible.size());
  this->ExactTransferFunctions = true;
  for (std::size_t v = 0; v < visible.size(); ++v)
  {
    vtkUnstructuredGridBase* input = nullptr;
    std::string error;
    if (!this->CheckScene(renderer, visible[v], input, size))
    {
      return false;
    }
    if (!PlaceVolume(visible[v], input, this->TransferFunctionSamples, placed[v], error) ||
      placed[v].cellData != placed.front().cellData)
    {
      vtkErrorMacro(<< "cannot integrate volume " << v + 1 << ": "
                    << (error.empty() ? "its scalars and volume 1's are not both point data "
                                        "or both cell data"
                                      : error));
      return false;
    }
    this->ExactTransferFunctions = this->ExactTransferFunctions && placed[v].exact;
  }
  mtpt::ReferenceSettings settings;
  vtkNew<vtkUnstructuredGrid> all;
  settings.unitDistance = JoinVolumes(placed, settings, all);
  mtpt::MeshAdapter adapter;
  if (!adapter.Update(all))
  {
    vtkErrorMacro(<< "cannot integrate the volumes: " << adapter.Error());
    return false;
  }
  const bool cellData = placed.front().cellData;
  double range[2];
  vtkIdType nonFinite = 0;
  const float* values =
    adapter.Scalars(cellData ? all->GetCellData()->GetScalars() : all->GetPointData()->GetScalars(),
      0, range, nonFinite);
  // The first volume's clipping planes; the view in world coordinates.
  if (const int ignored = SetView(renderer, visible.front(), size, settings))
  {
    vtkWarningMacro(<< "clipping with the first " << mtpt::ClipPlanes::Max << " clipping "
                    << "planes; " << ignored << " more are ignored, as the mapper does");
  }
  mtpt::ViewMatrices(renderer, nullptr, settings.modelView, settings.projection);
  if (const int lit = TranslucentTriangles(renderer, settings.triangles))
  {
    vtkWarningMacro(<< lit << " translucent actor(s) have lighting on; the reference draws "
                    << "them with their flat colour (lighting off)");
  }
  settings.scalarRange[0] = range[0];
  settings.scalarRange[1] = range[1] > range[0] ? range[1] : range[0] + 1.0;
  const mtpt::ScalarsView view{ values,
    cellData ? mtpt::ScalarsView::Association::Cells : mtpt::ScalarsView::Association::Points };
  return this->Integrate(adapter, view, settings, size);
}

bool vtkMTPTReferenceRenderer::Integrate(const mtpt::MeshAdapter& adapter,
  const mtpt::ScalarsView& view, const mtpt::ReferenceSettings& settings, const int size[2])
{
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
  this->Image->SetNumberOfTuples(static_cast<vtkIdType>(size[0]) * size[1]);
  std::copy(rgb.begin(), rgb.end(), this->Image->GetPointer(0));
  this->Image->Modified();
  this->Size[0] = size[0];
  this->Size[1] = size[1];
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
