// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Statistics.h
 * @brief Medians of timed runs, shared by every benchmark program (header-only, no VTK).
 */
#ifndef mtpt_bench_Statistics_h
#define mtpt_bench_Statistics_h

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace mtpt
{
namespace bench
{

/// Index of the value at the median (the lower middle one for an even count; 0 for none).
inline std::size_t MedianIndex(const std::vector<double>& values)
{
  if (values.empty())
  {
    return 0;
  }
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{ 0 });
  std::sort(order.begin(), order.end(),
    [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  return order[(order.size() - 1) / 2];
}

/// The median of `values`: the middle value, or the mean of the two middle values for an
/// even count; 0 for none.
inline double Median(std::vector<double> values)
{
  if (values.empty())
  {
    return 0;
  }
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

} // namespace bench
} // namespace mtpt

#endif
