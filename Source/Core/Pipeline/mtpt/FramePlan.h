// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FramePlan.h
 * @brief The plan of one frame: the mapper's settings and the facts of the input and the
 * window, resolved once into plain values that every later step reads
 * (Documentation/architecture.md, "The frame plan").
 *
 * PlanFrame is the one place where a setting meets what the frame can do: a downgrade
 * (dependent components draw their own colours, so pre-integrated shading and the blend
 * modes other than composite fall back; a depth-peeling pass draws every cell and
 * composites), which tables the frame reads, which cells may be culled, the size of the
 * composited image, the batches and the memory they bound. The pipeline (FramePipeline),
 * both backends and the fragment shader read the plan and decide nothing again. What the
 * plan changed from what was asked comes back as notes for the caller to report.
 */
#ifndef mtpt_FramePlan_h
#define mtpt_FramePlan_h

#include "mtpt/Compositor.h"
#include "mtpt/MeshView.h"
#include "mtpt/Records.h"
#include "mtpt/Shading.h"
#include "mtpt/TransferFunctionTable.h"

#include <cstddef>
#include <string>
#include <vector>

namespace mtpt
{

/// The buffers a frame's batches are decomposed into (Decompose.h): slots of 4 triangles for
/// OpenGL, fans for the CPU compositor.
enum class BatchTarget
{
  Slots,
  Fans
};

/**
 * What each vertex record carries to its fragments, and so how the fragment shader and the
 * compositor read it (the shader's `shadingMode` uniform takes these values):
 * - TableMeans: each vertex is classified, the mean of the transfer function at its front
 *   and back scalars (VTK-compatible shading);
 * - Scalars: the front and back scalars themselves, integrated per fragment
 *   (pre-integrated shading, and the blend modes that reduce scalars);
 * - Colours: the data's own colour and attenuation (dependent components).
 */
enum class FragmentValues
{
  TableMeans = 0,
  Scalars = 1,
  Colours = 2
};

/// What FramePipeline::BytesNeeded bounds the buffers of.
struct MemoryNeed
{
  std::size_t points = 0; ///< the mesh's points
  std::size_t cells = 0;  ///< its tetrahedra
  /// The largest window decomposed at once (FramePipeline::DrawBatches); clamped to the
  /// cells and pieces.
  std::size_t batch = 0;
  bool slots = false;         ///< windows decomposed into slots (the OpenGL backend)
  bool fans = false;          ///< windows decomposed into fans (the CPU compositor)
  bool levelOfDetail = false; ///< frames with a cell fraction below 1
  int threads = 1;            ///< OpenMP threads (0: all; the radix order's counts)
  /// Near-plane pieces: at most 3 per cell the near plane cuts, so they grow with the cut's
  /// area, not with the mesh. 0 leaves them out.
  std::size_t pieces = 0;
};

/// What the user asked for this frame: the mapper's settings, as plain values.
struct FrameSettings
{
  Shading shading = Shading::VTKCompatible;
  /// vtkVolumeMapper's blend mode as set: any int (one out of range is reported).
  int blendMode = 0;
  double averageRange[2] = { -1e300, 1e300 }; ///< AverageIPScalarRange, scalar units
  bool shade = false;                         ///< the volume property's Shade: light the volume
  bool cullInvisibleCells = true;             ///< cull transparent, out-of-view and sub-pixel cells
  /// The fraction of the visible cells a moving frame draws (LevelOfDetail.h), and the
  /// image sample distance (ImageSampling.h), both as the level of detail set them.
  double cellFraction = 1;
  float imageSampleDistance = 1;
  bool autoAdjustCellFraction = false; ///< moving frames may draw a fraction of the cells
  std::size_t batchSize = 0;           ///< tetrahedra per batch; 0: the whole order at once
  int threads = 0;                     ///< OpenMP threads; <= 0: the default (Threads.h)
  double unitDistance = 1;             ///< ScalarOpacityUnitDistance, positive
};

/// What the frame is given: facts of the input and the window, not choices.
struct FrameFacts
{
  std::size_t points = 0, cells = 0;
  bool vertexColours = false;             ///< dependent components: the data give the colours
  bool cellScalars = false;               ///< the scalars belong to cells (they have no gradient)
  bool peeling = false;                   ///< one peel of a depth-peeling pass (VolumetricPeel)
  BatchTarget target = BatchTarget::Fans; ///< the chosen backend's buffers
  int viewport[2] = { 0, 0 };             ///< the viewport's size, pixels
  /// The largest side of an image the backend composites at another size than the
  /// viewport's; 0: it draws at the viewport's size only.
  int sampledImageLimit = 0;
  /// Whether the backend samples every fragment at a pixel centre of the composited image,
  /// drawing at the viewport's size, and drawing at another size.
  bool centresOnly = false, sampledCentresOnly = false;
  Matrix4 projection = IdentityMatrix(); ///< eye to clip coordinates
  ClipPlanes clipPlanes;                 ///< the mapper's, in eye coordinates
  /// The near plane's pieces of the last frame (FrameStats::nearPieces): this frame's are
  /// known only once its stages have cut the cells (the caller then checks the bound again
  /// with them), and a moving view's change little from frame to frame.
  std::size_t nearPieces = 0;
};

/// What the plan changed from what was asked, for the caller to report once.
struct PlanNote
{
  /// What the note is about: the mapper's settings, or the volume's property.
  enum class About
  {
    Mapper,
    Property
  };
  About about = About::Mapper;
  bool error = false; ///< an error (the setting is invalid), else a warning
  /// What identifies the note while its subject does not change (the text may carry
  /// numbers).
  std::string key;
  std::string text;
};

/// The frame's plan: every decision a frame takes from its settings and facts.
struct FramePlan
{
  // How fragments become pixels.
  Shading shading = Shading::VTKCompatible; ///< after every downgrade
  FragmentValues values = FragmentValues::TableMeans;
  bool vertexColours = false;
  BlendMode blendMode = BlendMode::Composite; ///< after every downgrade
  double averageRange[2] = { -1e300, 1e300 };
  /// Composite blending sorts back to front; the other modes reduce in any order, and the
  /// cells stay in cell order.
  bool ordered = true;
  bool lit = false; ///< shaded by the renderer's lights (Lighting.h)
  /// The tables the frame reads beside the transfer function's: the prefix integrals of
  /// pre-integrated shading, the intensity integral of the average and additive modes.
  bool preIntegrationTable = false, intensityTable = false;
  double unitDistance = 1;
  /// Of the projection: how scalars are interpolated (perspective-exact where the values
  /// are scalars), and the eye ray of each pixel for depth ranges and clipping planes.
  PerspectiveInterpolation interpolation;
  bool perspectiveExact = false; ///< scalars interpolated perspective-exactly
  DepthClipping clipping;
  ClipPlanes clipPlanes;

  // What is drawn.
  double cellFraction = 1; ///< CellFractionLevel of the visible cells (1: every cell)
  /// The composited image: the viewport's size, or the image sample distance's; the
  /// sampled size the distance gave (the same but inside a depth-peeling pass, which
  /// composites at the viewport's size).
  ImageSize imageSize, sampledSize;
  bool cullOpacity = true; ///< cells the opacity table makes transparent
  bool cullFrustum = true; ///< cells outside the view volume
  bool cullPixels = false; ///< cells covering no pixel centre of the composited image

  // How it is drawn.
  BatchTarget target = BatchTarget::Fans;
  std::size_t batchSize = 0; ///< tetrahedra per batch; 0: the whole order at once
  /// The batches from the front of the order to its back (the CPU compositor's composite
  /// blending: FramePipeline::DrawBatches), else from the back.
  bool frontToBack = false;
  int threads = 0;
  MemoryNeed memory; ///< what FramePipeline::BytesNeeded bounds before the frame allocates

  std::vector<PlanNote> notes;

  /// Whether the image is composited at another size than the viewport's `viewport`.
  bool Sampled(const int viewport[2]) const
  {
    return imageSize.width != viewport[0] || imageSize.height != viewport[1];
  }
};

/**
 * The plan of a frame with `settings` and `facts`. Pure: the same arguments give the same
 * plan; thread-safe.
 */
FramePlan PlanFrame(const FrameSettings& settings, const FrameFacts& facts);

/**
 * The CPU compositor's settings for a frame of `plan`: the image's size, the transfer
 * function `table`, and its integrals where the plan reads them (`preIntegration`,
 * `intensity`, kept alive by the caller until the last Composite), the attenuations' unit
 * distance `unitDistance`, the clipping and the blending. The opaque depth and depth ranges
 * are left to the caller. Pure; thread-safe.
 */
CompositeSettings CompositeSettingsFor(const FramePlan& plan, const TransferFunctionTable& table,
  const PreIntegrationTable& preIntegration, const IntensityTable& intensity, double unitDistance);

/// The name of a blend mode as vtkVolumeMapper's getters spell it ("Composite", ...);
/// "Unknown" for a value out of range.
const char* BlendModeName(int mode);

/// Samples per pixel side at most, for image sample distances below 1: the image and its
/// buffers grow with the square of it.
constexpr int MaximumSamplesPerPixel = 4;

} // namespace mtpt

#endif
