// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file LargeBuffer.h
 * @brief The vector type of a frame's mesh-sized buffers (projected points, keys, the order,
 * ranks, decompositions, the compositor's lists): storage of HugePageBytes or more is
 * aligned to HugePageBytes and offered to the kernel for transparent huge pages before it
 * is first touched (Documentation/large-meshes.md, "Huge pages"). Its size is the one asked:
 * the memory a buffer holds is its capacity, as before.
 *
 * Why: the stages gather and scatter over these buffers at random (a batch's cells read
 * their points from the whole point array; the decomposition writes each cell's fan at its
 * rank; the compositor gathers a tile's fans). Past the caches every such access also needs
 * its page's translation, and with 4 KiB pages a gigabyte takes 262,144 of them, far more
 * than the processor's translation buffers hold; 2 MiB pages take 512. Where the system
 * keeps transparent huge pages for the regions that ask (Linux's "madvise" setting) or for
 * all ("always"), the buffers get them; elsewhere the hint changes nothing. What a
 * buffer holds, and every result, is the same either way.
 */
#ifndef mtpt_LargeBuffer_h
#define mtpt_LargeBuffer_h

#include <cstddef>
#include <limits>
#include <new>
#include <vector>

namespace mtpt
{

/// The size of a huge page on x86-64 and most AArch64 kernels, and the alignment of large
/// blocks.
constexpr std::size_t HugePageBytes = std::size_t{ 1 } << 21;

/**
 * `bytes` of storage aligned to `alignment` (a power of two); blocks of HugePageBytes or
 * more are aligned to a huge page and advised as huge-page candidates. Throws
 * std::bad_alloc when the memory is not there.
 */
void* AllocateLargeBuffer(std::size_t bytes, std::size_t alignment);

/// Frees what AllocateLargeBuffer(bytes, alignment) returned (null: nothing).
void FreeLargeBuffer(void* block, std::size_t bytes, std::size_t alignment) noexcept;

/// The allocator of LargeVector: stateless, every instance interchangeable.
template <typename T>
class LargeBufferAllocator
{
public:
  using value_type = T;

  LargeBufferAllocator() noexcept = default;
  template <typename U>
  LargeBufferAllocator(const LargeBufferAllocator<U>&) noexcept
  {
  }

  T* allocate(std::size_t n)
  {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T))
    {
      throw std::bad_array_new_length();
    }
    return static_cast<T*>(AllocateLargeBuffer(n * sizeof(T), alignof(T)));
  }
  void deallocate(T* block, std::size_t n) noexcept
  {
    FreeLargeBuffer(block, n * sizeof(T), alignof(T));
  }

  template <typename U>
  bool operator==(const LargeBufferAllocator<U>&) const noexcept
  {
    return true;
  }
  template <typename U>
  bool operator!=(const LargeBufferAllocator<U>&) const noexcept
  {
    return false;
  }
};

/// A std::vector whose storage LargeBufferAllocator provides.
template <typename T>
using LargeVector = std::vector<T, LargeBufferAllocator<T>>;

/**
 * Gives `buffer` room for `capacity` elements, dropping what it holds where it must grow: it
 * is freed first and allocated at exactly `capacity`. std::vector's own growth would hold
 * both blocks while it copies, and up to twice the elements asked for after, which the
 * memory bound of a frame does not allow (FramePipeline::BytesNeeded). For buffers a frame
 * writes anew. Returns whether it dropped the content.
 */
template <typename T>
bool ReserveDiscarding(LargeVector<T>& buffer, std::size_t capacity)
{
  if (buffer.capacity() >= capacity)
  {
    return false;
  }
  LargeVector<T>().swap(buffer);
  buffer.reserve(capacity);
  return true;
}

} // namespace mtpt

#endif
