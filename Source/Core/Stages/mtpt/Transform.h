// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Transform.h
 * @brief Stage 1 of a frame: every mesh point to eye and normalized device coordinates.
 *
 * Conventions: see MeshView.h (row-major matrices on column vectors, OpenGL NDC, the
 * camera looking down -z in eye space).
 *
 * Each point becomes one 64-byte record holding everything the later stages read about
 * it, so a tetrahedron costs four cache-line gathers instead of a dozen scattered reads of
 * coordinates, projections and scalars. Records are double precision: decomposition
 * classifies and measures with them, and with float NDC the thickness at a thick vertex
 * near a silhouette edge would carry an absolute error of about 1e-7 of the cell's
 * projected size (large relative errors for thin segments); eye coordinates are relative
 * to the camera, so meshes far from the origin keep their precision. Only the records
 * handed to the rasterizer are rounded to float.
 */
#ifndef mtpt_Transform_h
#define mtpt_Transform_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/Records.h"

#include "mtpt/Stage.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/**
 * Projects `points` into `out` (points.count records) with the model-view matrix
 * (view * model; a part of its own model matrix, MeshPart::model, with model-view times
 * it) and the projection matrix, and copies point scalars alongside.
 *
 * Thread safety: reentrant; runs on `threads` OpenMP threads (<= 0: all available).
 * Determinism: each record depends only on its own input point: identical for any
 * thread count.
 */
void ProjectPoints(const PointsView& points, const ScalarsView& scalars, const Matrix4& modelView,
  const Matrix4& projection, ProjectedPoint* out, int threads);

/// What the projected points depend on: TransformStage's key.
struct TransformKey
{
  MeshKey mesh;
  Matrix4 modelView{}, projection{};
  std::uint64_t placement = 0; ///< FrameInput::placementVersion: the parts' model matrices
  bool operator==(const TransformKey& o) const
  {
    return mesh == o.mesh && modelView == o.modelView && projection == o.projection &&
      placement == o.placement;
  }
};

/**
 * Stage 1 as a stage of FramePipeline (Stage.h): the projected points of the mesh, kept
 * until the data or a matrix changes.
 */
class TransformStage : public StageOf<TransformKey>
{
public:
  /// Projects the points unless they were projected with `key`; true when it projected.
  bool Update(const Key& key, const PointsView& points, const ScalarsView& scalars, int threads);

  /// One record per point (valid after Update; the vector may be longer than the mesh).
  const LargeVector<ProjectedPoint>& Points() const { return this->Projected; }
  /// Frees the records.
  void Release() override;
  std::size_t MemoryBytes() const override
  {
    return this->Projected.capacity() * sizeof(ProjectedPoint);
  }

private:
  LargeVector<ProjectedPoint> Projected; ///< grows to the largest mesh and is reused
};

} // namespace mtpt

#endif
