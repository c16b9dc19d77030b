// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Faults.h"

#include <atomic>
#include <new>

namespace mtpt
{

namespace
{

std::atomic<AllocationSite> injected{ AllocationSite::None };

/// Each site's name, as MTPT_TESTING_FAULT=allocation:NAME gives it.
struct SiteName
{
  AllocationSite site;
  const char* name;
};
constexpr SiteName Names[] = { { AllocationSite::Transform, "transform" },
  { AllocationSite::Culling, "culling" }, { AllocationSite::LevelOfDetail, "level-of-detail" },
  { AllocationSite::DepthKeys, "depth-keys" }, { AllocationSite::NearPlane, "near-plane" },
  { AllocationSite::Order, "order" }, { AllocationSite::Decomposition, "decomposition" },
  { AllocationSite::Tiles, "tiles" } };

} // namespace

void InjectAllocationFault(AllocationSite site)
{
  injected = site;
}

void AllocationPoint(AllocationSite site)
{
  AllocationSite expected = site;
  if (site != AllocationSite::None &&
    injected.compare_exchange_strong(expected, AllocationSite::None))
  {
    throw std::bad_alloc();
  }
}

const char* AllocationSiteName(AllocationSite site)
{
  for (const SiteName& entry : Names)
  {
    if (entry.site == site)
    {
      return entry.name;
    }
  }
  return "none";
}

bool AllocationSiteNamed(const std::string& name, AllocationSite& site)
{
  for (const SiteName& entry : Names)
  {
    if (name == entry.name)
    {
      site = entry.site;
      return true;
    }
  }
  return false;
}

} // namespace mtpt
