// SPDX-License-Identifier: BSD-3-Clause
// The default thread count (mtpt/Threads.h): OMP_NUM_THREADS wins, MPI ranks on one node
// share its hardware threads, an affinity mask is trusted as it is.
#include "mtpt/Threads.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

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

TEST(Threads, SmallWorkIsDoneByOneThread)
{
  EXPECT_EQ(mtpt::ThreadsForWork(0, 100, 8), 1);
  EXPECT_EQ(mtpt::ThreadsForWork(99, 100, 8), 1);
  EXPECT_EQ(mtpt::ThreadsForWork(250, 100, 8), 2);
  EXPECT_EQ(mtpt::ThreadsForWork(1000000, 100, 8), 8) << "never more than asked";
  EXPECT_EQ(mtpt::ThreadsForWork(1000000, 0, 3), 3) << "no grain: every thread";
  EXPECT_EQ(mtpt::ThreadsForWork(1000000, 100, 0), mtpt::DefaultThreadCount());
}

/// CPU seconds this process used so far, all threads.
double ProcessCPUSeconds()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
    1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// This thread's kernel id.
long KernelThreadId()
{
  return syscall(SYS_gettid);
}

/// Whether thread `id` of this process still exists (Linux: /proc/self/task/<id>).
bool ThreadExists(long id)
{
  return std::filesystem::exists("/proc/self/task/" + std::to_string(id));
}

/// Whether every thread of `ids` has exited within 30 seconds: a guard against a hang, not a
/// bound on how fast threads exit.
bool Exited(const std::vector<long>& ids)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (const long id : ids)
  {
    while (ThreadExists(id))
    {
      if (std::chrono::steady_clock::now() > deadline)
      {
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  return true;
}

/// Whether a thread of this process other than the calling one is running or runnable
/// (state R in /proc/self/task/<id>/stat): the only threads whose CPU time the process's
/// clock may not yet count (see ReleasedWorkersStopBusyWaiting).
bool OthersRun()
{
  const std::string self = std::to_string(KernelThreadId());
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task"))
  {
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    if (entry.path().filename() == self || !std::getline(stat, line))
    {
      continue; // the caller, or a thread that has just exited
    }
    const std::size_t name = line.rfind(')'); // the state follows the parenthesised name
    if (name != std::string::npos && name + 2 < line.size() && line[name + 2] == 'R')
    {
      return true;
    }
  }
  return false;
}

/// Whether no other thread of this process runs within 30 seconds (OthersRun).
bool OthersSettle()
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (OthersRun())
  {
    if (std::chrono::steady_clock::now() > deadline)
    {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

TEST(Threads, ReleasedWorkersStopBusyWaiting)
{
  // After a parallel region, idle workers may spin (GCC's default) and take a core from
  // whatever runs next, such as the OpenGL rasterizer. Released, they exit and use no CPU
  // while the calling thread sleeps; the next region still runs on every thread asked for.
  std::vector<long> workers; // the kernel ids of the last region's workers
  auto region = [&workers]
  {
    int team = 0;
    long ids[2] = { 0, 0 };
#pragma omp parallel num_threads(2)
    {
      ids[omp_get_thread_num()] = KernelThreadId(); // a team of at most 2
#pragma omp single
      team = omp_get_num_threads();
    }
    workers.assign(ids + 1, ids + team);
    return team;
  };
  EXPECT_EQ(region(), 2);
  if (!mtpt::ReleaseIdleThreads())
  {
    // LLVM's libomp (the sanitizer builds): see ReleaseIdleThreads.
    GTEST_SKIP() << "this OpenMP runtime cannot release its idle workers";
  }
  for (int attempt = 0; attempt < 3; ++attempt)
  {
    ASSERT_EQ(region(), 2);
    EXPECT_TRUE(ThreadExists(workers[0])) << "the region's worker waits for the next region";
    ASSERT_TRUE(mtpt::ReleaseIdleThreads());
    ASSERT_TRUE(Exited(workers)) << "released workers exit";
    // The clock is read once they have, and once no other thread runs (workers of a larger
    // team of an earlier test in this process exit too): another thread's CPU time is
    // brought up to date only at the scheduler's ticks and switches, so a reading taken
    // while a worker exits can leave out up to a tick of its spinning before the release,
    // counted in the sleep.
    ASSERT_TRUE(OthersSettle()) << "no other thread keeps running";
    const double before = ProcessCPUSeconds();
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
    const double spent = ProcessCPUSeconds() - before;
    EXPECT_LT(spent, 0.003) << "CPU seconds while asleep after the release";
  }
  EXPECT_EQ(region(), 2);
#pragma omp parallel num_threads(2)
  {
    EXPECT_FALSE(mtpt::ReleaseIdleThreads()) << "not from inside a parallel region";
  }
  mtpt::ReleaseIdleThreads();
}

} // namespace
