// SPDX-License-Identifier: BSD-3-Clause
// Run under `mpiexec -n N --bind-to none`: each rank checks that the default thread count
// is the node's hardware threads divided by the N ranks the launcher announced, and prints
// what it found. Exit status 0 when it is.
#include "mtpt/Threads.h"

#include <cstdio>

int main()
{
  const mtpt::ThreadEnvironment e = mtpt::CurrentThreadEnvironment();
  const int threads = mtpt::DefaultThreadCount();
  int expected = e.hardwareThreads / (e.localRanks > 0 ? e.localRanks : 1);
  expected = expected > 0 ? expected : 1;
  std::printf("rank of %d on this node: %d hardware threads, %d processors, default %d "
              "threads (expected %d)\n",
    e.localRanks, e.hardwareThreads, e.processors, threads, expected);
  if (e.localRanks < 2)
  {
    std::printf("no MPI launcher variable seen\n");
    return 1;
  }
  return threads == expected ? 0 : 1;
}
