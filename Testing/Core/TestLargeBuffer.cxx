// SPDX-License-Identifier: BSD-3-Clause
// The frame's mesh-sized buffers (mtpt/LargeBuffer.h): aligned, advised as huge-page
// candidates when large, and ordinary vectors otherwise.
#include "mtpt/LargeBuffer.h"
#include "mtpt/Records.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace
{

bool AlignedTo(const void* p, std::size_t alignment)
{
  return reinterpret_cast<std::uintptr_t>(p) % alignment == 0;
}

/**
 * The flags (smaps' VmFlags) of the mapping that holds `address`, empty when the process's
 * mappings cannot be read.
 */
std::string MappingFlags(const void* address)
{
  std::ifstream smaps("/proc/self/smaps");
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);)
  {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> begin >> dash >> end && dash == '-')
    {
      inside = begin <= at && at < end;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0)
    {
      return line.substr(8);
    }
  }
  return {};
}

} // namespace

TEST(LargeBuffer, LargeBlocksStartOnAHugePage)
{
  mtpt::LargeVector<mtpt::SortKey> keys(mtpt::HugePageBytes / sizeof(mtpt::SortKey) + 1, 7);
  EXPECT_TRUE(AlignedTo(keys.data(), mtpt::HugePageBytes));
  EXPECT_EQ(keys.front(), 7u);
  EXPECT_EQ(keys.back(), 7u);
  // Small blocks keep their type's alignment: the projected points are a cache line each.
  mtpt::LargeVector<mtpt::ProjectedPoint> points(3);
  EXPECT_TRUE(AlignedTo(points.data(), alignof(mtpt::ProjectedPoint)));
  // Growing past the threshold, then copied and swapped: an ordinary vector.
  mtpt::LargeVector<std::uint32_t> list;
  for (std::uint32_t i = 0; i < (1u << 20); ++i)
  {
    list.push_back(i);
  }
  mtpt::LargeVector<std::uint32_t> copy = list;
  mtpt::LargeVector<std::uint32_t>().swap(list);
  EXPECT_TRUE(list.empty());
  ASSERT_EQ(copy.size(), std::size_t{ 1 } << 20);
  EXPECT_EQ(copy[12345], 12345u);
}

TEST(LargeBuffer, LargeBlocksAreOfferedHugePages)
{
  // Linux lists the advice among a mapping's flags ("hg": MADV_HUGEPAGE).
  mtpt::LargeVector<char> block(4 * mtpt::HugePageBytes, 1);
  const std::string flags = MappingFlags(block.data());
  if (flags.empty())
  {
    GTEST_SKIP() << "this system does not list its mappings' flags (/proc/self/smaps)";
  }
  EXPECT_NE(flags.find(" hg"), std::string::npos) << "flags: " << flags;
}

TEST(LargeBuffer, AnImpossibleSizeThrowsBeforeAllocating)
{
  // A size whose bytes overflow is refused before any allocator is asked.
  mtpt::LargeBufferAllocator<mtpt::Fan> fans;
  EXPECT_THROW(
    fans.allocate(static_cast<std::size_t>(-1) / sizeof(mtpt::Fan) + 1), std::bad_array_new_length);
}
