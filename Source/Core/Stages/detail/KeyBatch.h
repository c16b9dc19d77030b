// SPDX-License-Identifier: BSD-3-Clause
// Internal: the depth keys' per-cell arithmetic (DepthKeys.cxx: the centroid depth, the
// frustum and pixel-centre culling) for several tetrahedra at once, one per SIMD lane,
// written once (KeyBatch.cxx) and compiled by Google Highway for every instruction set it
// targets. The operations are the scalar code's, in its order, without fused multiply-adds,
// so each lane's result is the scalar result bit for bit (Documentation/algorithm.md,
// "Several tetrahedra at once").
#ifndef mtpt_detail_KeyBatch_h
#define mtpt_detail_KeyBatch_h

#include "detail/DecomposeBatch.h"

#include <cstdint>

namespace mtpt
{
namespace detail
{

/// Why a cell of a key batch is left out: KeyKept for none.
enum KeyVerdict : std::int64_t
{
  KeyKept = 0,
  KeyOutsideFrustum = 1,
  KeyCoversNoPixel = 2
};

/// What ComputeVisibleDepthKeys culls (mtpt::KeyCulling) and how it measures depth.
struct KeyRules
{
  bool perspective = false;
  bool frustum = false;
  ImageSize imageSize; ///< set: pixel-centre culling
};

/// The cells of one key batch: their corners' point ids, lane-major.
struct KeyBatch
{
  alignas(64) std::int64_t point[4][BatchSize];
};

/// Per cell: the verdict (KeyVerdict; culling applies only where all four corners are
/// usable) and the centroid depth (CentroidDepth) before its conversion to float, which the
/// caller makes (a vector conversion may clamp where the scalar one gives infinity).
struct KeyBatchResult
{
  alignas(64) std::int64_t verdict[BatchSize];
  alignas(64) double depth[BatchSize];
};

/**
 * The verdicts and depths of cells [0, count) of `batch`, whose corners are `points`.
 * Every lane up to the next multiple of the vector length must hold valid point ids.
 * Thread safety: reads its inputs, writes `result` only.
 */
void ComputeKeyBatch(const ProjectedPoint* points, const KeyBatch& batch, int count,
  const KeyRules& rules, KeyBatchResult& result);

} // namespace detail
} // namespace mtpt

#endif
