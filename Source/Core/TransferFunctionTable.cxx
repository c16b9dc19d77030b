// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/TransferFunctionTable.h"

namespace mtpt
{

void TransferFunctionTable::Lookup(float scalar, float rgba[4]) const
{
  // Texel-space coordinate of a texture sampled with linear filtering and clamp to edge.
  const double span = this->high > this->low ? this->high - this->low : 1.0;
  const auto scale = static_cast<float>((this->size - 1) / span);
  float t = (scalar - static_cast<float>(this->low)) * scale;
  const auto last = static_cast<float>(this->size - 1);
  t = t > 0.0f ? (t < last ? t : last) : 0.0f; // NaN maps to 0
  const int i = static_cast<int>(t);
  const int j = i + 1 < this->size ? i + 1 : i;
  const float f = t - static_cast<float>(i);
  const float* a = this->table + 4 * i;
  const float* b = this->table + 4 * j;
  for (int k = 0; k < 4; ++k)
  {
    rgba[k] = a[k] + f * (b[k] - a[k]);
  }
}

} // namespace mtpt
