// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Faults.h
 * @brief Testing hooks: a frame's allocations made to fail on purpose, one site at a time,
 * to show that a failure anywhere in a frame is reported, leaves nothing half built, and is
 * followed by a whole next frame (Documentation/testing.md, "Faults").
 *
 * Each place where a frame allocates a buffer that grows with the mesh, the window or the
 * cells cut calls AllocationPoint(site) first; after InjectAllocationFault(site) the next
 * such call throws std::bad_alloc, as the allocation would where memory runs out. The sites
 * are called outside any parallel region, so the exception reaches the caller.
 */
#ifndef mtpt_Faults_h
#define mtpt_Faults_h

#include <string>

namespace mtpt
{

/// Where a frame allocates.
enum class AllocationSite
{
  None,
  Transform,     ///< the projected points
  Culling,       ///< the visible cells' list
  LevelOfDetail, ///< the importance order and the moving frame's subset
  DepthKeys,     ///< the depth keys
  NearPlane,     ///< the pieces of the cells the near plane cuts, while cutting
  Order,         ///< the order, its ranks and rank groups
  Decomposition, ///< a batch's slots or fans
  Tiles          ///< the CPU compositor's tiles and bins
};

/**
 * Testing only: the next AllocationPoint(site) throws std::bad_alloc (once); None clears
 * it. Not thread-safe with respect to frames running.
 */
void InjectAllocationFault(AllocationSite site);

/// Throws std::bad_alloc when a fault is injected at `site`, clearing it. Thread-safe.
void AllocationPoint(AllocationSite site);

/// The site's name ("transform", "near-plane", ...) and back; false for an unknown name.
const char* AllocationSiteName(AllocationSite site);
bool AllocationSiteNamed(const std::string& name, AllocationSite& site);

} // namespace mtpt

#endif
