// SPDX-License-Identifier: BSD-3-Clause
// Internal: the threading layer. Stage math stays in plain functions; only the loops
// that call it know about OpenMP (STYLE.md: keep scheduling out of the per-tet math).
#ifndef mtpt_detail_Parallel_h
#define mtpt_detail_Parallel_h

#include <chrono>

namespace mtpt
{
namespace detail
{

/// The OpenMP thread count for a requested count: <= 0 means all available.
int ResolveThreads(int requested);

/// Seconds elapsed on a steady clock since `start`.
inline double SecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace detail
} // namespace mtpt

#endif
