// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Timing.h
 * @brief The one stopwatch of the project: seconds on a steady clock, for the stage timers
 * of the core, the VTK module's backends and the benchmarks.
 */
#ifndef mtpt_Timing_h
#define mtpt_Timing_h

#include <chrono>

namespace mtpt
{

using Clock = std::chrono::steady_clock;

/// Seconds elapsed on the steady clock since `start`. Thread safety: reentrant.
inline double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

} // namespace mtpt

#endif
