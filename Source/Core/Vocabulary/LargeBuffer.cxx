// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/LargeBuffer.h"

#include <algorithm>
#include <cstdlib>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mtpt
{

namespace
{
/// The alignment small blocks are allocated with: at least operator new's own.
std::align_val_t SmallAlignment(std::size_t alignment)
{
  return std::align_val_t(std::max(alignment, alignof(std::max_align_t)));
}

/// Whether a block takes the huge-page path (else operator new's); allocation and release
/// must decide alike.
bool OnHugePages(std::size_t bytes, std::size_t alignment)
{
  return bytes >= HugePageBytes && alignment <= HugePageBytes;
}
} // namespace

void* AllocateLargeBuffer(std::size_t bytes, std::size_t alignment)
{
  if (!OnHugePages(bytes, alignment))
  {
    return ::operator new(bytes, SmallAlignment(alignment));
  }
  // Aligned to a huge page, its size as asked: the huge pages are the whole 2 MiB extents
  // inside the block, its last partial one takes small pages, and what the aligned block
  // leaves unused before it is never touched, so never resident.
  void* block = nullptr;
  if (::posix_memalign(&block, HugePageBytes, bytes) != 0 || !block)
  {
    throw std::bad_alloc();
  }
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // A hint, before the first touch: the faults that follow take huge pages where the kernel
  // has them. Refused (a kernel without them, or set to never), the pages stay small.
  ::madvise(block, bytes, MADV_HUGEPAGE);
#endif
  return block;
}

void FreeLargeBuffer(void* block, std::size_t bytes, std::size_t alignment) noexcept
{
  if (!block)
  {
    return;
  }
  if (!OnHugePages(bytes, alignment))
  {
    ::operator delete(block, SmallAlignment(alignment));
    return;
  }
  std::free(block);
}

} // namespace mtpt
