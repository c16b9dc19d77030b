// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMultiThreadedProjectedTetrahedraMapper
 * @brief   Multi-threaded projected tetrahedra: a drop-in replacement for
 *          vtkProjectedTetrahedraMapper.
 *
 * Renders an unstructured grid, or a composite data set of them, with the projected
 * tetrahedra algorithm as Fan et al. parallelize it (J. Visualization 24, 2021): per frame
 * the cells are sorted back to front on NumberOfThreads OpenMP threads and each tetrahedron
 * is decomposed into 4 triangles at a fixed stride, identical for any thread count. The
 * OpenGL backend draws them blended; the CPU backend composites them in screen tiles with
 * SIMD instructions, and is chosen automatically where OpenGL is a software rasterizer.
 * Both work in every window VTK makes (multisampled or not, on- or off-screen) and in VTK's
 * depth peeling of volumes.
 *
 * Scalar selection and vtkVolumeProperty mean what they mean for
 * vtkProjectedTetrahedraMapper; other cells are split into tetrahedra. Where the images
 * differ, this mapper's is the more accurate (exact segment lengths, no 8-bit colours, cells
 * cut at the near plane); PRE_INTEGRATED_SHADING integrates the transfer functions exactly
 * along each fragment's segment. The mapper's clipping planes (world coordinates, up to 8)
 * cut each fragment's segment exactly. Cells that cannot show are culled before the sort, and
 * results are reused while their inputs are unchanged. While the view moves, the image
 * sample distance and the fraction of the cells drawn adjust to the time VTK allots; a
 * still frame is the full image.
 *
 * Blend modes 0 to 4 as VTK's GPU ray caster defines them; maximum and minimum intensity,
 * average and additive frames need no order and sort nothing. The property's shading lights
 * the volume by the renderer's lights, each tetrahedron at its centroid, as VTK's GPU ray
 * caster lights a sample. Documentation/mapper.md explains each of these in full.
 *
 * @sa vtkProjectedTetrahedraMapper vtkUnstructuredGridVolumeMapper
 */
#ifndef vtkMultiThreadedProjectedTetrahedraMapper_h
#define vtkMultiThreadedProjectedTetrahedraMapper_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "vtkRenderingMTPTModule.h" // for export macro
#include "vtkUnstructuredGridVolumeMapper.h"

#include <cstddef> // for std::size_t
#include <memory>  // for std::unique_ptr
#include <vector>  // for std::vector

VTK_ABI_NAMESPACE_BEGIN
class vtkOpenGLRenderWindow;
class vtkRenderWindow;
class vtkUnstructuredGridBase;
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END
namespace mtpt
{
struct BackendFrame;
struct FrameFacts;
struct FrameInput;
struct FramePlan;
struct FrameSettings;
struct GroupedVolume;
class RenderBackend;
}

class VTKRENDERINGMTPT_EXPORT vtkMultiThreadedProjectedTetrahedraMapper
  : public vtkUnstructuredGridVolumeMapper
{
public:
  static vtkMultiThreadedProjectedTetrahedraMapper* New();
  vtkTypeMacro(vtkMultiThreadedProjectedTetrahedraMapper, vtkUnstructuredGridVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Visibility-order implementations (see mtpt/VisibilityOrder.h).
  enum OrderMethods
  {
    PARTITION_SORT = 0, ///< the paper's Algorithm 1: sequential partition, parallel sorts
    RADIX_SORT = 1      ///< parallel LSD radix sort: no sequential phase (default)
  };

  /// How the sorted triangles reach the framebuffer.
  enum Backends
  {
    AUTOMATIC_BACKEND = 0, ///< CPU compositor on software OpenGL, OpenGL otherwise (default)
    OPENGL_BACKEND = 1,    ///< upload and draw with OpenGL blending
    CPU_BACKEND = 2        ///< the multi-threaded CPU compositor
  };

  ///@{
  /// Backend selection, and the backend the last Render used.
  vtkSetClampMacro(Backend, int, AUTOMATIC_BACKEND, CPU_BACKEND);
  vtkGetMacro(Backend, int);
  void SetBackendToAutomatic() { this->SetBackend(AUTOMATIC_BACKEND); }
  void SetBackendToOpenGL() { this->SetBackend(OPENGL_BACKEND); }
  void SetBackendToCPU() { this->SetBackend(CPU_BACKEND); }
  int GetLastBackend();
  const char* GetBackendAsString();
  ///@}

  /// True if `renderer` names a software rasterizer (llvmpipe, softpipe, SWR, swrast).
  static bool IsSoftwareRenderer(const char* renderer);

  ///@{
  /**
   * Number of OpenMP threads for the CPU stages. 0 (the default) chooses as the class
   * documentation says (OMP_NUM_THREADS, or the node's cores shared among MPI ranks).
   * Negative values are rejected with a warning and leave the setting unchanged.
   */
  void SetNumberOfThreads(int threads);
  vtkGetMacro(NumberOfThreads, int);
  /// The thread count the next frame uses (NumberOfThreads, or the default for 0).
  int GetEffectiveNumberOfThreads();
  ///@}

  ///@{
  /**
   * Visibility-order implementation. The order itself (back to front, ties by cell id) is
   * the same for every method; only its speed differs.
   */
  vtkSetClampMacro(OrderMethod, int, PARTITION_SORT, RADIX_SORT);
  vtkGetMacro(OrderMethod, int);
  void SetOrderMethodToPartitionSort() { this->SetOrderMethod(PARTITION_SORT); }
  void SetOrderMethodToRadixSort() { this->SetOrderMethod(RADIX_SORT); }
  const char* GetOrderMethodAsString();
  ///@}

  enum ShadingModes
  {
    /// As vtkProjectedTetrahedraMapper: colour and attenuation classified at the vertices
    /// (the mean of front and back at the thick vertex) and interpolated, with VTK's
    /// alpha/beta slip fixed and float colours (default).
    VTK_COMPATIBLE_SHADING = 0,
    /// The front scalar, back scalar and segment length are interpolated and each fragment
    /// is shaded by pre-integration over them (integral functions of the transfer
    /// functions, exact optical depth): features of the transfer functions between vertex
    /// values are not missed, and interpolates perspective-exactly. See
    /// mtpt::PreIntegrationTable; its accuracy: Documentation/accuracy.md; its cost on the
    /// CPU backend: Documentation/compositor.md, "Pre-integrated shading at the fast mode's
    /// price".
    PRE_INTEGRATED_SHADING = 1
  };

  ///@{
  /**
   * How fragments are classified: VTK_COMPATIBLE_SHADING (default) or
   * PRE_INTEGRATED_SHADING. Both backends give the same image for either mode.
   */
  vtkSetClampMacro(ShadingMode, int, VTK_COMPATIBLE_SHADING, PRE_INTEGRATED_SHADING);
  vtkGetMacro(ShadingMode, int);
  void SetShadingModeToVTKCompatible() { this->SetShadingMode(VTK_COMPATIBLE_SHADING); }
  void SetShadingModeToPreIntegrated() { this->SetShadingMode(PRE_INTEGRATED_SHADING); }
  const char* GetShadingModeAsString();
  ///@}

  /// The blend modes beyond vtkUnstructuredGridVolumeMapper's two, with the values of
  /// vtkVolumeMapper's (COMPOSITE_BLEND 0 and MAXIMUM_INTENSITY_BLEND 1 are inherited).
  enum MoreBlendModes
  {
    MINIMUM_INTENSITY_BLEND = 2,
    AVERAGE_INTENSITY_BLEND = 3,
    ADDITIVE_BLEND = 4
  };

  ///@{
  /**
   * Blend modes as VTK's GPU ray caster defines them (SetBlendMode, inherited, takes 0 to 4;
   * Documentation/blend-modes.md): maximum and minimum intensity show the transfer functions
   * at the largest and smallest scalar along each ray; average intensity the mean of
   * opacity times the normalized scalar where the scalar lies in AverageIPScalarRange;
   * additive its integral per ScalarOpacityUnitDistance. Each is computed exactly along each
   * fragment's segment, and none needs the visibility order: their frames sort nothing.
   */
  void SetBlendModeToMinimumIntensity() { this->SetBlendMode(MINIMUM_INTENSITY_BLEND); }
  void SetBlendModeToAverageIntensity() { this->SetBlendMode(AVERAGE_INTENSITY_BLEND); }
  void SetBlendModeToAdditive() { this->SetBlendMode(ADDITIVE_BLEND); }
  const char* GetBlendModeAsString();
  vtkSetVector2Macro(AverageIPScalarRange, double);
  vtkGetVectorMacro(AverageIPScalarRange, double, 2);
  ///@}

  ///@{
  /// Sub-array threshold MAX of the partition sort (default 32768, at least 16).
  vtkSetClampMacro(MaxSubArraySize, vtkIdType, 16, VTK_ID_MAX);
  vtkGetMacro(MaxSubArraySize, vtkIdType);
  ///@}

  ///@{
  /**
   * Blend into a 32-bit float framebuffer when the context supports it (default on), as
   * vtkProjectedTetrahedraMapper does, so that thousands of thin layers do not lose
   * precision to 8-bit rounding at every blend.
   */
  vtkSetMacro(UseFloatingPointFrameBuffer, bool);
  vtkGetMacro(UseFloatingPointFrameBuffer, bool);
  vtkBooleanMacro(UseFloatingPointFrameBuffer, bool);
  ///@}

  ///@{
  /// Wait for OpenGL after the upload and after the draw so their timers are exact.
  vtkSetMacro(SynchronizedTiming, bool);
  vtkGetMacro(SynchronizedTiming, bool);
  vtkBooleanMacro(SynchronizedTiming, bool);
  ///@}

  ///@{
  /// Seconds spent by the last Render in each stage (0 before the first).
  double GetTransformSeconds();
  /// Opacity culling: cell scalar ranges and the visible-cell list, and the level of
  /// detail's subset of it (0 when reused).
  double GetCullSeconds();
  double GetDepthKeySeconds();
  double GetOrderSeconds();
  double GetDecomposeSeconds();
  /// Shading: lighting the drawn cells (0 unshaded).
  double GetLightingSeconds();
  /// OpenGL backend: buffer upload. CPU backend: depth read-back and image upload.
  double GetUploadSeconds();
  /// OpenGL backend: the draw call. CPU backend: the quad that blends the image in.
  double GetDrawSeconds();
  /// CPU backend: compositing on the CPU (0 with the OpenGL backend).
  double GetCompositeSeconds();
  /// CPU backend: the part of compositing that sorts fans into screen tiles.
  double GetBinSeconds();
  /// CPU backend: the part of compositing that sets up triangles and shades fragments.
  double GetRasterSeconds();
  /// transform + cull + depth keys + order + decompose
  double GetCPUStageSeconds();
  ///@}

  ///@{
  /**
   * Tetrahedra decomposed per batch (default 1,048,576: 168 MB of vertex and index
   * buffers). 0 decomposes and draws the whole mesh at once. Negative values are rejected
   * with a warning. With several batches an unchanged view still sorts nothing again, but
   * decomposes and uploads each batch again.
   */
  void SetBatchSize(vtkIdType size);
  vtkGetMacro(BatchSize, vtkIdType);
  ///@}

  ///@{
  /**
   * The most bytes the mapper's CPU buffers may hold (GetMemoryBytes). Before a frame
   * allocates them, an upper bound for the input's points and tetrahedra and the batch size
   * (mtpt::FramePipeline::BytesNeeded) is compared with it: a frame that would exceed it is
   * not drawn, and an error says what it needs and what to change. 0 (default): the physical
   * memory available when the frame starts, plus what the buffers hold already. Negative
   * values are rejected with a warning.
   */
  void SetMemoryLimit(vtkIdType bytes);
  vtkGetMacro(MemoryLimit, vtkIdType);
  ///@}

  ///@{
  /**
   * Cull cells that cannot change the image (default on): fully transparent, outside the
   * view volume, covering no pixel centre. Off draws every cell, for verification and
   * for measuring what culling saves; the image is the same.
   */
  vtkSetMacro(CullInvisibleCells, bool);
  vtkGetMacro(CullInvisibleCells, bool);
  vtkBooleanMacro(CullInvisibleCells, bool);
  ///@}

  ///@{
  /// Reuse stage results across frames when their inputs did not change (default on).
  vtkSetMacro(ReuseResults, bool);
  vtkGetMacro(ReuseResults, bool);
  vtkBooleanMacro(ReuseResults, bool);
  ///@}

  ///@{
  /**
   * Several volumes in one picture (default on). The visible volumes of a renderer whose
   * mappers are MTPT mappers with this on are drawn together: the first of them in the
   * renderer's order draws the cells of all of them in one visibility order, with its own
   * mapper's settings, each cell with its own volume's scalars, transfer functions, unit
   * distance and matrix, and the others draw nothing. Where their cells interleave in depth
   * the picture is then right, which drawing them one after the other (VTK's way) cannot
   * give. Volumes that differ in what one frame cannot mix (blend mode, shading mode,
   * clipping planes, lighting; Documentation/mapper.md, "Several volumes") are drawn one
   * after the other, with a warning once. Off: this volume is drawn by itself, as VTK draws
   * every volume.
   */
  vtkSetMacro(CompositeWithOtherVolumes, bool);
  vtkGetMacro(CompositeWithOtherVolumes, bool);
  vtkBooleanMacro(CompositeWithOtherVolumes, bool);
  ///@}

  ///@{
  /**
   * Sampling distance in the image, in pixels, as vtkUnstructuredGridVolumeRayCastMapper's:
   * 1 (the default) composites one sample per pixel; 2 one per 2 x 2 pixels (the image is
   * floor(viewport / 2) pixels on each side, stretched over the viewport with bilinear
   * filtering); 0.5 four per pixel (at most 4 x 4 per pixel, and at most the largest
   * texture of the OpenGL context, with a warning beyond). Clamped to [0.1, 100]; NaN is
   * rejected with a warning. With AutoAdjustSampleDistances on (the default) every Render
   * sets it from the time the renderer allots: set it with automatic adjustment off for a
   * fixed distance.
   */
  virtual void SetImageSampleDistance(float distance);
  vtkGetMacro(ImageSampleDistance, float);
  ///@}

  ///@{
  /**
   * The smallest image sample distance automatic adjustment chooses (default 1, the
   * full-resolution image); clamped to [0.1, 100]. Where it exceeds the maximum it wins.
   */
  virtual void SetMinimumImageSampleDistance(float distance);
  vtkGetMacro(MinimumImageSampleDistance, float);
  ///@}

  ///@{
  /// The largest image sample distance automatic adjustment chooses (default 10); clamped to
  /// [0.1, 100].
  virtual void SetMaximumImageSampleDistance(float distance);
  vtkGetMacro(MaximumImageSampleDistance, float);
  ///@}

  ///@{
  /**
   * Whether every Render adjusts ImageSampleDistance to the time the renderer allots the
   * volume (vtkVolume::GetAllocatedRenderTime, from the render window's desired update
   * rate), as vtkUnstructuredGridVolumeRayCastMapper does (default on): the distance is
   * scaled by sqrt(last frame's time / allotted time) and clamped to [minimum, maximum];
   * the first frame, never timed, is at the minimum. A frame stopped by the abort check
   * keeps the previous distance and is not timed. With it on, each frame waits for OpenGL
   * to finish (glFinish) before its time is taken, as VTK's GPU ray cast mapper does, so
   * that the time is that of the drawing and not of its submission.
   */
  vtkSetClampMacro(AutoAdjustSampleDistances, vtkTypeBool, 0, 1);
  vtkGetMacro(AutoAdjustSampleDistances, vtkTypeBool);
  vtkBooleanMacro(AutoAdjustSampleDistances, vtkTypeBool);
  ///@}

  ///@{
  /**
   * The fraction of the visible cells a frame draws, in (0, 1] (default 1, every cell).
   * Below 1 the frame draws an evenly spread subset of the cells, chosen from an importance
   * order computed once per input change, and scales every drawn cell's attenuation by the
   * inverse of the fraction drawn, so that the volume keeps its look at a fraction of the
   * per-cell work (Documentation/level-of-detail.md). Rounded down to a level 2^(-k/4).
   * Inside a depth-peeling pass every cell is drawn (as the image sample distance is 1).
   * With AutoAdjustCellFraction on (the default) every Render sets it from the time the
   * renderer allots: set it with automatic adjustment off for a fixed fraction.
   */
  vtkSetClampMacro(CellFraction, float, 0.001f, 1.0f);
  vtkGetMacro(CellFraction, float);
  ///@}

  ///@{
  /// The smallest cell fraction automatic adjustment chooses (default 0.05); clamped to
  /// [0.001, 1]. 1 turns the level of detail off.
  vtkSetClampMacro(MinimumCellFraction, float, 0.001f, 1.0f);
  vtkGetMacro(MinimumCellFraction, float);
  ///@}

  ///@{
  /**
   * Whether every Render adjusts CellFraction to the time the renderer allots the volume
   * (default on). With AutoAdjustSampleDistances on as well, one rule splits the time
   * between the two from the measured costs of the last frame: the per-cell CPU stages
   * scale with the fraction, the rest with the fraction and the image sample distance
   * (mtpt::ChooseDetail). A still frame (an allotment the full frame fits, as VTK's
   * StillUpdateRate gives) always draws every cell at the minimum distance: the same image
   * as a fresh mapper's.
   */
  vtkSetClampMacro(AutoAdjustCellFraction, vtkTypeBool, 0, 1);
  vtkGetMacro(AutoAdjustCellFraction, vtkTypeBool);
  vtkBooleanMacro(AutoAdjustCellFraction, vtkTypeBool);
  ///@}

  /// Visible cells the last Render left out for its level of detail.
  vtkIdType GetNumberOfCellsLeftOut();

  /// The size of the image the last Render composited the volume at: the viewport's at
  /// image sample distance 1, else floor(viewport / ImageSampleDistance) (0, 0 before any).
  vtkGetVectorMacro(ImageInUseSize, int, 2);

  /// Tetrahedra sorted and decomposed by the last Render (after culling).
  vtkIdType GetNumberOfTetrahedra();

  ///@{
  /// Cells the last Render culled before sorting them: fully transparent, outside the view
  /// volume, covering no pixel centre (the last also counts near-plane pieces culled when
  /// they were decomposed).
  vtkIdType GetNumberOfOpacityCulledCells();
  vtkIdType GetNumberOfFrustumCulledCells();
  vtkIdType GetNumberOfPixelCulledCells();
  ///@}

  ///@{
  /**
   * Cells the last Render cut by the camera's near plane, and the tetrahedra drawn in their
   * place (their visible parts; counted in GetNumberOfTetrahedra). vtkProjectedTetrahedraMapper
   * drops such cells whole, which leaves holes when the camera is near or inside the mesh.
   */
  vtkIdType GetNumberOfNearClippedCells();
  vtkIdType GetNumberOfNearClipPieces();
  ///@}

  /**
   * Tetrahedra the last Render sorted but did not decompose or draw: every pixel they cover
   * was opaque already. The CPU backend draws a frame of several batches (SetBatchSize)
   * front to back and leaves out the cells of later batches behind the pixels the earlier
   * ones made opaque, which changes no pixel. 0 with the OpenGL backend, in one batch, and
   * in blend modes other than composite.
   */
  vtkIdType GetNumberOfHiddenCells();

  /**
   * How many times the mapper has split its input into tetrahedra. Grids with other cells
   * (hexahedra, voxels, wedges, pyramids, polyhedra, higher-order or mixed) are split by
   * vtkDataSetTriangleFilter once per change of the input (its MTime), not every frame;
   * grids of tetrahedra only are used as they are and do not count.
   */
  vtkIdType GetNumberOfTetrahedralizations();

  /// Batches the last Render decomposed and drew.
  int GetNumberOfBatches();

  /// CPU backend: pixels the last Render's triangles covered and shaded (0 with OpenGL).
  vtkIdType GetNumberOfFragments();

  /// The instruction set of the CPU compositor's fragment loops here (e.g. "AVX2").
  static const char* GetCompositorInstructionSet();

  /// Whether the last Render was stopped by the render window's abort check.
  bool GetLastFrameStopped();

  /// What the last Render reused: a bitwise OR of the ReuseFlags.
  enum ReuseFlags
  {
    REUSED_TRANSFORM = 1,    ///< projected points of the previous frame
    REUSED_ORDER = 2,        ///< no key computed and nothing sorted
    ORDER_FROM_PREVIOUS = 4, ///< sorted starting from the previous order
    REUSED_DECOMPOSITION = 8, ///< no tetrahedron decomposed (and, in OpenGL, no upload)
    REUSED_IMAGE = 16, ///< CPU backend: nothing composited; the previous frame's image served
    /// The blend mode needs no order (maximum, minimum, average, additive): nothing sorted
    ORDER_NOT_NEEDED = 32
  };
  int GetLastFrameReuse();

  /// Bytes held by the mapper's CPU buffers (points, keys, order, one batch's buffers).
  vtkIdType GetMemoryBytes();
  /**
   * The bound the last frame's buffers were checked against (SetMemoryLimit): the most they
   * may take, with the near plane's pieces that frame cut. GetMemoryBytes() never exceeds
   * the largest bound of the frames drawn since the buffers were last freed.
   */
  vtkIdType GetMemoryBytesBound();

  /// Whether the mapper can render into this window (an OpenGL2 window).
  static bool IsSupported(vtkRenderWindow* window);

  void Render(vtkRenderer* renderer, vtkVolume* volume) override;

  ///@{
  /**
   * Bounds of the input's finite points (of every unstructured block of a composite input).
   * Points with a NaN or infinite coordinate are not drawn (the cells using them are
   * skipped, with a warning), and the bounds VTK computes for such a grid are uninitialized
   * or infinite, which would hide the volume or break the renderer's camera reset and
   * clipping range. Computed once per input change.
   */
  double* GetBounds() VTK_SIZEHINT(6) override;
  void GetBounds(double bounds[6]) override;
  ///@}
  void ReleaseGraphicsResources(vtkWindow* window) override;

protected:
  vtkMultiThreadedProjectedTetrahedraMapper();
  ~vtkMultiThreadedProjectedTetrahedraMapper() override;

  /// An unstructured grid or a composite data set (vtkDataObjectTree) of them.
  int FillInputPortInformation(int port, vtkInformation* info) override;

  int Backend = AUTOMATIC_BACKEND;
  int NumberOfThreads = 0;
  int OrderMethod = RADIX_SORT;
  int ShadingMode = VTK_COMPATIBLE_SHADING;
  double AverageIPScalarRange[2] = { VTK_DOUBLE_MIN, VTK_DOUBLE_MAX };
  vtkIdType MaxSubArraySize = 32768;
  bool UseFloatingPointFrameBuffer = true;
  bool SynchronizedTiming = false;
  vtkIdType BatchSize = 1 << 20;
  vtkIdType MemoryLimit = 0;
  bool ReuseResults = true;
  bool CompositeWithOtherVolumes = true;
  bool CullInvisibleCells = true;
  float ImageSampleDistance = 1.0f;
  float MinimumImageSampleDistance = 1.0f;
  float MaximumImageSampleDistance = 10.0f;
  vtkTypeBool AutoAdjustSampleDistances = 1;
  float CellFraction = 1.0f;
  float MinimumCellFraction = 0.05f;
  vtkTypeBool AutoAdjustCellFraction = 1;
  int ImageInUseSize[2] = { 0, 0 };

  ///@{
  /**
   * The time of the last frame this mapper drew `volume` in `renderer`, seconds (0 when it
   * has not), from which automatic adjustment scales the image sample distance; as
   * vtkUnstructuredGridVolumeRayCastMapper keeps it, per renderer and volume. Retrieve is
   * virtual so that a test can supply simulated frame times.
   */
  void StoreRenderTime(vtkRenderer* renderer, vtkVolume* volume, double seconds);
  virtual double RetrieveRenderTime(vtkRenderer* renderer, vtkVolume* volume);
  ///@}

  /**
   * Seconds the last frame spent in the CPU stages that follow the cells drawn (depth keys,
   * order, decomposition), in compositing (the CPU compositor's binning and rasterization;
   * -1 where not measured apart: OpenGL's drawing) and in work that follows the viewport
   * alone (read-back, magnification, write-back), from which automatic adjustment splits the
   * time between cell fraction and image sample distance (mtpt::ChooseDetail). Virtual so
   * that a test can supply simulated times.
   */
  virtual void RetrieveFrameCosts(
    double& cellSeconds, double& sampleSeconds, double& viewportSeconds);

  /// Seconds from the start of the last frame this mapper drew to the start of this one (0
  /// before the second), from which automatic adjustment estimates what the rest of each
  /// frame takes (mtpt::VolumeBudget). Virtual so that a test can supply simulated times.
  virtual double RetrieveFrameInterval();

private:
  vtkMultiThreadedProjectedTetrahedraMapper(
    const vtkMultiThreadedProjectedTetrahedraMapper&) = delete;
  void operator=(const vtkMultiThreadedProjectedTetrahedraMapper&) = delete;

  // The steps of Render: the glue between VTK, the core's frame pipeline and a backend.
  void MoveToWindow(vtkOpenGLRenderWindow* window);
  bool PrepareInput(const std::vector<mtpt::GroupedVolume>& group, vtkVolumeProperty* property,
    mtpt::FrameInput& frame);
  /**
   * What this frame draws for `volume` (CompositeWithOtherVolumes): its own input, or the
   * volumes drawn with it, this one first (`group`); false when another mapper of its group
   * draws it.
   */
  bool GroupVolumes(
    vtkRenderer* renderer, vtkVolume* volume, std::vector<mtpt::GroupedVolume>& group);
  bool DrawPrepared(vtkRenderer* renderer, vtkVolume* volume, vtkOpenGLRenderWindow* window,
    mtpt::FrameInput& frame);
  mtpt::RenderBackend* ChooseBackend();
  /// Sets an image sample distance setting, clamped to VTK's range; NaN is rejected.
  void SetDistance(const char* name, float distance, float& setting);
  /// Sets a count or size that must not be negative (Modified on a change); a negative
  /// `value` is rejected with a warning naming `setter`, `what` it is and `zero`'s meaning.
  template <typename T>
  void SetNonNegative(const char* setter, const char* what, const char* zero, T value, T& setting);
  /// Sets ImageSampleDistance and CellFraction for the next frame from the time allotted.
  void AdjustDetail(vtkRenderer* renderer, vtkVolume* volume);
  /// The frame's view, its plan (mtpt::PlanFrame, whose notes are reported here), what the
  /// plan sets of `frame`, and the lighting a lit plan reads.
  void SetUpFrame(vtkRenderer* renderer, vtkVolume* volume, vtkOpenGLRenderWindow* window,
    mtpt::RenderBackend* backend, mtpt::FrameInput& frame, mtpt::BackendFrame& draw);
  /// The settings of this mapper and the volume's `property` a frame is planned from.
  mtpt::FrameSettings FrameSettingsOf(vtkVolumeProperty* property);
  /// The facts of the input, the window and the chosen backend a frame is planned from.
  mtpt::FrameFacts FrameFactsOf(vtkRenderer* renderer, vtkOpenGLRenderWindow* window,
    mtpt::RenderBackend* backend, const mtpt::FrameInput& frame, const mtpt::BackendFrame& draw);
  /// The renderer's lights and each cell's normal (computed once per change of the data).
  void SetUpLighting(
    vtkRenderer* renderer, vtkVolumeProperty* property, mtpt::FrameInput& frame);
  /// The pipeline's settings for the frame, and its progress and abort callbacks.
  void ConfigurePipeline(vtkOpenGLRenderWindow* window);
  void DrawFrame(mtpt::RenderBackend* backend, mtpt::BackendFrame& draw);
  /// Whether the frame's buffers fit MemoryLimit (or the memory available); reports when not.
  bool FitsInMemory(const mtpt::FramePlan& plan);
  void ReportProgress(vtkOpenGLRenderWindow* window, double fraction);

  class Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
