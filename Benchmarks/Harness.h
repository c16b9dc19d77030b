// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Harness.h
 * @brief What every benchmark program shares: scenes and windows, the camera path, the
 * contenders (MTPT's backends and VTK's unstructured-grid mappers), frame timing with
 * correct medians, image errors, and command-line options (CLI11).
 *
 * The rules every figure follows:
 * - Windows are as VTK makes them by default (multisampled; off-screen), for every mapper,
 *   and, where a benchmark asks for it, also with multisampling off
 *   (vtkRenderWindow::SetMultiSamples(0)): a mapper's time depends on it (on Mesa llvmpipe
 *   VTK's PT takes about twice as long multisampled), so every contender is timed in both
 *   kinds of window and a ratio between two mappers takes each at its faster one
 *   (FasterWindow).
 * - Timed frames move the camera: before every frame (the warm-up frame included) it turns
 *   by a small azimuth step (FrameTiming::step, 1 degree unless an option says otherwise),
 *   so that no mapper re-uses a previous frame's result. Frames with an unchanged view are
 *   timed separately and labelled so.
 * - A frame is vtkRenderWindow::Render followed by WaitForCompletion (the rasterizer done).
 * - The result of N frames is their median (the mean of the two middle values for even N);
 *   per-stage figures are those of the frame whose time is that median (the lower of the
 *   two middle frames for even N), so stage times add up to a frame that happened.
 * - VTK's ray caster and Z-sweep use a fixed image sample distance of 1 (auto-adjustment
 *   off), so every mapper draws every pixel; so does MTPT unless its settings ask for
 *   another distance, or for automatic adjustment with a desired update rate (then the
 *   window asks for that rate, as an interactor does while the user drags, and warm-up
 *   frames let the distance settle before the timed ones).
 */
#ifndef mtpt_bench_Harness_h
#define mtpt_bench_Harness_h

#include "DataFolder.h"
#include "Statistics.h"

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkImageData.h"            // Measurement holds images
#include "vtkNew.h"
#include "vtkSmartPointer.h"

#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace CLI
{
class App;
}

VTK_ABI_NAMESPACE_BEGIN
class vtkAbstractVolumeMapper;
class vtkCallbackCommand;
class vtkDataObject;
class vtkRenderWindow;
class vtkRenderer;
class vtkUnstructuredGrid;
class vtkUnstructuredGridVolumeMapper;
class vtkVolume;
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{
namespace bench
{

/// A benchmark scene: a grid of tetrahedra and the scalar range its transfer function spans.
struct Scene
{
  std::string name;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  double range[2] = { 0, 1 };
  std::shared_ptr<void> storage; ///< arrays the grid uses in place, if not VTK's own
  std::string arrayName;         ///< the scalars coloured by
  bool cellScalars = false;      ///< one value per cell rather than per point
  /// A composite data set (a multi-block file): drawn instead of `grid` by the mappers that
  /// take one (MTPT, VTK's multi-block mapper); `grid` then holds its blocks appended.
  vtkSmartPointer<vtkDataObject> blocks;
  /// The same field as image data, for the scenes made from one (the wavelet): what VTK's
  /// GPU ray caster draws (DrawsImageData). Null for the others.
  vtkSmartPointer<vtkImageData> image;
};

/**
 * Scenes by name: "wavelet" (vtkRTAnalyticSource over [-30, 30]^3 tetrahedralized:
 * 1,080,000 tetrahedra, with its image data), "grid:N" (a generated jittered grid of at least
 * N tetrahedra), "bluntfin" (the repository's data set, 187,395; from the data folder's
 * bluntfin/ when the repository is not at hand, as in the device kit), "cubes" (two cubes of
 * 5 tetrahedra, as VTK's small PT tests), "blocks" (a 10^3 block source of 6,000 tetrahedra,
 * as VTK's vector-component test), and the real meshes of a data folder ("comb", "kiefer",
 * "pulley", "fire_ug", "ironProt"; see `SharedDataSets`). Returns false with `error` set
 * when the name is unknown or its file cannot be read.
 */
bool LoadScene(
  const std::string& name, const std::string& dataFolder, Scene& scene, std::string& error);

/**
 * A scene from a VTK file (.vtu, or legacy .vtk of any data set), split into tetrahedra
 * (vtkDataSetTriangleFilter, every array passed), coloured by the array named `array`
 * (point data first, then cell data), else the active point scalars, else the first point
 * array, else the first cell array; that array is made the active scalars. A multi-block
 * file (.vtm) keeps its blocks (Scene::blocks), the array chosen in the first block with
 * cells and made active in every block. Returns false with `error` set when the file cannot
 * be read, holds no cells or no such array.
 */
bool LoadSceneFile(
  const std::string& path, const std::string& array, Scene& scene, std::string& error);

/// The benchmark's transfer functions: a cool-warm colour map and opacity rising linearly
/// over `range`, unit distance a fiftieth of the grid's diagonal.
vtkSmartPointer<vtkVolumeProperty> MakeProperty(const Scene& scene);

/// How MTPT's contenders are set up.
struct MapperSettings
{
  int threads = 0;               ///< 0: the default
  std::string shading = "vtk";   ///< "vtk" or "pre-integrated"
  std::string order = "radix";   ///< "radix" or "partition"
  /// "composite", "maximum", "minimum", "average" or "additive" (BlendModeNames)
  std::string blend = "composite";
  float imageSampleDistance = 1; ///< fixed, unless autoAdjust
  /// AutoAdjustSampleDistances and AutoAdjustCellFraction (off: every pixel and cell drawn)
  bool autoAdjust = false;
  long long batchSize = 1 << 20; ///< SetBatchSize (0: one batch)
  long long memoryLimitMiB = 0;  ///< SetMemoryLimit in MiB (0: the memory available)
};

/**
 * Contenders by name: "mtpt" (vtkMultiThreadedProjectedTetrahedraMapper choosing its
 * backend), "mtpt-cpu" and "mtpt-gl" (with the CPU or the OpenGL backend), "vtk-pt"
 * (vtkProjectedTetrahedraMapper), "vtk-multiblock" (vtkMultiBlockUnstructuredGridVolumeMapper:
 * VTK's PT block after block), "raycast" (vtkUnstructuredGridVolumeRayCastMapper) and
 * "zsweep" (vtkUnstructuredGridVolumeZSweepMapper). Null for an unknown name.
 */
vtkSmartPointer<vtkUnstructuredGridVolumeMapper> MakeMapper(
  const std::string& name, const MapperSettings& settings = {});

/**
 * Every contender of MakeMapper, and "gpu-raycast": VTK's GPU ray caster
 * (vtkGPUVolumeRayCastMapper, full resolution every frame) of the scene's image data, for
 * scale where a scene has one. Null for an unknown name.
 */
vtkSmartPointer<vtkAbstractVolumeMapper> MakeContender(
  const std::string& name, const MapperSettings& settings = {});

/// Whether contender `name` draws the scene's image data (Scene::image) instead of its grid.
bool DrawsImageData(const std::string& name);

/// OpenGL's vendor, renderer and version strings in a window as VTK makes it here.
struct OpenGLInfo
{
  std::string vendor, renderer, version;
};
OpenGLInfo QueryOpenGL();

/// The blend modes' names, in the order of their values (vtkVolumeMapper's enum).
const std::vector<std::string>& BlendModeNames();

/// Every contender name MakeContender knows.
const std::vector<std::string>& ContenderNames();

/// The camera of a stage's start view, after it is reset on the volume (VTK's default
/// direction, looking down -z).
struct View
{
  double azimuth = 30, elevation = 20; ///< degrees
  double zoom = 1;
  bool parallel = false; ///< orthographic instead of perspective
};

/// How a stage's window looks.
struct StageOptions
{
  View view;
  double background[3] = { 1, 1, 1 };
  bool onScreen = false; ///< a window on the display (default: off-screen)
  /// Frames a second the window asks for (vtkRenderWindow::SetDesiredUpdateRate, what an
  /// interactor sets while the user drags); 0: VTK's default (a still frame).
  double desiredUpdateRate = 0;
  /// VTK's default window (multisampled) if true; false: vtkRenderWindow::SetMultiSamples(0).
  bool multisampling = true;
};

/// How a window's kind is named in tables: "multisampled" (VTK's default) or
/// "single-sampled".
const char* WindowName(bool multisampling);

/**
 * The errors a mapper reported during a frame (vtkErrorMacro, VTK's ErrorEvent), thrown by
 * Stage::Frame once the frame is done, so that a program stops, writing nothing, instead of
 * going on with the frame's image. Programs catch it in main (ReportMapperError).
 */
struct MapperError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Prints `error` as `program: ...`, with what may avoid it, and returns the exit status (1).
int ReportMapperError(const char* program, const MapperError& error);

/// A volume in a renderer in a window as VTK makes it by default. Its input is the scene's
/// blocks for the mappers that take a composite data set, its image data for those that draw
/// image data, else its grid. The mapper's errors are printed as they come and fail the
/// frame (MapperError).
class Stage
{
public:
  Stage(const Scene& scene, vtkVolumeProperty* property, vtkAbstractVolumeMapper* mapper, int width,
    int height, const StageOptions& options = {});
  ~Stage();
  Stage(const Stage&) = delete; // its mapper's observer holds the address of Errors
  Stage& operator=(const Stage&) = delete;

  /// The starting view (StageOptions::view).
  void StartView();
  /// Turns the camera by `degrees` of azimuth about the volume.
  void Turn(double degrees);
  /// One frame: Render and WaitForCompletion; milliseconds. Throws MapperError when the mapper
  /// reported an error during it.
  double Frame();
  /// The window's RGB image as drawn by the last frame.
  vtkSmartPointer<vtkImageData> Image();
  /// Draws the volume with another mapper from now on, of `input` (null: the same input).
  void SetMapper(vtkAbstractVolumeMapper* mapper, vtkDataObject* input = nullptr);

  vtkRenderer* GetRenderer() { return this->Renderer; }
  vtkRenderWindow* GetWindow() { return this->Window; }
  vtkVolume* GetVolume() { return this->Volume; }

private:
  vtkNew<vtkVolume> Volume;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkRenderWindow> Window;
  vtkAbstractVolumeMapper* Mapper;
  View StartCamera;
  vtkNew<vtkCallbackCommand> ErrorWatch;    ///< observes the mapper's ErrorEvent
  unsigned long ErrorObserver = 0;          ///< its tag on the mapper
  std::vector<std::string> Errors;          ///< what the mapper reported since the last frame
};

/// The frames of one measurement.
struct FrameTiming
{
  std::vector<double> frames; ///< milliseconds of each timed frame
  double median = 0;          ///< their median
  std::size_t medianFrame = 0;
  bool slow = false; ///< the warm-up frame took longer than the slow limit: it is the result
};

/// How frames are timed (see the file comment).
struct TimingOptions
{
  int repeat = 5;          ///< timed frames
  double step = 1.0;       ///< degrees of azimuth before each frame; 0: unchanged view
  double slowLimit = 20.0; ///< seconds: a slower warm-up frame ends the measurement
  int warmUp = 1;          ///< untimed frames first (the camera turning before each too)
};

/**
 * Times frames of `stage` from its start view. `afterFrame(i)` runs after timed frame i
 * (to record a mapper's stage timers).
 */
FrameTiming TimeFrames(Stage& stage, const TimingOptions& options,
  const std::function<void(std::size_t)>& afterFrame = {});

/// Options every frame benchmark takes.
struct CommonOptions
{
  TimingOptions timing;
  MapperSettings mapper;        ///< MTPT's threads, shading, order and image sample distance
  std::string dataFolder;       ///< real meshes beyond the repository's (optional)
  double desiredUpdateRate = 0; ///< StageOptions::desiredUpdateRate of every measurement
  /// The kinds of window every contender is timed in (StageOptions::multisampling), in
  /// order: VTK's default (multisampled) and single-sampled unless --multisampling says.
  std::vector<bool> windows = { true, false };
  int rounds = 1; ///< times every measurement is repeated, contenders alternating
};

/// MTPT's timers and counters of one frame, milliseconds and counts (zero for VTK's
/// mappers).
struct StageFigures
{
  double transform = 0, cull = 0, keys = 0, order = 0, decompose = 0, cpuStages = 0;
  double composite = 0, bin = 0, raster = 0, upload = 0, draw = 0;
  double fragments = 0;
  long long sorted = 0, pixelCulled = 0;
  long long hidden = 0; ///< sorted, then left out behind opaque pixels (GetNumberOfHiddenCells)
  long long memoryBytes = 0;      ///< the mapper's buffers after the frame (GetMemoryBytes)
  double imageSampleDistance = 1; ///< the distance the frame was composited at
  int imageSize[2] = { 0, 0 };    ///< the composited image's size (ImageInUseSize)
  std::string backend;            ///< "CPU" or "OpenGL": the backend that drew
};

/// The figures of the last frame `mapper` drew.
StageFigures FiguresOf(vtkAbstractVolumeMapper* mapper);

/// The rasterization's nanoseconds per fragment drawn and core of `f` on `threads` threads;
/// 0 without fragments.
double NsPerFragmentCore(const StageFigures& f, int threads);

/// What one contender measured on one scene and window size.
struct Measurement
{
  FrameTiming moving;                  ///< the camera turning before every frame
  FrameTiming unchanged;               ///< the same view every frame (when asked for)
  vtkSmartPointer<vtkImageData> image; ///< at the end of the moving frames
  StageFigures mtpt;                   ///< MTPT's figures of the median moving frame
};

/**
 * Times contender `name` (MakeMapper with options.mapper) on `scene` in a width x height
 * window: moving frames, and with `unchanged` also frames of an unchanged view.
 */
Measurement Measure(const Scene& scene, vtkVolumeProperty* property, const std::string& name,
  int width, int height, const CommonOptions& options, bool unchanged = false,
  const StageOptions& stage = {});

/// A median as a table shows it ("12.3", "456", with "*" when one slow frame).
std::string FormatMs(const FrameTiming& t);

/// One contender's measurements in each kind of window (CommonOptions::windows), and which
/// of them was the faster: ratios between mappers take each at its faster window.
struct WindowMeasurements
{
  std::vector<bool> windows;             ///< multisampling of each entry
  std::vector<Measurement> measurements; ///< one per window
  /// The index of the faster window (smaller median moving frame); 0 when there is one.
  std::size_t Faster() const;
  const Measurement& Fastest() const { return this->measurements[this->Faster()]; }
  /// The measurement in the window of this kind, or null when it was not measured.
  const Measurement* In(bool multisampling) const;
};

/**
 * Times every contender of `names` (Measure) in every kind of window of options.windows,
 * options.rounds times: each round measures every contender in every window in turn, so
 * that other load on the machine falls on all of them alike. Each (contender, window)
 * result is its median round: the round whose median moving frame is the median of its
 * rounds (the lower middle one for an even count).
 */
std::map<std::string, WindowMeasurements> MeasureContenders(const Scene& scene,
  vtkVolumeProperty* property, const std::vector<std::string>& names, int width, int height,
  const CommonOptions& options, bool unchanged = false, const StageOptions& stage = {});

/// The median round of `rounds` (see MeasureContenders).
Measurement MedianRound(std::vector<Measurement> rounds);

/// "2218 (single-sampled 1006)": the median in the first window kind and in the others.
std::string FormatWindows(const WindowMeasurements& m);

/// A window size "512" (square) or "1920x1080"; false for anything else.
bool ParseSize(const std::string& text, int& width, int& height);

/// RMSE over RGB in [0, 1] and largest channel difference of two images of equal size.
struct ImageError
{
  double rmse = 1, worst = 1;
};
ImageError CompareImages(vtkImageData* a, vtkImageData* b);

/// Adds --batch-size and --memory-limit (MTPT's SetBatchSize and SetMemoryLimit) to `app`.
void AddMemoryOptions(CLI::App& app, MapperSettings& settings);
/// Adds --repeat, --rounds, --step, --slow-limit, --threads, --shading, --order,
/// --blend-mode, --batch-size, --memory-limit, --instruction-set, --data and
/// --multisampling to `app`.
void AddCommonOptions(CLI::App& app, CommonOptions& options);

/// Adds --image-sample-distance, --desired-update-rate and --warm-up to `app` (the frame
/// benchmark's); call ApplyImageSamplingOptions after parsing.
void AddImageSamplingOptions(CLI::App& app, CommonOptions& options);

/// After parsing: a desired update rate turns MTPT's automatic adjustment on (starting from
/// the distance given, 1 by default) with 10 warm-up frames unless --warm-up was given.
void ApplyImageSamplingOptions(CLI::App& app, CommonOptions& options);

/// A comma-separated list as its items ("a,b" -> {"a", "b"}).
std::vector<std::string> SplitList(const std::string& list);

/// Kilobytes from a /proc/self/status line ("VmRSS", "VmHWM"); -1 when it has none.
long StatusKiB(const char* field);

/// Resets the process's peak resident memory (VmHWM) to its current resident memory.
void ResetPeakMemory();

} // namespace bench
} // namespace mtpt

#endif
