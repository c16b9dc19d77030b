// SPDX-License-Identifier: BSD-3-Clause
// Scenes, rendering and image metrics shared by the mapper's image tests.
#ifndef mtpt_RenderingTestUtilities_h
#define mtpt_RenderingTestUtilities_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkCommand.h"
#include "vtkNew.h"
#include "vtkSmartPointer.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkDataObject;
class vtkMultiThreadedProjectedTetrahedraMapper;
class vtkUnstructuredGridBase;
class vtkActor;
class vtkImageData;
class vtkRenderWindow;
class vtkMTPTReferenceRenderer;
class vtkRenderer;
class vtkUnstructuredGrid;
class vtkUnstructuredGridVolumeMapper;
class vtkVolume;
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{
namespace rendering_test
{

/// n^3 cubes over [-1, 1]^3, 5 tetrahedra each, a smooth point scalar "field" and a cell
/// scalar "cellField" (its value at the cell centre).
vtkSmartPointer<vtkUnstructuredGrid> MakeTetrahedralBox(int n);

/// A real mesh: Data/bluntfin_tets.vtu (scalar "Density").
vtkSmartPointer<vtkUnstructuredGrid> LoadBluntFin();

/// Colour ramp and linearly rising opacity over [low, high].
vtkSmartPointer<vtkVolumeProperty> MakeProperty(double low, double high, double unitDistance);

/// For scalars in [0, 1]: transparent except for a narrow opacity peak (height 20) at 0.5,
/// of width 0.02 (on the box, about a fifth of the scalar step between vertices).
vtkSmartPointer<vtkVolumeProperty> MakeNarrowPeakProperty(double unitDistance);

/// The window a scene is drawn in. Tests run in the window VTK makes by default
/// (multisampled: VTK asks for 8 samples, Mesa grants 4), off-screen unless a test is about
/// on-screen windows; `multiSamples` 0 turns multisampling off, for tests about that setting.
struct WindowSettings
{
  bool offScreen = true;
  int multiSamples = -1; ///< -1: VTK's default
};

/// A camera direction: azimuth and elevation (degrees) from the default view along -z.
struct View
{
  double azimuth, elevation;
};

/// Directions from which a wrong visibility order shows: from +z (where a mesh stored
/// slab by slab is already nearly back to front), from -z and obliquely from above.
extern const View Views[3];

struct Scene
{
  vtkUnstructuredGrid* grid = nullptr;
  vtkSmartPointer<vtkVolumeProperty> property;
  bool perspective = true;
  int size = 200;
  double azimuth = 30, elevation = 20;
  WindowSettings window;
  /// Called with the volume and renderer before rendering (transform, extra actors...).
  std::function<void(vtkVolume*, vtkRenderer*)> customize;

  Scene From(const View& view) const
  {
    Scene s = *this;
    s.azimuth = view.azimuth;
    s.elevation = view.elevation;
    return s;
  }
};

/// The scene of `grid` with `property`, from the first of Views.
inline Scene MakeScene(
  vtkUnstructuredGrid* grid, vtkSmartPointer<vtkVolumeProperty> property, bool perspective)
{
  Scene s;
  s.grid = grid;
  s.property = std::move(property);
  s.perspective = perspective;
  return s;
}

/// The blunt fin's transfer functions: colour ramp and rising opacity over its density.
vtkSmartPointer<vtkVolumeProperty> MakeBluntFinProperty();

/// A volume drawn by a mapper, in a renderer with the tests' background, in a window.
struct Stage
{
  vtkSmartPointer<vtkVolume> volume;
  vtkSmartPointer<vtkRenderer> renderer;
  vtkSmartPointer<vtkRenderWindow> window;
};

/// `input` (a grid, or a composite data set of grids) drawn by `mapper` with `property` in a
/// `width` x `height` window (not rendered).
Stage MakeStage(vtkDataObject* input, vtkVolumeProperty* property,
  vtkUnstructuredGridVolumeMapper* mapper, int width, int height, WindowSettings window = {});

/// Points the renderer's camera at its props from `view` (after ResetCamera).
void SetView(vtkRenderer* renderer, const View& view, bool perspective);

/// A copy of `grid` with its cells stored in a random order (cell data follows), so that
/// storage order says nothing about visibility order.
vtkSmartPointer<vtkUnstructuredGrid> ShuffleCells(vtkUnstructuredGrid* grid, unsigned seed);

/// The stage of `scene` with its camera set, rendered `frames` times (what Render draws).
Stage RenderStage(const Scene& scene, vtkUnstructuredGridVolumeMapper* mapper, int frames = 1);

/// Renders `scene` with `mapper` offscreen and returns the RGB image. `frames` > 1 renders
/// again before reading back (catches state carried between frames).
vtkSmartPointer<vtkImageData> Render(
  const Scene& scene, vtkUnstructuredGridVolumeMapper* mapper, int frames = 1);

/**
 * The exact reference image (vtkMTPTReferenceRenderer) of the stage's volume as its
 * renderer shows it (of `input` instead of the mapper's input, when given), rounded to 8-bit
 * RGB like a window's pixels; null (and a gtest failure) if it cannot be computed.
 */
vtkSmartPointer<vtkImageData> ReferenceImage(
  const Stage& stage, vtkUnstructuredGridBase* input = nullptr);

/// The exact reference of every visible volume of `renderer` integrated together
/// (vtkMTPTReferenceRenderer::RenderVolumes), rounded as ReferenceImage's.
vtkSmartPointer<vtkImageData> VolumesReferenceImage(vtkRenderer* renderer);

/// The last image of `reference`, rounded to 8-bit RGB like a window's pixels.
vtkSmartPointer<vtkImageData> ImageOf(vtkMTPTReferenceRenderer* reference);

/// The RGB back buffer of a rendered window. `rerender` renders again first (the default
/// of vtkWindowToImageFilter); that render may use a slightly different aspect ratio, so
/// tests of frame-to-frame reuse read the buffer as it is.
vtkSmartPointer<vtkImageData> Grab(vtkRenderWindow* window, bool rerender = true);

struct ImageDifference
{
  double rmse = 0;         ///< root mean square over RGB in [0, 1], all pixels
  double coveredRmse = 0;  ///< the same over the pixels the volume covers in either image
  double worst = 0;        ///< largest channel difference in [0, 1]
  double fractionOver = 0; ///< fraction of the covered pixels with a channel difference > 0.1
  double covered = 0;      ///< fraction of all pixels covered in either image
};
/// Differences of two RGB images; "covered" means differing from `background` by more than
/// 2/255 in some channel.
ImageDifference Compare(vtkImageData* a, vtkImageData* b, const double* background = nullptr);

/// Bounds on an ImageDifference.
struct Limits
{
  double coveredRmse = 1, worst = 1, fractionOver = 1;
};

/// Prints the difference of `ours` and `theirs` under `label` and checks it against the
/// limits (a gtest failure per bound exceeded), and that `ours` is not blank (at least
/// `minCovered` of its pixels covered).
void ExpectClose(vtkImageData* ours, vtkImageData* theirs, const Limits& limits,
  const std::string& label, double minCovered = 0.05, const double* background = nullptr);

/// Fraction of pixels that differ from the background colour by more than 2/255.
double CoveredFraction(vtkImageData* image, const double background[3]);

/// Background of every scene (the default of Compare and ExpectClose).
extern const double Background[3];

/// Baseline comparison: Testing/Data/Baseline/<name>.png. With MTPT_UPDATE_BASELINES=1 in
/// the environment the image is written there instead (and the comparison passes).
ImageDifference CompareWithBaseline(vtkImageData* image, const std::string& name);

/// Writes the image next to the test binary (for inspection after a failure).
void Save(vtkImageData* image, const std::string& name);

/// A mapper drawing through `backend` (vtkMultiThreadedProjectedTetrahedraMapper's constants).
vtkSmartPointer<vtkMultiThreadedProjectedTetrahedraMapper> MakeMapper(int backend);

/// "cpu" or "gl", for image names.
const char* ShortBackendName(int backend);

/**
 * The image of `stage`'s window with a fresh mapper of `under`'s input drawing the volume
 * (after `setUp` configures it), in the same window and state; `under` draws the volume
 * again afterwards.
 */
vtkSmartPointer<vtkImageData> FreshMapperImage(const Stage& stage,
  vtkMultiThreadedProjectedTetrahedraMapper* under,
  const std::function<void(vtkMultiThreadedProjectedTetrahedraMapper*)>& setUp);

/// "CPU", "OpenGL" or "automatic", for messages.
const char* BackendName(int backend);

/// The two backends, CPU first.
extern const int Backends[2];

/// Where VTK's PT draws the image this mapper's is compared with.
enum class TheirWindow
{
  /// Without multisampling: in a multisampled window VTK's PT speckles along cell edges (it
  /// shades fragments of triangles that cover a sample but not the pixel centre with
  /// extrapolated thicknesses; TestMapperWindows.cxx measures it), which no bound on the
  /// worst pixel would survive.
  SingleSampled,
  /// The window this mapper draws in (VTK's default), for scenes with opaque geometry,
  /// whose antialiased edges differ from a single-sampled window's by up to 0.6.
  Same
};

/**
 * Renders `scene` from every direction of Views with VTK's PT and with this mapper through
 * each backend (in VTK's default window), saves the images, and checks the differences.
 */
void ExpectCloseToVTK(const Scene& scene, const std::string& name, const Limits& limits,
  TheirWindow window = TheirWindow::SingleSampled);

/**
 * Renders `scene` from every direction of Views with this mapper through each backend, in
 * `shading`, and checks the images against the exact ray integral of the same view.
 */
void ExpectCloseToReference(
  const Scene& scene, const std::string& name, const Limits& limits, int shading);

/// Collects error and warning events of one object.
class MessageObserver : public vtkCommand
{
public:
  static MessageObserver* New() { return new MessageObserver; }
  void Execute(vtkObject*, unsigned long event, void* data) override;
  std::vector<std::string> errors, warnings;
  void Clear()
  {
    errors.clear();
    warnings.clear();
  }
};

/// Adds an opaque cube [-h, h]^3 (VTK's default surface colour and lighting) to `renderer`.
void AddOpaqueCube(vtkRenderer* renderer, double h);

/**
 * A fixture whose tests take the backend as their parameter and share one grid, `Box`: the
 * box of 10 x 10 x 10 cubes split into tetrahedra (MakeTetrahedralBox), its cells shuffled.
 */
class ShuffledBoxTest : public ::testing::TestWithParam<int>
{
protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  static vtkSmartPointer<vtkUnstructuredGrid> Box;
};

} // namespace rendering_test
} // namespace mtpt

#endif
