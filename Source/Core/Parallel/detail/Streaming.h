// SPDX-License-Identifier: BSD-3-Clause
// Internal: copies of the decomposition's records to buffers that another thread reads next
// (the OpenGL upload, the compositor's tiles), with non-temporal stores on x86-64. Plain
// stores to lines not in cache first read them for ownership; with ~40 stores a record the
// store buffer fills and the core stalls (Documentation/algorithm.md, "Decomposition at a
// fixed stride", has the measurement). The one copy of each record kind, for the
// decomposition and for the compositor's binning; the batched decomposition's writers
// (Decompose.cxx, SlotWriter and FanWriter) stream the same bytes from registers instead.
#ifndef mtpt_detail_Streaming_h
#define mtpt_detail_Streaming_h

#include "mtpt/Records.h"

#if defined(__x86_64__) || defined(_M_X64)
#include <immintrin.h>
#endif

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace mtpt
{
namespace detail
{

/**
 * Copies a finished slot (assembled on the stack) to its place in the buffers with
 * non-temporal 8-byte stores where available (see the file comment). The buffers are read
 * next by the upload, not by this thread, so bypassing the cache is free.
 * Requires 8-byte aligned buffers (any new/malloc allocation); otherwise memcpy is used.
 */
inline void StoreSlot(const TetVertex source[VerticesPerTetrahedron],
  const std::uint32_t sourceIndices[IndicesPerTetrahedron], TetVertex* vertices,
  std::uint32_t* indices, bool streaming)
{
#if defined(__x86_64__) || defined(_M_X64)
  constexpr std::size_t VertexWords = VerticesPerTetrahedron * sizeof(TetVertex) / 8;
  constexpr std::size_t IndexWords = IndicesPerTetrahedron * sizeof(std::uint32_t) / 8;
  static_assert(VertexWords * 8 == VerticesPerTetrahedron * sizeof(TetVertex) &&
      IndexWords * 8 == IndicesPerTetrahedron * sizeof(std::uint32_t),
    "a slot is whole 8-byte words");
  if (streaming)
  {
    long long words[VertexWords + IndexWords];
    std::memcpy(words, source, VertexWords * 8);
    std::memcpy(words + VertexWords, sourceIndices, IndexWords * 8);
    auto* vertexWords = reinterpret_cast<long long*>(vertices);
    auto* indexWords = reinterpret_cast<long long*>(indices);
    for (std::size_t i = 0; i < VertexWords; ++i)
    {
      _mm_stream_si64(vertexWords + i, words[i]);
    }
    for (std::size_t i = 0; i < IndexWords; ++i)
    {
      _mm_stream_si64(indexWords + i, words[VertexWords + i]);
    }
    return;
  }
#endif
  (void)streaming;
  std::memcpy(vertices, source, VerticesPerTetrahedron * sizeof(TetVertex));
  std::memcpy(indices, sourceIndices, IndicesPerTetrahedron * sizeof(std::uint32_t));
}

/// Makes a thread's non-temporal stores visible before it leaves a parallel region.
inline void FinishStores()
{
#if defined(__x86_64__) || defined(_M_X64)
  _mm_sfence();
#endif
}

/// Whether both buffers allow 8-byte non-temporal stores.
inline bool CanStream(const TetVertex* vertices, const std::uint32_t* indices)
{
  return ((reinterpret_cast<std::uintptr_t>(vertices) | reinterpret_cast<std::uintptr_t>(indices)) &
           7u) == 0;
}

/// Whether fans can be stored at `fans` with 16-byte non-temporal stores (StoreFan).
inline bool CanStreamFans(const Fan* fans)
{
  return (reinterpret_cast<std::uintptr_t>(fans) & 15u) == 0;
}

/**
 * Copies a fan to its place with non-temporal 16-byte stores (SSE2, every x86-64) where
 * available (see the file comment): 8 stores a fan instead of 16 of 8 bytes. Streaming
 * requires a 16-byte aligned target (CanStreamFans).
 */
inline void StoreFan(const Fan& source, Fan* target, bool streaming)
{
#if defined(__x86_64__) || defined(_M_X64)
  if (streaming)
  {
    constexpr std::size_t Lanes = sizeof(Fan) / sizeof(__m128i);
    auto* targetLanes = reinterpret_cast<__m128i*>(target);
    for (std::size_t i = 0; i < Lanes; ++i)
    {
      _mm_stream_si128(targetLanes + i,
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(&source) + i));
    }
    return;
  }
#endif
  (void)streaming;
  *target = source;
}

} // namespace detail
} // namespace mtpt

#endif
