// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameStatistics.h
 * @brief What the last frame measured and counted, in one record: the CPU stages' times
 * and counts (FramePipeline), the drawing's times (a backend's), and the CPU compositor's.
 * The mapper's getters (GetTransformSeconds, GetNumberOfPixelCulledCells, ...) read it, and
 * the level of detail's rule reads its costs.
 */
#ifndef mtpt_FrameStatistics_h
#define mtpt_FrameStatistics_h

#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"

#include <cstddef>

namespace mtpt
{

/// Seconds a backend spent drawing the last frame, and how the drawing ended.
struct DrawTimes
{
  double upload = 0;    ///< OpenGL: buffer upload; CPU: read-back of depth and colour, image upload
  double draw = 0;      ///< OpenGL: the draw calls; CPU: the quad that writes the image
  double composite = 0; ///< CPU: compositing on the CPU (and magnifying a sampled image)
  /// Of the above, the work that follows the viewport alone, whatever the cells and the
  /// image sample distance (CPU: read-back, magnification, image upload and write-back;
  /// OpenGL: writing an off-screen target back), for the level of detail's budget rule.
  double viewport = 0;
  int batches = 0;          ///< batches drawn (FramePipeline::DrawBatches)
  bool stopped = false;     ///< the batch callback stopped the frame
  bool imageReused = false; ///< CPU: the previous frame's composited image served
};

/// The last frame's record.
struct FrameStatistics
{
  StageTimes stages;          ///< the CPU stages' seconds
  FrameStats counts;          ///< the cells culled, sorted and drawn; what was reused
  DrawTimes drawing;          ///< the backend's
  CompositorStats compositor; ///< the CPU compositor's (zero when OpenGL drew)
  bool cpu = false;           ///< the CPU backend drew it
  std::size_t tetrahedra = 0; ///< tetrahedra in the order (after culling)
  bool stopped = false;       ///< stopped by an abort before it was whole

  /// Seconds of the work that follows the cells drawn: keys, order, decomposition and
  /// lighting (the level of detail's rule, ChooseDetail).
  double CellSeconds() const
  {
    return stages.keys + stages.order + stages.decompose + stages.light;
  }
  /// Seconds of compositing (binning and rasterization), -1 where not measured apart
  /// (OpenGL draws; a reused image).
  double SampleSeconds() const
  {
    return cpu && !drawing.imageReused ? compositor.binSeconds + compositor.rasterSeconds : -1;
  }
};

} // namespace mtpt

#endif
