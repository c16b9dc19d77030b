// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TransferFunctionTable.h
 * @brief Colour and opacity transfer functions sampled into one RGBA table, read as the
 * OpenGL path's texture reads them, and the table's integral functions for pre-integrated
 * shading. Shared by the compositor, the OpenGL shaders (same formulas) and opacity culling.
 */
#ifndef mtpt_TransferFunctionTable_h
#define mtpt_TransferFunctionTable_h

#include "mtpt/SegmentShared.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace mtpt
{

/**
 * A transfer function sampled over a scalar range: `table` holds `size` RGBA entries,
 * entry i at scalar low + i * (high - low) / (size - 1), read with linear interpolation and
 * clamped at both ends (the GL path's texture with linear filtering and clamp to edge).
 * Alpha is the attenuation per ScalarOpacityUnitDistance (VTK's scalar opacity).
 */
struct TransferFunctionTable
{
  const float* table = nullptr; ///< 4 * size floats
  int size = 0;
  double low = 0, high = 1;

  /// RGBA at `scalar`.
  void Lookup(float scalar, float rgba[4]) const;
  /// RGBA at entry coordinate u in [0, size - 1] (linear between entries, in double).
  void LookupEntry(double u, float rgba[4]) const;

  /// `scalar` in entry units: 0 at `low`, size - 1 at `high`, clamped (NaN gives 0).
  double EntryCoordinate(double scalar) const;
  /// The same, not clamped (NaN gives 0).
  double UnclampedEntryCoordinate(double scalar) const;
};

/**
 * Pre-integrated shading (Documentation/algorithm.md, "Shading"): the colour and opacity of
 * a ray segment along which the scalar runs linearly from `front` to `back`, computed from
 * the integral functions of the table (Engel, Kraus and Ertl, "High-quality pre-integrated
 * volume rendering using hardware-accelerated pixel shading", 2001) instead of from the two
 * end values. With the table's attenuation tau(u) and colour c(u) linear between entries,
 * the integral functions
 *   T(u) = integral_0^u tau,   E(u) = integral_0^u c tau
 * are exact piecewise cubics, stored at the entries (prefix sums) and completed inside an
 * entry in closed form. A segment's optical depth is then exact for any transfer function
 * the table holds, however narrow its features: a peak between the two end scalars is
 * counted in full. The segment is composited front to back in up to
 * MaxPreIntegrationSteps equal scalar steps (PreIntegrationSteps: one per
 * PreIntegrationStepDepth of optical depth), each with its exact optical depth and its
 * attenuation-weighted mean colour; only the order of emission inside one step is
 * approximated.
 */
struct PreIntegrationTable
{
  /// 4 * size prefix sums (T, E_r, E_g, E_b) at the entries, entry units.
  std::vector<double> integrals;
  /// The same as float sums high + low, for single-precision code (the CPU compositor's
  /// vectors, the OpenGL backend's shader), so that differences of nearby entries keep their
  /// precision: 8 floats per entry, the four high parts then the four low parts. Followed by
  /// Padding copies of the last entry, as is
  std::vector<float> integralsSplit;
  /// the table itself (4 * (size + Padding) floats): the CPU compositor loads an entry and
  /// the next at once, which a table of one entry must hold too.
  std::vector<float> paddedTable;
  static constexpr int Padding = 1;

  /// Builds the prefix sums of `tf` (recompute whenever the table changes).
  void Build(const TransferFunctionTable& tf);

  /// Whether the prefix sums cover `tf` (built from it, not empty); if not, every segment
  /// is transparent.
  bool Covers(const TransferFunctionTable& tf) const
  {
    const std::size_t entries = static_cast<std::size_t>(std::max(tf.size, 0));
    return tf.size >= 1 && this->integrals.size() >= 4 * entries &&
      this->integralsSplit.size() >= 8 * (entries + Padding) &&
      this->paddedTable.size() >= 4 * (entries + Padding);
  }

  /**
   * Colour (not premultiplied) and opacity of a segment of eye-space length `length`
   * from scalar `front` to `back`, with `inverseUnit` = 1 / ScalarOpacityUnitDistance.
   * The OpenGL fragment shader evaluates the same formulas, and the CPU compositor too,
   * several fragments per SIMD vector (detail/TileRaster.cxx, tested against this function).
   */
  void Segment(const TransferFunctionTable& tf, float front, float back, float length,
    float inverseUnit, float rgba[4]) const;
};

/**
 * Average and additive blending (BlendMode) integrate o(s) x along each segment, with o the
 * table's opacity and x the scalar normalized over the table's range: x = u / (size - 1)
 * at entry coordinate u. With o linear between entries, o x is quadratic there, so
 *   W(u) = integral_0^u o x du
 * is an exact piecewise cubic, stored at the entries (prefix sums) and completed inside an
 * entry in closed form, as PreIntegrationTable's integrals. The OpenGL backend's shader
 * reads the same sums.
 */
struct IntensityTable
{
  /// W at the entries, and the same as a float sum high + low (for the vector paths and the
  /// OpenGL backend: differences of nearby entries keep their precision).
  std::vector<double> prefix;
  std::vector<float> prefixHigh, prefixLow;

  /// Builds the prefix sums of `tf` (recompute whenever the table changes).
  void Build(const TransferFunctionTable& tf);

  /// Whether the prefix sums cover `tf`; if not, every mean is 0.
  bool Covers(const TransferFunctionTable& tf) const
  {
    const auto size = static_cast<std::size_t>(tf.size);
    return tf.size >= 1 && this->prefix.size() >= size && this->prefixHigh.size() >= size &&
      this->prefixLow.size() >= size;
  }

  /**
   * The mean of o x over the entry coordinates [u0, u1] (u0 <= u1; beyond the table the
   * scalar is clamped to its ends, as the table's lookups clamp it); o x at u0 when they are
   * equal.
   */
  double Mean(const TransferFunctionTable& tf, double u0, double u1) const;
};

/**
 * The average's scalar range (AverageIntensity) in entry coordinates of `tf`, within
 * [-`beyond`, `beyond`]. It applies to the clamped scalar, so where it reaches an end of the
 * table it is open beyond that end (-+`beyond`). With `beyond` a float (AverageRangeBeyond),
 * the entries convert to float safely, however far the range lies.
 */
void AverageRangeEntries(
  const TransferFunctionTable& tf, const double range[2], double beyond, double entries[2]);

/// The `beyond` of AverageRangeEntries for the compositor and the OpenGL backend: far past
/// any table, and a float.
constexpr double AverageRangeBeyond = 1e30;

/// At most this many compositing steps per segment (pre-integrated shading).
constexpr int MaxPreIntegrationSteps = MTPT_MAX_SEGMENT_STEPS;
/// One compositing step per this much optical depth (pre-integrated shading).
constexpr double PreIntegrationStepDepth = MTPT_STEP_DEPTH;

/// The compositing steps of a segment of optical depth `depth`: ceil(depth /
/// PreIntegrationStepDepth) within [1, MaxPreIntegrationSteps] (1 for NaN).
inline int PreIntegrationSteps(double depth)
{
  const double wanted = std::ceil(depth / PreIntegrationStepDepth);
  return wanted > 1.0 ? static_cast<int>(std::min<double>(MaxPreIntegrationSteps, wanted)) : 1;
}

} // namespace mtpt

#endif
