// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Threads.h
 * @brief How many OpenMP threads the CPU stages use when the caller asks for "all".
 *
 * A thread count <= 0 passed to any stage means the default, chosen so that a node is not
 * oversubscribed:
 * 1. OMP_NUM_THREADS set: OpenMP's own count (omp_get_max_threads()), as every OpenMP
 *    program does; the user said what they want.
 * 2. Several MPI ranks on this node (the launcher's environment says how many:
 *    OMPI_COMM_WORLD_LOCAL_SIZE from Open MPI, MPI_LOCALNRANKS from MPICH and Intel MPI,
 *    MV2_COMM_WORLD_LOCAL_SIZE from MVAPICH2, PALS_LOCAL_SIZE from Cray PALS) and no CPU
 *    affinity narrowing this process: the node's hardware threads divided by the ranks on
 *    it (at least 1). ParaView's pvbatch and pvserver under mpiexec are the usual case.
 * 3. Otherwise OpenMP's count, which follows the process's affinity mask: a launcher that
 *    binds each rank to its own cores has already divided the node.
 * No MPI library is linked or called: the launchers' variables are read.
 */
#ifndef mtpt_Threads_h
#define mtpt_Threads_h

#include <cstddef>

namespace mtpt
{

/// What the default thread count depends on (see the file comment).
struct ThreadEnvironment
{
  int processors = 1;            ///< processors this process may run on (omp_get_num_procs)
  int hardwareThreads = 1;       ///< hardware threads of the node
  bool threadsRequested = false; ///< OMP_NUM_THREADS is set
  int openMPThreads = 1;         ///< omp_get_max_threads()
  int localRanks = 1;            ///< MPI ranks on this node (1 when not under MPI)
};

/// The environment of this process now. Thread safety: reentrant (reads the environment).
ThreadEnvironment CurrentThreadEnvironment();

/// The default thread count for `environment` (rules in the file comment). Pure function.
int DefaultThreadCount(const ThreadEnvironment& environment);

/**
 * The default thread count of this process: the launcher's variables are read once (they
 * do not change while it runs), OpenMP's count every call (omp_set_num_threads may change
 * it). Thread safety: reentrant.
 */
int DefaultThreadCount();

/// `requested` when positive, otherwise DefaultThreadCount().
int ResolveThreadCount(int requested);

/**
 * The threads worth waking for `items` items of work that cost about the same each:
 * ResolveThreadCount(requested), but at most one per `itemsPerThread` items (at least 1).
 * Waking OpenMP's workers costs tens of microseconds, and after a parallel region they
 * busy-wait for a while (see ReleaseIdleThreads): small work is done by the calling thread.
 * Pure function of its arguments and DefaultThreadCount().
 */
int ThreadsForWork(std::size_t items, std::size_t itemsPerThread, int requested);

/**
 * Ends the busy-waiting of this thread's idle OpenMP workers: after a parallel region they
 * spin for milliseconds (GCC's libgomp by default) before they sleep, and on a machine
 * where OpenGL is itself a CPU rasterizer (Mesa llvmpipe) that spinning takes cores from
 * the rasterizer's threads while they draw the rest of the frame. Implemented with
 * omp_pause_resource_all(omp_pause_soft) (OpenMP 5.0): the workers are released and the
 * next parallel region starts new ones, once per frame. Does nothing inside a parallel
 * region or where the runtime cannot release them: LLVM's libomp keeps spinning for its
 * KMP_BLOCKTIME after a soft pause (set KMP_BLOCKTIME=0 there instead). Returns whether it
 * released them.
 * Thread safety: call from the thread that ran the parallel regions, outside any.
 */
bool ReleaseIdleThreads();

} // namespace mtpt

#endif
