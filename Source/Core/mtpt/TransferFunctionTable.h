// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TransferFunctionTable.h
 * @brief Colour and opacity transfer functions sampled into one RGBA table, read as the
 * OpenGL path's texture reads them. Shared by the compositor and opacity culling.
 */
#ifndef mtpt_TransferFunctionTable_h
#define mtpt_TransferFunctionTable_h

namespace mtpt
{

/**
 * A transfer function sampled over a scalar range: `table` holds `size` RGBA entries,
 * entry i at scalar low + i * (high - low) / (size - 1), read with linear interpolation and
 * clamped at both ends (the GL path's texture with linear filtering and clamp to edge).
 */
struct TransferFunctionTable
{
  const float* table = nullptr; ///< 4 * size floats
  int size = 0;
  double low = 0, high = 1;

  /// RGBA at `scalar`.
  void Lookup(float scalar, float rgba[4]) const;
};

} // namespace mtpt

#endif
