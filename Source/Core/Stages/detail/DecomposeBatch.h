// SPDX-License-Identifier: BSD-3-Clause
// Internal: the arithmetic of the decomposition (Decompose.cxx, ClassifyProjection and
// ComputeFanGeometry) for several tetrahedra at once, one per SIMD lane, written once
// (DecomposeBatch.cxx) and compiled by Google Highway for every instruction set it targets.
// Which vertex plays which part (the thick vertex, the diagonals' ends) is looked up from
// the signs of the four projected areas in a table the scalar code fills (Decompose.cxx),
// so the two can never disagree on it; the values are the scalar code's operations in the
// scalar code's order, without fused multiply-adds, so every lane's result is the scalar
// result bit for bit (Documentation/algorithm.md, "Several tetrahedra at once").
#ifndef mtpt_detail_DecomposeBatch_h
#define mtpt_detail_DecomposeBatch_h

#include "mtpt/Records.h"

#include <cstddef>
#include <cstdint>

namespace mtpt
{
namespace detail
{

/// Tetrahedra per batch: a multiple of every double-precision lane count Highway uses.
constexpr int BatchSize = 16;

/// Sign patterns of the four projected areas: bit i of the low nibble is set when area i is
/// positive, bit i of the high nibble when it is negative; neither when it is within the
/// zero band.
constexpr int SignPatterns = 256;

/**
 * Per sign pattern, the corners in the parts they play: for a quadrilateral projection
 * (a, b, d0, d1), the ends of the two diagonals, which cross at alpha along a->b and beta
 * along d0->d1; for a triangle projection (j0, j1, j2, t), the outer corners and the thick
 * (inner) vertex; and whether the projection is a quadrilateral (1) or not (0).
 */
struct RoleTable
{
  alignas(64) std::int64_t role[4][SignPatterns];
  alignas(64) std::int64_t quadrilateral[SignPatterns];
  /// The zero band, relative to the projection's area (ClassificationTolerance).
  double tolerance = 0;
};

/// The tetrahedra of one batch: corner point ids and scalars, lane-major.
struct TetBatch
{
  alignas(64) std::int64_t point[4][BatchSize];
  alignas(64) float scalar[4][BatchSize];
};

/// What the batch computes per tetrahedron.
struct TetBatchResult
{
  alignas(64) std::int64_t pattern[BatchSize]; ///< the sign pattern (SignPatterns)
  /// 1 when the projection has an area to speak of (ClassifyProjection's first test).
  alignas(64) std::int64_t hasArea[BatchSize];
  /// The thick vertex's record: x, y, front z, front scalar, back scalar, thickness.
  alignas(64) float thick[6][BatchSize];
};

/**
 * Classifies and computes the thick vertex of tetrahedra [0, count) of `batch`, whose corners
 * are `points` (all usable) and whose scalars are finite. count <= BatchSize.
 * Thread safety: reads its inputs, writes `result` only.
 */
void DecomposeBatch(const ProjectedPoint* points, const TetBatch& batch, int count,
  const RoleTable& roles, TetBatchResult& result);

/// The instruction set DecomposeBatch runs with on this processor (benchmarks print it).
const char* DecomposeTargetName();

} // namespace detail
} // namespace mtpt

#endif
