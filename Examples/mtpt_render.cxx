// SPDX-License-Identifier: BSD-3-Clause
// mtpt_render: renders an unstructured grid with vtkMultiThreadedProjectedTetrahedraMapper
// to a PNG (or an interactive window), prints the mapper's per-stage times and, with
// --compare-vtk, VTK's own vtkProjectedTetrahedraMapper on the same scene.
#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCamera.h"
#include "vtkCellData.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDataSet.h"
#include "vtkDataSetReader.h"
#include "vtkDataSetTriangleFilter.h"
#include "vtkDoubleArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeCollection.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"
#include "vtkXMLUnstructuredGridReader.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace
{

struct Options
{
  std::string input = MTPT_EXAMPLE_DEFAULT_DATA;
  std::string output = "mtpt.png";
  std::string array;
  std::string tf = "smooth";
  std::string order = "radix";
  std::string backend = "auto";
  std::string shading = "vtk";
  int width = 800, height = 600;
  double azimuth = 0, elevation = 30, zoom = 1.0, unitDistance = 0;
  bool parallel = false, interactive = false, compare = false, reference = false;
  int threads = 0, frames = 5;
};

void Usage()
{
  std::printf(
    "usage: mtpt_render [options] [file.vtu|file.vtk]\n"
    "Renders an unstructured grid with vtkMultiThreadedProjectedTetrahedraMapper.\n"
    "Non-tetrahedral cells are split with vtkDataSetTriangleFilter first.\n"
    "  --output FILE        PNG to write (default mtpt.png)\n"
    "  --size WxH           window size (default 800x600)\n"
    "  --array NAME         scalar array (default: active scalars, else the first array;\n"
    "                       vectors are rendered by magnitude)\n"
    "  --azimuth A --elevation E --zoom Z   camera (defaults 0, 30, 1)\n"
    "  --parallel           parallel projection (default perspective)\n"
    "  --tf smooth|bands    transfer function: a ramp, or narrow bands (default smooth)\n"
    "  --unit-distance D    ScalarOpacityUnitDistance (default: diagonal / 40)\n"
    "  --threads N          threads for the CPU stages (default 0: all)\n"
    "  --order radix|partition   visibility order (default radix)\n"
    "  --backend auto|gl|cpu     how triangles reach the screen (default auto)\n"
    "  --shading vtk|pre-integrated   VTK-compatible (default) or pre-integrated shading\n"
    "  --frames N           frames to time (default 5; medians are printed)\n"
    "  --compare-vtk        also render with vtkProjectedTetrahedraMapper (<output>-vtkpt.png)\n"
    "  --reference          render the exact ray-integral reference of the scene and print\n"
    "                       each image's error against it (RMSE, PSNR, worst channel)\n"
    "  --interactive        open a window instead of only writing the PNG\n"
    "  --help\n"
    "Default data set: %s\n",
    MTPT_EXAMPLE_DEFAULT_DATA);
}

bool Parse(int argc, char** argv, Options& o)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto next = [&](const char* what) -> const char*
    {
      if (i + 1 >= argc)
      {
        std::fprintf(stderr, "mtpt_render: %s needs %s\n", a.c_str(), what);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--help" || a == "-h")
    {
      Usage();
      std::exit(0);
    }
    else if (a == "--output")
      o.output = next("a file name");
    else if (a == "--size")
    {
      if (std::sscanf(next("WxH"), "%dx%d", &o.width, &o.height) != 2 || o.width < 1 ||
        o.height < 1)
      {
        std::fprintf(stderr, "mtpt_render: --size takes WxH with positive numbers\n");
        return false;
      }
    }
    else if (a == "--array")
      o.array = next("a name");
    else if (a == "--azimuth")
      o.azimuth = std::atof(next("degrees"));
    else if (a == "--elevation")
      o.elevation = std::atof(next("degrees"));
    else if (a == "--zoom")
      o.zoom = std::atof(next("a factor"));
    else if (a == "--parallel")
      o.parallel = true;
    else if (a == "--tf")
      o.tf = next("smooth or bands");
    else if (a == "--unit-distance")
      o.unitDistance = std::atof(next("a distance"));
    else if (a == "--threads")
      o.threads = std::atoi(next("a count"));
    else if (a == "--order")
      o.order = next("radix or partition");
    else if (a == "--backend")
      o.backend = next("auto, gl or cpu");
    else if (a == "--shading")
      o.shading = next("vtk or pre-integrated");
    else if (a == "--reference")
      o.reference = true;
    else if (a == "--frames")
      o.frames = std::max(1, std::atoi(next("a count")));
    else if (a == "--compare-vtk")
      o.compare = true;
    else if (a == "--interactive")
      o.interactive = true;
    else if (!a.empty() && a[0] == '-')
    {
      std::fprintf(stderr, "mtpt_render: unknown option %s (see --help)\n", a.c_str());
      return false;
    }
    else
      o.input = a;
  }
  if (o.tf != "smooth" && o.tf != "bands")
  {
    std::fprintf(stderr, "mtpt_render: --tf takes smooth or bands\n");
    return false;
  }
  if (o.order != "radix" && o.order != "partition")
  {
    std::fprintf(stderr, "mtpt_render: --order takes radix or partition\n");
    return false;
  }
  if (o.backend != "auto" && o.backend != "gl" && o.backend != "cpu")
  {
    std::fprintf(stderr, "mtpt_render: --backend takes auto, gl or cpu\n");
    return false;
  }
  if (o.shading != "vtk" && o.shading != "pre-integrated")
  {
    std::fprintf(stderr, "mtpt_render: --shading takes vtk or pre-integrated\n");
    return false;
  }
  return true;
}

bool EndsWith(const std::string& s, const std::string& suffix)
{
  return s.size() >= suffix.size() &&
    s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Reads the file and returns tetrahedra with the chosen scalars active; null on error.
vtkSmartPointer<vtkUnstructuredGrid> Load(const Options& o, double range[2])
{
  vtkSmartPointer<vtkDataSet> data;
  if (EndsWith(o.input, ".vtu"))
  {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    if (!reader->CanReadFile(o.input.c_str()))
    {
      std::fprintf(
        stderr, "mtpt_render: cannot read '%s' as a VTK XML unstructured grid\n", o.input.c_str());
      return nullptr;
    }
    reader->SetFileName(o.input.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
  else if (EndsWith(o.input, ".vtk"))
  {
    vtkNew<vtkDataSetReader> reader;
    reader->SetFileName(o.input.c_str());
    reader->Update();
    data = reader->GetOutput();
  }
  else
  {
    std::fprintf(stderr, "mtpt_render: '%s' is neither .vtu nor .vtk\n", o.input.c_str());
    return nullptr;
  }
  if (!data || data->GetNumberOfCells() == 0)
  {
    std::fprintf(
      stderr, "mtpt_render: '%s' holds no cells (missing or unreadable file?)\n", o.input.c_str());
    return nullptr;
  }
  // Scalars: the named array, else the active point scalars, else the first point array,
  // else the first cell array.
  vtkDataArray* scalars = nullptr;
  bool cells = false;
  if (!o.array.empty())
  {
    scalars = data->GetPointData()->GetArray(o.array.c_str());
    if (!scalars && (scalars = data->GetCellData()->GetArray(o.array.c_str())))
    {
      cells = true;
    }
    if (!scalars)
    {
      std::fprintf(stderr, "mtpt_render: no point or cell array named '%s'\n", o.array.c_str());
      return nullptr;
    }
  }
  else if ((scalars = data->GetPointData()->GetScalars()) ||
    (data->GetPointData()->GetNumberOfArrays() > 0 &&
      (scalars = data->GetPointData()->GetArray(0))))
  {
  }
  else if (data->GetCellData()->GetNumberOfArrays() > 0 &&
    (scalars = data->GetCellData()->GetArray(0)))
  {
    cells = true;
  }
  if (!scalars)
  {
    std::fprintf(stderr, "mtpt_render: '%s' has no data arrays to render\n", o.input.c_str());
    return nullptr;
  }
  vtkDataSetAttributes* attributes = cells
    ? static_cast<vtkDataSetAttributes*>(data->GetCellData())
    : static_cast<vtkDataSetAttributes*>(data->GetPointData());
  attributes->SetActiveScalars(scalars->GetName());
  scalars->GetRange(range, scalars->GetNumberOfComponents() > 1 ? -1 : 0);

  vtkNew<vtkDataSetTriangleFilter> tetrahedralize;
  tetrahedralize->SetInputData(data);
  tetrahedralize->TetrahedraOnlyOn();
  tetrahedralize->Update();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(tetrahedralize->GetOutput());
  std::printf("%s: %lld points, %lld tetrahedra, %s scalars '%s' in [%g, %g]\n", o.input.c_str(),
    static_cast<long long>(grid->GetNumberOfPoints()),
    static_cast<long long>(grid->GetNumberOfCells()), cells ? "cell" : "point",
    scalars->GetName() ? scalars->GetName() : "", range[0], range[1]);
  return grid;
}

vtkSmartPointer<vtkVolumeProperty> MakeProperty(
  const Options& o, const double range[2], double diagonal)
{
  const double lo = range[0], hi = range[1] > range[0] ? range[1] : range[0] + 1;
  vtkNew<vtkColorTransferFunction> color;
  vtkNew<vtkPiecewiseFunction> opacity;
  if (o.tf == "smooth")
  {
    // Cool-to-warm, with the stops low in the range: in most simulation fields (the blunt
    // fin's density among them) the bulk of the volume sits in the lowest fifth.
    color->AddRGBPoint(lo, 0.23, 0.30, 0.75);
    color->AddRGBPoint(lo + 0.15 * (hi - lo), 0.87, 0.87, 0.87);
    color->AddRGBPoint(lo + 0.4 * (hi - lo), 0.96, 0.60, 0.35);
    color->AddRGBPoint(hi, 0.71, 0.02, 0.15);
    opacity->AddPoint(lo, 0.0);
    opacity->AddPoint(lo + 0.15 * (hi - lo), 0.25);
    opacity->AddPoint(hi, 1.0);
  }
  else
  {
    color->AddRGBPoint(lo, 0.2, 0.4, 1.0);
    color->AddRGBPoint(hi, 1.0, 0.5, 0.1);
    opacity->AddPoint(lo, 0.0);
    for (double f : { 0.2, 0.45, 0.7 })
    {
      const double c = lo + f * (hi - lo), w = 0.02 * (hi - lo);
      opacity->AddPoint(c - w, 0.0);
      opacity->AddPoint(c, 1.0);
      opacity->AddPoint(c + w, 0.0);
    }
    opacity->AddPoint(hi, 0.0);
  }
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(o.unitDistance > 0 ? o.unitDistance : diagonal / 40);
  return property;
}

double Median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

struct Timing
{
  double frame = 0, transform = 0, keys = 0, order = 0, decompose = 0, composite = 0, upload = 0,
         draw = 0;
};

/// Renders `frames` frames after one warm-up, returns median times, writes the PNG.
Timing RenderFrames(const Options& o, vtkUnstructuredGrid* grid, vtkVolumeProperty* property,
  vtkUnstructuredGridVolumeMapper* mapper, const std::string& png, vtkRenderWindow* window,
  vtkRenderer* renderer)
{
  mapper->SetInputData(grid);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  renderer->RemoveAllViewProps();
  renderer->AddVolume(volume);
  // The same camera for every scene: ResetCamera keeps the view direction, so start from
  // VTK's default direction each time before turning.
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(0, 0, 1);
  camera->SetFocalPoint(0, 0, 0);
  camera->SetViewUp(0, 1, 0);
  renderer->ResetCamera();
  camera->SetParallelProjection(o.parallel ? 1 : 0);
  camera->Azimuth(o.azimuth);
  camera->Elevation(o.elevation);
  camera->OrthogonalizeViewUp();
  camera->Zoom(o.zoom);
  renderer->ResetCameraClippingRange();
  window->Render();
  auto* ours = vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(mapper);
  std::vector<double> frame, transform, keys, order, decompose, composite, upload, draw;
  for (int f = 0; f < o.frames; ++f)
  {
    const auto start = std::chrono::steady_clock::now();
    window->Render();
    window->WaitForCompletion();
    frame.push_back(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (ours)
    {
      transform.push_back(ours->GetTransformSeconds());
      keys.push_back(ours->GetDepthKeySeconds());
      order.push_back(ours->GetOrderSeconds());
      decompose.push_back(ours->GetDecomposeSeconds());
      composite.push_back(ours->GetCompositeSeconds());
      upload.push_back(ours->GetUploadSeconds());
      draw.push_back(ours->GetDrawSeconds());
    }
  }
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  grab->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(png.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  return { Median(frame), Median(transform), Median(keys), Median(order), Median(decompose),
    Median(composite), Median(upload), Median(draw) };
}

vtkVolume* FirstVolume(vtkRenderer* renderer)
{
  vtkVolumeCollection* volumes = renderer->GetVolumes();
  volumes->InitTraversal();
  return volumes->GetNextVolume();
}

/// The window's image against the reference: RMSE and PSNR over linear RGB, worst channel.
void PrintError(const char* name, vtkMTPTReferenceRenderer* exact, vtkRenderer* renderer)
{
  double e[3];
  if (exact->CompareWithRenderer(renderer, e))
  {
    std::printf("%s against the exact reference: RMSE %.5f, PSNR %.1f dB, worst channel %.3f\n",
      name, e[0], e[1], e[2]);
  }
}

/// `output` without its .png ending, followed by `suffix`.
std::string Sibling(std::string output, const char* suffix)
{
  if (EndsWith(output, ".png"))
  {
    output.resize(output.size() - 4);
  }
  return output + suffix;
}

/// The reference's last image as an 8-bit PNG.
void WriteImage(vtkMTPTReferenceRenderer* exact, const std::string& png)
{
  const int* size = exact->GetSize();
  vtkNew<vtkImageData> image;
  image->SetDimensions(size[0], size[1], 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  vtkDoubleArray* rgb = exact->GetImage();
  for (vtkIdType i = 0; i < rgb->GetNumberOfValues(); ++i)
  {
    const double v = std::min(1.0, std::max(0.0, rgb->GetValue(i)));
    out[i] = static_cast<unsigned char>(std::lround(255.0 * v));
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(png.c_str());
  writer->SetInputData(image);
  writer->Write();
}

} // namespace

int main(int argc, char** argv)
{
  Options o;
  if (!Parse(argc, argv, o))
  {
    return 2;
  }
  double range[2];
  auto grid = Load(o, range);
  if (!grid)
  {
    return 1;
  }
  const double diagonal = grid->GetLength();
  auto property = MakeProperty(o, range, diagonal);

  vtkNew<vtkMultiThreadedProjectedTetrahedraMapper> mapper;
  mapper->SetNumberOfThreads(o.threads);
  mapper->SetOrderMethod(o.order == "radix"
      ? vtkMultiThreadedProjectedTetrahedraMapper::RADIX_SORT
      : vtkMultiThreadedProjectedTetrahedraMapper::PARTITION_SORT);
  mapper->SetBackend(o.backend == "gl" ? vtkMultiThreadedProjectedTetrahedraMapper::OPENGL_BACKEND
      : o.backend == "cpu"             ? vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND
                           : vtkMultiThreadedProjectedTetrahedraMapper::AUTOMATIC_BACKEND);
  mapper->SetShadingMode(o.shading == "vtk"
      ? vtkMultiThreadedProjectedTetrahedraMapper::VTK_COMPATIBLE_SHADING
      : vtkMultiThreadedProjectedTetrahedraMapper::PRE_INTEGRATED_SHADING);
  mapper->SynchronizedTimingOn();

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(1.0, 1.0, 1.0);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(o.width, o.height);
  window->AddRenderer(renderer);
  window->SetOffScreenRendering(o.interactive ? 0 : 1);

  const Timing t = RenderFrames(o, grid, property, mapper, o.output, window, renderer);
  const char* backend =
    mapper->GetLastBackend() == vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND
    ? "CPU compositor"
    : "OpenGL";
  std::printf("\nMTPT, %d threads requested (0: all), %s order, %s backend, %dx%d, median of %d "
              "frames (ms):\n",
    o.threads, o.order.c_str(), backend, o.width, o.height, o.frames);
  std::printf("| transform | depth keys | order | decompose | composite | upload | draw | "
              "CPU stages | frame |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::printf("| %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n",
    1e3 * t.transform, 1e3 * t.keys, 1e3 * t.order, 1e3 * t.decompose, 1e3 * t.composite,
    1e3 * t.upload, 1e3 * t.draw, 1e3 * (t.transform + t.keys + t.order + t.decompose),
    1e3 * t.frame);
  std::printf("wrote %s\n", o.output.c_str());
  vtkNew<vtkMTPTReferenceRenderer> exact;
  if (o.reference)
  {
    if (!exact->Render(renderer, FirstVolume(renderer)))
    {
      return 1;
    }
    std::printf("exact reference: %.1f s, %lld ray segments%s\n", exact->GetRenderSeconds(),
      static_cast<long long>(exact->GetNumberOfSegments()),
      exact->GetExactTransferFunctions() ? "" : " (transfer functions sampled)");
    PrintError("MTPT", exact, renderer);
    const std::string png = Sibling(o.output, "-reference.png");
    WriteImage(exact, png);
    std::printf("wrote %s (the reference, rounded to 8 bits)\n", png.c_str());
  }

  if (o.compare)
  {
    const std::string vtkPng = Sibling(o.output, "-vtkpt.png");
    vtkNew<vtkProjectedTetrahedraMapper> reference;
    const Timing v = RenderFrames(o, grid, property, reference, vtkPng, window, renderer);
    std::printf("vtkProjectedTetrahedraMapper, same scene: %.1f ms per frame; MTPT is %.2fx "
                "faster; wrote %s\n",
      1e3 * v.frame, v.frame / t.frame, vtkPng.c_str());
    if (o.reference)
    {
      PrintError("vtkProjectedTetrahedraMapper", exact, renderer);
    }
    if (o.interactive)
    {
      // Leave the MTPT scene in the window.
      RenderFrames(o, grid, property, mapper, o.output, window, renderer);
    }
  }

  if (o.interactive)
  {
    vtkNew<vtkRenderWindowInteractor> interactor;
    interactor->SetRenderWindow(window);
    interactor->Initialize();
    window->Render();
    interactor->Start();
  }
  return 0;
}
