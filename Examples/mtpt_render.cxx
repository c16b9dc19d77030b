// SPDX-License-Identifier: BSD-3-Clause
// mtpt_render: renders an unstructured grid with vtkMultiThreadedProjectedTetrahedraMapper
// to a PNG (or an interactive window) and times it with the benchmark harness
// (Benchmarks/Harness.h): the camera turns before every timed frame, so no frame re-uses
// the previous one's results; frames of an unchanged view are timed apart and labelled.
// With --compare-vtk, VTK's own vtkProjectedTetrahedraMapper is timed on the same scene,
// both mappers in VTK's default window (multisampled) and single-sampled, the ratio taking
// each in its faster window, and the two images are written side by side; with --reference, both
// are compared with the exact ray integral. With --interactive, the window asks for --update-rate
// frames a second while the mouse drags the view (VTK's interactor asks for 15), the mapper draws
// a fraction of the cells at a coarser image sample distance to keep up (its level of detail),
// and the full image comes back when the mouse is released.
#include "Harness.h"

#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "vtkCallbackCommand.h"
#include "vtkColorTransferFunction.h"
#include "vtkDoubleArray.h"
#include "vtkImageAppend.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPlane.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkTextProperty.h"
#include "vtkTextRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  std::string input = MTPT_EXAMPLE_DEFAULT_DATA;
  std::string output = "mtpt.png";
  std::string array;
  std::string tf = "structure";
  std::string background = "dark";
  std::string backend = "auto";
  std::string size = "800x600";
  int width = 800, height = 600;
  double unitDistance = 0;
  View view{ 0, 30, 1, false };
  CommonOptions common;
  bool unchanged = true, interactive = false, compare = false, reference = false;
  bool compareMerged = false;
  double updateRate = 15; ///< frames a second asked for while dragging (--interactive)
  std::vector<std::string> clipPlanes; ///< --clip-plane: "ox,oy,oz,nx,ny,nz" each
  bool shade = false;                  ///< --shade, with vtkVolumeProperty's coefficients
  double ambient = 0.1, diffuse = 0.7, specular = 0.2, specularPower = 10;
};

/// Adds the --clip-plane planes to `mapper`; false (and a message) for a malformed one.
bool AddClipPlanes(vtkAbstractMapper* mapper, const std::vector<std::string>& planes)
{
  for (const std::string& text : planes)
  {
    double v[6];
    char end = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", v, v + 1, v + 2, v + 3, v + 4,
          v + 5, &end) != 6 ||
      (v[3] == 0 && v[4] == 0 && v[5] == 0))
    {
      std::fprintf(stderr,
        "mtpt_render: --clip-plane takes ox,oy,oz,nx,ny,nz with a non-zero normal, not '%s'\n",
        text.c_str());
      return false;
    }
    vtkNew<vtkPlane> plane;
    plane->SetOrigin(v[0], v[1], v[2]);
    plane->SetNormal(v[3], v[4], v[5]);
    mapper->AddClippingPlane(plane);
  }
  return true;
}

/// The transfer functions of --tf over the scalar range.
vtkSmartPointer<vtkVolumeProperty> MakeTransferFunctions(
  const Options& o, const double range[2], double diagonal)
{
  const double lo = range[0], hi = range[1] > range[0] ? range[1] : range[0] + 1;
  auto at = [lo, hi](double f) { return lo + f * (hi - lo); };
  vtkNew<vtkColorTransferFunction> color;
  vtkNew<vtkPiecewiseFunction> opacity;
  if (o.tf == "structure")
  {
    // A perceptual map (dark purple through orange to pale yellow, after matplotlib's
    // "inferno") and an opacity that leaves the bulk of the field nearly clear, so that the
    // shells of higher values inside it show: meant for a dark background.
    const double stops[][4] = { { 0.00, 0.00, 0.00, 0.02 }, { 0.08, 0.26, 0.04, 0.41 },
      { 0.16, 0.58, 0.15, 0.40 }, { 0.28, 0.87, 0.32, 0.23 }, { 0.45, 0.99, 0.57, 0.04 },
      { 1.00, 0.99, 1.00, 0.64 } };
    for (const auto& s : stops)
    {
      color->AddRGBPoint(at(s[0]), s[1], s[2], s[3]);
    }
    opacity->AddPoint(at(0.0), 0.0);
    opacity->AddPoint(at(0.1), 0.0);
    opacity->AddPoint(at(0.16), 0.12);
    opacity->AddPoint(at(0.3), 0.45);
    opacity->AddPoint(at(0.6), 0.8);
    opacity->AddPoint(at(1.0), 1.0);
  }
  else if (o.tf == "smooth")
  {
    // Cool-to-warm, with the stops low in the range: in most simulation fields (the blunt
    // fin's density among them) the bulk of the volume sits in the lowest fifth.
    color->AddRGBPoint(lo, 0.23, 0.30, 0.75);
    color->AddRGBPoint(at(0.15), 0.87, 0.87, 0.87);
    color->AddRGBPoint(at(0.4), 0.96, 0.60, 0.35);
    color->AddRGBPoint(hi, 0.71, 0.02, 0.15);
    opacity->AddPoint(lo, 0.0);
    opacity->AddPoint(at(0.15), 0.25);
    opacity->AddPoint(hi, 1.0);
  }
  else // bands: narrow opacity peaks, where vertex classification misses features
  {
    color->AddRGBPoint(lo, 0.2, 0.4, 1.0);
    color->AddRGBPoint(hi, 1.0, 0.5, 0.1);
    opacity->AddPoint(lo, 0.0);
    for (double f : { 0.2, 0.45, 0.7 })
    {
      opacity->AddPoint(at(f) - 0.02 * (hi - lo), 0.0);
      opacity->AddPoint(at(f), 1.0);
      opacity->AddPoint(at(f) + 0.02 * (hi - lo), 0.0);
    }
    opacity->AddPoint(hi, 0.0);
  }
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(o.unitDistance > 0 ? o.unitDistance : diagonal / 40);
  property->SetShade(o.shade ? 1 : 0);
  property->SetAmbient(o.ambient);
  property->SetDiffuse(o.diffuse);
  property->SetSpecular(o.specular);
  property->SetSpecularPower(o.specularPower);
  return property;
}

void WritePNG(vtkImageData* image, const std::string& path)
{
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  writer->Write();
  if (writer->GetErrorCode() != 0)
  {
    std::fprintf(stderr, "mtpt_render: could not write %s\n", path.c_str());
    std::exit(1);
  }
  std::printf("wrote %s\n", path.c_str());
}

/// `output` without its .png ending, followed by `suffix`.
std::string Sibling(std::string output, const char* suffix)
{
  if (output.size() >= 4 && output.compare(output.size() - 4, 4, ".png") == 0)
  {
    output.resize(output.size() - 4);
  }
  return output + suffix;
}

/// The reference's last image as an 8-bit image.
vtkSmartPointer<vtkImageData> ReferenceImage(vtkMTPTReferenceRenderer* exact)
{
  const int* size = exact->GetSize();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(size[0], size[1], 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  vtkDoubleArray* rgb = exact->GetImage();
  for (vtkIdType i = 0; i < rgb->GetNumberOfValues(); ++i)
  {
    out[i] =
      static_cast<unsigned char>(std::lround(255.0 * std::clamp(rgb->GetValue(i), 0.0, 1.0)));
  }
  return image;
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

/// One mapper's timing: moving frames (and their MTPT figures) and unchanged-view frames.
struct Timed
{
  FrameTiming moving, unchanged;
  StageFigures figures; ///< of the median moving frame (MTPT only)
};

Timed Time(Stage& stage, vtkUnstructuredGridVolumeMapper* mapper, const Options& o)
{
  Timed t;
  std::vector<StageFigures> figures;
  t.moving =
    TimeFrames(stage, o.common.timing, [&](std::size_t) { figures.push_back(FiguresOf(mapper)); });
  if (!figures.empty())
  {
    t.figures = figures[std::min(t.moving.medianFrame, figures.size() - 1)];
  }
  if (o.unchanged && !t.moving.slow)
  {
    TimingOptions still = o.common.timing;
    still.step = 0;
    t.unchanged = TimeFrames(stage, still);
  }
  return t;
}

/// After each interaction (the mouse released): the level of detail of the last moving
/// frame and its time.
void ReportInteraction(vtkObject*, unsigned long, void* clientData, void*)
{
  auto* mapper = static_cast<Mapper*>(clientData);
  std::printf("moving: %.3g of the visible cells (%lld tetrahedra), image sample distance %.2f "
              "(%d x %d pixels), %.0f ms per frame\n",
    static_cast<double>(mapper->GetCellFraction()),
    static_cast<long long>(mapper->GetNumberOfTetrahedra()), mapper->GetImageSampleDistance(),
    mapper->GetImageInUseSize()[0], mapper->GetImageInUseSize()[1],
    1e3 * mapper->GetTimeToDraw());
  std::fflush(stdout);
}

/// The interactor asks for `rate` frames a second while the mouse drags, as VTK's interactor
/// styles do (vtkInteractorStyle::StartState), and for VTK's still rate when it is released.
void Interact(Stage& stage, Mapper* mapper, double rate)
{
  stage.StartView();
  vtkNew<vtkRenderWindowInteractor> interactor;
  interactor->SetRenderWindow(stage.GetWindow());
  if (rate > 0)
  {
    interactor->SetDesiredUpdateRate(rate);
    interactor->SetStillUpdateRate(0.0001);
    std::printf("dragging: the volume is drawn with fewer cells and coarser to keep %g frames a "
                "second, and in full when the mouse is released\n",
      rate);
  }
  interactor->Initialize();
  vtkNew<vtkCallbackCommand> report;
  report->SetCallback(ReportInteraction);
  report->SetClientData(mapper);
  if (rate > 0 && mapper)
  {
    interactor->AddObserver(vtkCommand::EndInteractionEvent, report);
  }
  stage.GetWindow()->Render();
  interactor->Start();
}

/**
 * `image` (RGB) with a band above it holding `text`, for the side-by-side picture. Without a
 * text renderer (VTK built without FreeType) the band stays empty and a warning says so.
 */
vtkSmartPointer<vtkImageData> Labelled(vtkImageData* image, const std::string& text)
{
  int size[3];
  image->GetDimensions(size);
  vtkNew<vtkTextProperty> style;
  style->SetFontSize(std::max(12, size[0] / 40));
  style->SetColor(1.0, 1.0, 1.0);
  vtkNew<vtkImageData> label;
  int textSize[2] = { 0, 0 };
  vtkTextRenderer* renderer = vtkTextRenderer::GetInstance();
  if (!renderer || !renderer->RenderString(style, text, label, textSize, 72))
  {
    std::fprintf(stderr, "mtpt_render: no text renderer; the picture has no labels\n");
    textSize[0] = textSize[1] = 0;
  }
  const int margin = style->GetFontSize() / 2, band = style->GetFontSize() + 2 * margin;
  auto out = vtkSmartPointer<vtkImageData>::New();
  out->SetDimensions(size[0], size[1] + band, 1);
  out->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* pixels = static_cast<unsigned char*>(out->GetScalarPointer());
  std::fill(pixels, pixels + 3 * size[0] * (size[1] + band), static_cast<unsigned char>(0));
  std::copy_n(static_cast<unsigned char*>(image->GetScalarPointer()), 3 * size[0] * size[1], pixels);
  // The text's pixels, white blended by their alpha over the black band (row 0 at the bottom).
  const int* extent = label->GetExtent();
  for (int y = extent[2]; y <= extent[3] && textSize[0] > 0; ++y)
  {
    for (int x = extent[0]; x <= extent[1]; ++x)
    {
      const int px = margin + x - extent[0], py = size[1] + margin + y - extent[2];
      if (px < size[0] && py < size[1] + band)
      {
        const double alpha = label->GetScalarComponentAsDouble(x, y, 0, 3) / 255.0;
        unsigned char* p = pixels + 3 * (static_cast<std::size_t>(py) * size[0] + px);
        std::fill(p, p + 3, static_cast<unsigned char>(std::lround(255 * alpha)));
      }
    }
  }
  return out;
}

/// "115" and "105 ms", or with --unchanged "115 (unchanged view 4.1)".
std::string Cell(const Timed& t, const Options& o)
{
  return o.unchanged ? FormatMs(t.moving) + " (unchanged view " + FormatMs(t.unchanged) + ")"
                     : FormatMs(t.moving);
}

/**
 * --compare-vtk: VTK's mapper for the input (its PT, or for blocks its multi-block mapper) on
 * the same scene and camera path, in `stage` (VTK's default window, multisampled) and in a
 * single-sampled window, where MTPT is timed too; VTK's PT takes about twice as long
 * multisampled on Mesa llvmpipe, so the ratio printed takes each mapper in its faster window.
 * Writes VTK's image (default window, start view) beside `ourImage` (MTPT's there).
 */
void CompareWithVTK(Stage& stage, const Scene& scene, vtkVolumeProperty* property,
  vtkUnstructuredGridVolumeMapper* mapper, vtkImageData* ourImage, const Timed& ours,
  const Options& o, vtkMTPTReferenceRenderer* exact)
{
  vtkDataObject* input = scene.blocks ? scene.blocks.Get() : scene.grid.Get();
  const char* kind = scene.blocks ? "vtk-multiblock" : "vtk-pt";
  const char* theirName =
    scene.blocks ? "vtkMultiBlockUnstructuredGridVolumeMapper" : "vtkProjectedTetrahedraMapper";
  auto theirs = MakeMapper(kind);
  stage.SetMapper(theirs, input);
  stage.StartView();
  stage.Frame();
  auto vtkImage = stage.Image();
  WritePNG(vtkImage, Sibling(o.output, "-vtkpt.png"));
  if (o.reference)
  {
    PrintError(theirName, exact, stage.GetRenderer());
  }
  const Timed theirsDefault = Time(stage, theirs, o);
  // Side by side, each labelled with its median frame in VTK's default window.
  vtkNew<vtkImageAppend> side;
  side->AddInputData(Labelled(ourImage, "MTPT (" + ours.figures.backend + " backend): " +
      FormatMs(ours.moving) + " ms a frame"));
  side->AddInputData(Labelled(vtkImage,
    std::string(theirName) + ": " + FormatMs(theirsDefault.moving) + " ms a frame"));
  side->SetAppendAxis(0);
  side->Update();
  WritePNG(side->GetOutput(), Sibling(o.output, "-side-by-side.png"));
  stage.SetMapper(mapper, input);

  // The same two mappers in a single-sampled window (the mapper's own kind: MTPT's backend
  // choice and settings as above).
  StageOptions look;
  look.view = o.view;
  look.multisampling = false;
  const char* contender =
    o.backend == "cpu" ? "mtpt-cpu" : (o.backend == "gl" ? "mtpt-gl" : "mtpt");
  auto ourSingleMapper = MakeMapper(contender, o.common.mapper);
  AddClipPlanes(ourSingleMapper, o.clipPlanes);
  Stage single(scene, property, ourSingleMapper, o.width, o.height, look);
  const Timed ourSingle = Time(single, ourSingleMapper, o);
  auto theirSingleMapper = MakeMapper(kind);
  single.SetMapper(theirSingleMapper, input);
  const Timed theirSingle = Time(single, theirSingleMapper, o);

  std::printf("\nEach mapper in VTK's default window (multisampled) and single-sampled, the "
              "camera turning before every frame (ms):\n| mapper | multisampled | "
              "single-sampled |\n|---|---:|---:|\n| MTPT | %s | %s |\n| %s | %s | %s |\n",
    Cell(ours, o).c_str(), Cell(ourSingle, o).c_str(), theirName, Cell(theirsDefault, o).c_str(),
    Cell(theirSingle, o).c_str());
  const double a = ours.moving.median, b = ourSingle.moving.median;
  const double c = theirsDefault.moving.median, d = theirSingle.moving.median;
  std::printf("%s in its faster window (%s, %s ms) / MTPT in its faster (%s, %s ms): MTPT %.2fx "
              "faster (multisampled %.2fx, single-sampled %.2fx)\n",
    theirName, WindowName(d >= c),
    FormatMs(d < c ? theirSingle.moving : theirsDefault.moving).c_str(), WindowName(b >= a),
    FormatMs(b < a ? ourSingle.moving : ours.moving).c_str(), std::min(c, d) / std::min(a, b),
    c / a, d / b);
}

} // namespace

int main(int argc, char** argv)
try
{
  Options o;
  CLI::App app{ "Renders an unstructured grid with vtkMultiThreadedProjectedTetrahedraMapper "
                "and times it, the camera turning before every timed frame. Non-tetrahedral "
                "cells are split with vtkDataSetTriangleFilter first." };
  app.add_option("input", o.input,
    "data set: .vtu, .vtk, or .vtm (multi-block; default: the embedded blunt fin)");
  app.add_option("--output", o.output, "PNG to write");
  app.add_option("--size", o.size, "window size, WxH (or one number for a square)");
  app.add_option("--array", o.array,
    "scalar array (default: the active point scalars, else the first array; vectors by "
    "magnitude)");
  app.add_option("--azimuth", o.view.azimuth, "camera azimuth, degrees");
  app.add_option("--elevation", o.view.elevation, "camera elevation, degrees");
  app.add_option("--zoom", o.view.zoom, "camera zoom")->check(CLI::PositiveNumber);
  app.add_flag("--parallel", o.view.parallel, "parallel projection (default perspective)");
  app
    .add_option("--tf", o.tf,
      "transfer function: structure (perceptual map, inner shells), smooth (cool-warm "
      "ramp) or bands (narrow opacity peaks)")
    ->check(CLI::IsMember({ "structure", "smooth", "bands" }));
  app.add_option("--background", o.background, "dark or white")
    ->check(CLI::IsMember({ "dark", "white" }));
  app.add_option(
    "--unit-distance", o.unitDistance, "ScalarOpacityUnitDistance (default: the diagonal / 40)");
  app.add_option("--backend", o.backend, "how triangles reach the screen")
    ->check(CLI::IsMember({ "auto", "gl", "cpu" }));
  o.common.timing.repeat = 5;
  app.add_option("--frames", o.common.timing.repeat, "timed frames (medians are printed)")
    ->check(CLI::PositiveNumber);
  app.add_option("--step", o.common.timing.step,
    "degrees the camera turns before every timed frame (0: an unchanged view)");
  app.add_option("--threads", o.common.mapper.threads, "threads for the CPU stages (0: all)")
    ->check(CLI::NonNegativeNumber);
  app.add_option("--order", o.common.mapper.order, "visibility order")
    ->check(CLI::IsMember({ "radix", "partition" }));
  app.add_option("--shading", o.common.mapper.shading, "VTK-compatible or pre-integrated shading")
    ->check(CLI::IsMember({ "vtk", "pre-integrated" }));
  app.add_option("--blend-mode", o.common.mapper.blend,
    "composite; maximum or minimum intensity; average intensity; additive (VTK's blend modes; "
    "VTK's PT composites in --compare-vtk)")
    ->check(CLI::IsMember(BlendModeNames()));
  AddMemoryOptions(app, o.common.mapper);
  app.add_flag("--shade", o.shade,
    "light the volume by the renderer's headlight, as VTK's GPU ray caster lights image data "
    "(VTK's PT ignores it in --compare-vtk)");
  app.add_option("--ambient", o.ambient, "shading: ambient coefficient")
    ->check(CLI::Range(0.0, 1.0));
  app.add_option("--diffuse", o.diffuse, "shading: diffuse coefficient")
    ->check(CLI::Range(0.0, 1.0));
  app.add_option("--specular", o.specular, "shading: specular coefficient")
    ->check(CLI::Range(0.0, 1.0));
  app.add_option("--specular-power", o.specularPower, "shading: specular exponent")
    ->check(CLI::NonNegativeNumber);
  app.add_flag("--compare-vtk", o.compare,
    "also time vtkProjectedTetrahedraMapper (for a .vtm: "
    "vtkMultiBlockUnstructuredGridVolumeMapper), "
    "both mappers multisampled (VTK's default window) and single-sampled, the ratio taking each "
    "in its faster window, and write <output>-vtkpt.png and <output>-side-by-side.png");
  app.add_flag("--compare-merged", o.compareMerged,
    "for a .vtm: also time MTPT on the blocks appended into one grid");
  app.add_flag("--reference", o.reference,
    "render the exact ray-integral reference and print each image's error against it");
  app.add_flag("--interactive", o.interactive, "open a window instead of only writing the PNG");
  app
    .add_option("--update-rate", o.updateRate,
      "with --interactive: frames a second asked for while the mouse drags the view (VTK's "
      "interactor asks for 15); the volume is drawn with a fraction of its cells at a coarser "
      "image sample distance to keep up (AutoAdjustCellFraction, AutoAdjustSampleDistances) "
      "and in full when the mouse is released; 0: always in full")
    ->check(CLI::NonNegativeNumber);
  auto* distance = app
                     .add_option("--image-sample-distance", o.common.mapper.imageSampleDistance,
                       "a fixed image sample distance: one sample per D x D pixels, "
                       "stretched over the window (turns the automatic adjustment off)")
                     ->check(CLI::Range(0.1, 100.0));
  app.add_option("--clip-plane", o.clipPlanes,
    "a clipping plane ox,oy,oz,nx,ny,nz in world coordinates, keeping the side the normal "
    "points to (repeatable; VTK's PT ignores them in --compare-vtk)");
  CLI11_PARSE(app, argc, argv);
  // Automatic adjustment unless a fixed distance is asked for; frames of a window at VTK's
  // default (still) update rate are drawn in full either way.
  o.common.mapper.autoAdjust = distance->count() == 0 && o.updateRate > 0;
  if (!ParseSize(o.size, o.width, o.height))
  {
    std::fprintf(
      stderr, "mtpt_render: --size takes WxH with positive numbers, not '%s'\n", o.size.c_str());
    return 2;
  }

  Scene scene;
  std::string error;
  if (!LoadSceneFile(o.input, o.array, scene, error))
  {
    std::fprintf(stderr, "mtpt_render: %s\n", error.c_str());
    return 1;
  }
  std::printf("%s: %s%lld points, %lld tetrahedra, %s scalars '%s' in [%g, %g]\n", o.input.c_str(),
    scene.blocks ? "blocks of " : "", static_cast<long long>(scene.grid->GetNumberOfPoints()),
    static_cast<long long>(scene.grid->GetNumberOfCells()), scene.cellScalars ? "cell" : "point",
    scene.arrayName.c_str(), scene.range[0], scene.range[1]);
  auto property = MakeTransferFunctions(o, scene.range, scene.grid->GetLength());

  StageOptions look;
  look.view = o.view;
  look.onScreen = o.interactive;
  if (o.background == "dark")
  {
    std::fill(look.background, look.background + 3, 0.06);
  }
  const char* contender =
    o.backend == "cpu" ? "mtpt-cpu" : (o.backend == "gl" ? "mtpt-gl" : "mtpt");
  auto mapper = MakeMapper(contender, o.common.mapper);
  if (!AddClipPlanes(mapper, o.clipPlanes))
  {
    return 2;
  }
  Stage stage(scene, property, mapper, o.width, o.height, look);

  // The picture, at the start view.
  stage.Frame();
  auto ours = stage.Image();
  WritePNG(ours, o.output);
  vtkNew<vtkMTPTReferenceRenderer> exact;
  if (o.reference)
  {
    if (!exact->Render(stage.GetRenderer(), stage.GetVolume()))
    {
      return 1;
    }
    std::printf("exact reference: %.1f s, %lld ray segments%s\n", exact->GetRenderSeconds(),
      static_cast<long long>(exact->GetNumberOfSegments()),
      exact->GetExactTransferFunctions() ? "" : " (transfer functions sampled)");
    PrintError("MTPT", exact, stage.GetRenderer());
    WritePNG(ReferenceImage(exact), Sibling(o.output, "-reference.png"));
  }

  const Timed t = Time(stage, mapper, o);
  const StageFigures& f = t.figures;
  std::printf("\nMTPT, %s backend, %s shading, %s blending%s, %s order, %d threads requested "
              "(0: all), %dx%d; median of %d frames, the camera turning %.2f degrees before "
              "each (ms; CPU stages include lighting the cells when shaded):\n",
    f.backend.c_str(), o.common.mapper.shading.c_str(), o.common.mapper.blend.c_str(),
    o.shade ? ", lit by the headlight" : "", o.common.mapper.order.c_str(),
    o.common.mapper.threads, o.width, o.height, o.common.timing.repeat, o.common.timing.step);
  std::printf("| transform | cull | depth keys | order | decompose | CPU stages | composite (bin "
              "+ raster) | upload | draw | frame |%s\n",
    o.unchanged ? " frame, unchanged view |" : "");
  std::printf(
    "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|%s\n", o.unchanged ? "---:|" : "");
  std::printf(
    "| %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f (%.1f + %.1f) | %.1f | %.1f | %s |%s\n",
    f.transform, f.cull, f.keys, f.order, f.decompose, f.cpuStages, f.composite, f.bin, f.raster,
    f.upload, f.draw, FormatMs(t.moving).c_str(),
    o.unchanged ? (" " + FormatMs(t.unchanged) + " |").c_str() : "");

  if (o.compareMerged && scene.blocks)
  {
    auto merged = MakeMapper(contender, o.common.mapper);
    stage.SetMapper(merged, scene.grid);
    stage.StartView();
    stage.Frame();
    if (o.reference)
    {
      PrintError("MTPT on the blocks appended", exact, stage.GetRenderer());
    }
    const Timed m = Time(stage, merged, o);
    std::printf(
      "MTPT on the blocks appended into one grid: %s ms per frame\n", FormatMs(m.moving).c_str());
    stage.SetMapper(mapper, scene.blocks);
  }

  if (o.compare)
  {
    CompareWithVTK(stage, scene, property, mapper, ours, t, o, exact);
  }

  if (o.interactive)
  {
    Interact(stage, Mapper::SafeDownCast(mapper), o.common.mapper.autoAdjust ? o.updateRate : 0);
  }
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_render", error);
}
