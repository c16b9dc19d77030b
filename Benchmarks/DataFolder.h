// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DataFolder.h
 * @brief Where the benchmarks look for real meshes beyond the repository's own data
 * (Data/, and the meshes they generate): the folder in the environment variable
 * MTPT_DATA_DIR, else the one configured with the CMake option MTPT_EXTRA_DATA_DIR; none
 * by default. Such a folder holds comb/, kiefer/, pulley/, fire_ug/, ironProt/ as
 * MeshLoader.h lists them.
 */
#ifndef mtpt_bench_DataFolder_h
#define mtpt_bench_DataFolder_h

#include <cstdlib>
#include <string>

#ifndef MTPT_EXTRA_DATA_DIR
#define MTPT_EXTRA_DATA_DIR ""
#endif

namespace mtpt
{
namespace bench
{

/// The folder of real meshes, or "" when none is configured.
inline std::string DefaultDataFolder()
{
  const char* environment = std::getenv("MTPT_DATA_DIR");
  return environment && *environment ? environment : MTPT_EXTRA_DATA_DIR;
}

} // namespace bench
} // namespace mtpt

#endif
