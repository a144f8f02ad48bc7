// ReservedBlocks: blocks end to end in the reserved range, then from the heap once the range is full or where
// the system refuses it; every block usable, none moved, the contiguous part reported as it is.
#include "memory/reserved_blocks.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace {

constexpr std::size_t kBlockBytes = 14336;  // GridBroadphase's: 256 proxies of 56 bytes

/// Writes a pattern over every block and reads it back, so a block that is not writable or that overlaps
/// another shows.
void expectBlocksHoldTheirOwnBytes(const gpucol::ReservedBlocks& blocks) {
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    std::memset(blocks.block(i), int(i & 0xff), blocks.blockBytes());
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(blocks.block(i)) % 64, 0u) << "block " << i;
    EXPECT_EQ(blocks.table()[i], blocks.block(i));
  }
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const auto* bytes = static_cast<const unsigned char*>(blocks.block(i));
    EXPECT_EQ(bytes[0], i & 0xff) << "block " << i;
    EXPECT_EQ(bytes[blocks.blockBytes() - 1], i & 0xff) << "block " << i;
  }
}

TEST(ReservedBlocks, BlocksLieEndToEndAndNeverMove) {
  gpucol::ReservedBlocks blocks(kBlockBytes, std::size_t(1) << 24);
  EXPECT_EQ(blocks.base(), nullptr);
  EXPECT_EQ(blocks.contiguousBytes(), 0u);
  std::vector<void*> seen;
  for (int i = 0; i < 300; ++i) seen.push_back(blocks.add());
  ASSERT_EQ(blocks.size(), 300u);
  const auto* base = static_cast<const unsigned char*>(blocks.base());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i], blocks.block(i)) << "block " << i << " moved";
    EXPECT_EQ(blocks.block(i), base + i * kBlockBytes) << "block " << i << " is not where the range puts it";
  }
  EXPECT_EQ(blocks.contiguousBytes(), 300 * kBlockBytes);
  expectBlocksHoldTheirOwnBytes(blocks);
}

TEST(ReservedBlocks, BlocksPastAFullRangeComeFromTheHeap) {
  gpucol::ReservedBlocks blocks(kBlockBytes, 4);
  for (int i = 0; i < 7; ++i) blocks.add();
  ASSERT_EQ(blocks.size(), 7u);
  EXPECT_EQ(blocks.contiguousBytes(), 4 * kBlockBytes) << "the first four lie in the range";
  const auto* base = static_cast<const unsigned char*>(blocks.base());
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(blocks.block(i), base + i * kBlockBytes);
  expectBlocksHoldTheirOwnBytes(blocks);
}

TEST(ReservedBlocks, ARefusedReservationStillGivesEveryBlock) {
  // 2^62 bytes: more than any address space, so the reservation fails.
  gpucol::ReservedBlocks blocks(4096, std::size_t(1) << 50);
  for (int i = 0; i < 20; ++i) blocks.add();
  ASSERT_EQ(blocks.size(), 20u);
  EXPECT_EQ(blocks.contiguousBytes(), 4096u) << "only the first block is known to be one array";
  expectBlocksHoldTheirOwnBytes(blocks);
}

}  // namespace
