// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Threads.h"

#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <thread>

namespace mtpt
{

namespace
{

/// A positive integer from the environment variable `name`, or 0.
int PositiveVariable(const char* name)
{
  const char* value = std::getenv(name);
  if (!value || !*value)
  {
    return 0;
  }
  char* end = nullptr;
  const long parsed = std::strtol(value, &end, 10);
  return end && *end == '\0' && parsed > 0 && parsed < (1 << 20) ? static_cast<int>(parsed) : 0;
}

/// MPI ranks on this node, as the launchers announce it; 1 when none does.
int LocalRanks()
{
  for (const char* name : { "OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS",
         "MV2_COMM_WORLD_LOCAL_SIZE", "PALS_LOCAL_SIZE" })
  {
    if (const int ranks = PositiveVariable(name))
    {
      return ranks;
    }
  }
  return 1;
}

struct LaunchEnvironment
{
  bool threadsRequested;
  int localRanks;
  int hardwareThreads;
};

const LaunchEnvironment& Launch()
{
  static const LaunchEnvironment launch = []
  {
    // An empty OMP_NUM_THREADS is no request (libgomp rejects it and uses its default).
    const char* requested = std::getenv("OMP_NUM_THREADS");
    return LaunchEnvironment{ requested && *requested, LocalRanks(),
      std::max(1, static_cast<int>(std::thread::hardware_concurrency())) };
  }();
  return launch;
}

} // namespace

ThreadEnvironment CurrentThreadEnvironment()
{
  const LaunchEnvironment& launch = Launch();
  ThreadEnvironment e;
  e.processors = std::max(1, omp_get_num_procs());
  e.hardwareThreads = launch.hardwareThreads;
  e.threadsRequested = launch.threadsRequested;
  e.openMPThreads = std::max(1, omp_get_max_threads());
  e.localRanks = launch.localRanks;
  return e;
}

int DefaultThreadCount(const ThreadEnvironment& e)
{
  if (e.threadsRequested)
  {
    return std::max(1, e.openMPThreads);
  }
  const bool narrowedByAffinity = e.processors < e.hardwareThreads;
  if (e.localRanks > 1 && !narrowedByAffinity)
  {
    return std::max(1, e.hardwareThreads / e.localRanks);
  }
  return std::max(1, e.openMPThreads);
}

int DefaultThreadCount()
{
  return DefaultThreadCount(CurrentThreadEnvironment());
}

int ResolveThreadCount(int requested)
{
  return requested > 0 ? requested : DefaultThreadCount();
}

int ThreadsForWork(std::size_t items, std::size_t itemsPerThread, int requested)
{
  const std::size_t worth = items / std::max<std::size_t>(itemsPerThread, 1);
  const auto resolved = static_cast<std::size_t>(ResolveThreadCount(requested));
  return static_cast<int>(std::max<std::size_t>(1, std::min(worth, resolved)));
}

bool ReleaseIdleThreads()
{
  // OpenMP 5.0's pause API: GCC's libgomp has it from GCC 10 on while still announcing
  // OpenMP 4.5 in _OPENMP.
// LLVM's libomp (its omp.h defines KMP_VERSION_MAJOR) accepts the soft pause but, up to at
// least LLVM 14, its workers keep spinning until their KMP_BLOCKTIME (200 ms) runs out, so
// there it releases nothing and says so.
#if defined(_OPENMP) && !defined(KMP_VERSION_MAJOR) &&                                             \
  (_OPENMP >= 201811 || (defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 10))
  return omp_in_parallel() == 0 && omp_pause_resource_all(omp_pause_soft) == 0;
#else
  return false;
#endif
}

} // namespace mtpt
