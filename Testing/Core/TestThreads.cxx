// SPDX-License-Identifier: BSD-3-Clause
// The default thread count (mtpt/Threads.h): OMP_NUM_THREADS wins, MPI ranks on one node
// share its hardware threads, an affinity mask is trusted as it is.
#include "mtpt/Threads.h"

#include <gtest/gtest.h>

namespace
{

mtpt::ThreadEnvironment Node(int hardware, int processors, int openMP, int ranks, bool requested)
{
  mtpt::ThreadEnvironment e;
  e.hardwareThreads = hardware;
  e.processors = processors;
  e.openMPThreads = openMP;
  e.localRanks = ranks;
  e.threadsRequested = requested;
  return e;
}

TEST(Threads, OneProcessUsesEveryProcessorItMayRunOn)
{
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 16, 16, 1, false)), 16);
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 4, 4, 1, false)), 4); // taskset to 4 cores
}

TEST(Threads, OMPNumThreadsIsRespected)
{
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 16, 3, 1, true)), 3);
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 16, 3, 4, true)), 3) << "even under MPI";
}

TEST(Threads, MPIRanksOnANodeShareItsHardwareThreads)
{
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 16, 16, 4, false)), 4);
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 16, 16, 3, false)), 5);
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(2, 2, 2, 8, false)), 1) << "never below one";
}

TEST(Threads, RanksBoundToTheirOwnCoresKeepTheirMask)
{
  // mpiexec --bind-to core: each rank may run on its own processors only; OpenMP's
  // count already follows the mask, dividing again would leave cores idle.
  EXPECT_EQ(mtpt::DefaultThreadCount(Node(16, 4, 4, 4, false)), 4);
}

TEST(Threads, ExplicitCountsArePassedThrough)
{
  EXPECT_EQ(mtpt::ResolveThreadCount(3), 3);
  EXPECT_EQ(mtpt::ResolveThreadCount(0), mtpt::DefaultThreadCount());
  EXPECT_GE(mtpt::DefaultThreadCount(), 1);
}

} // namespace
