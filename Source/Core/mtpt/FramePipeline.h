// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FramePipeline.h
 * @brief The CPU stages of one frame in sequence (transform, keys, order, decompose),
 * owning their buffers and timing each stage.
 */
#ifndef mtpt_FramePipeline_h
#define mtpt_FramePipeline_h

#include "mtpt/Decompose.h"
#include "mtpt/VisibilityOrder.h"

#include <memory>
#include <vector>

namespace mtpt
{

/// Wall-clock seconds of each CPU stage of the last frame. `decompose` includes inverting
/// the order (DecomposeTetrahedraByRank).
struct StageTimes
{
  double transform = 0, keys = 0, order = 0, decompose = 0;
  double Total() const { return transform + keys + order + decompose; }
};

/// What a frame needs to know about the mesh and the view.
struct FrameInput
{
  PointsView points;
  CellsView cells;
  ScalarsView scalars;
  Matrix4 modelView = IdentityMatrix();  ///< view * model
  Matrix4 projection = IdentityMatrix(); ///< eye to clip coordinates
  bool perspective = false;
  /// Viewport in pixels; when set, cells covering no pixel centre are culled (see
  /// DecomposeInput). Leave 0 for multisampled targets.
  int viewportWidth = 0, viewportHeight = 0;
};

/**
 * Runs the four CPU stages and keeps their results until the next Run. Buffers grow to
 * the largest mesh seen and are reused, so steady-state frames allocate nothing.
 * Thread safety: one object per thread of control; the stages use OpenMP inside.
 */
class FramePipeline
{
public:
  FramePipeline();

  void SetOrderMethod(OrderMethod method, std::size_t maxSubArraySize = DefaultMaxSubArraySize);
  OrderMethod GetOrderMethod() const { return Order->Method(); }

  /// Runs all stages on `threads` OpenMP threads (<= 0: all available).
  /// Returns false (and leaves empty buffers) if the mesh is too large for 32-bit indices.
  bool Run(const FrameInput& input, int threads);

  const StageTimes& Times() const { return LastTimes; }
  std::size_t TetrahedronCount() const { return Count; }
  const std::vector<ProjectedPoint>& Points() const { return ProjectedPoints; }
  const std::vector<SortKey>& Keys() const { return SortedKeys; }
  const std::vector<TetVertex>& Vertices() const { return VertexBuffer; }
  const std::vector<std::uint32_t>& Indices() const { return IndexBuffer; }

  /// Largest tetrahedron count whose fixed-stride buffers fit 32-bit indices.
  static std::size_t MaxTetrahedra();

private:
  std::unique_ptr<VisibilityOrder> Order;
  std::size_t MaxSubArraySize = DefaultMaxSubArraySize;
  std::vector<ProjectedPoint> ProjectedPoints;
  std::vector<SortKey> SortedKeys;
  std::vector<std::uint32_t> Rank;
  std::vector<TetVertex> VertexBuffer;
  std::vector<std::uint32_t> IndexBuffer;
  std::size_t Count = 0;
  StageTimes LastTimes;
};

} // namespace mtpt

#endif
