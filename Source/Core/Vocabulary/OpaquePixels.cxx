// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/OpaquePixels.h"

#include <algorithm>
#include <atomic>

namespace mtpt
{

namespace
{
/// Versions are unique across every object of the process, so that a result keyed on one
/// object's bits never matches another's.
std::uint64_t NextStamp()
{
  static std::atomic<std::uint64_t> next{ 1 };
  return next.fetch_add(1, std::memory_order_relaxed) + 1;
}
} // namespace

void OpaquePixels::Reset(int width, int height)
{
  this->ImageWidth = std::max(0, width);
  this->ImageHeight = std::max(0, height);
  this->RowWords = (this->ImageWidth + BitsPerWord - 1) / BitsPerWord;
  this->Bits.assign(static_cast<std::size_t>(this->RowWords) * this->ImageHeight, 0);
  this->AnyOpaque = false;
  this->Stamp = NextStamp();
}

void OpaquePixels::Marked(bool anyOpaque)
{
  this->AnyOpaque = anyOpaque;
  this->Stamp = NextStamp();
}

void OpaquePixels::Release()
{
  std::vector<std::uint64_t>().swap(this->Bits);
  this->ImageWidth = this->ImageHeight = this->RowWords = 0;
  this->AnyOpaque = false;
  this->Stamp = NextStamp();
}

} // namespace mtpt
