// Growing scratch to an exact size (exact_vector.h) and PairBuckets' byte count against the heap
// (counting_heap.h): bytes() after packInto is the high-water mark of the whole, so the heap must never have
// held more, also while a thread's sort buffers grew from one bucket to a larger one (they once held the old
// and the new arrays at once).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/packed_pairs.h"
#include "broadphase/pair_buckets.h"
#include "counting_heap.h"
#include "memory/exact_vector.h"

namespace {

TEST(ExactVector, GrowingFreesTheOldArrayFirst) {
  std::vector<std::uint32_t> v(1000);
  const gpucol::test::HeapOfStep heap = gpucol::test::measureHeap([&] { gpucol::resizeExact(v, 2000); });
  EXPECT_EQ(v.size(), 2000u);
  EXPECT_EQ(v.capacity(), 2000u);
  EXPECT_EQ(heap.kept, std::ptrdiff_t(4000));
  EXPECT_EQ(heap.mark, heap.kept) << "the old array was still held when the new one was allocated";
}

/// Packs keys whose buckets (of lower slot a: a >> 10 for 2^15 slots, pair_buckets.cpp's rule) hold
/// `sizes[i]` keys each, on one thread, and checks that the heap never held more than the count says.
void expectPackingHeldWhatItCounts(const std::vector<std::uint32_t>& sizes) {
  constexpr std::uint32_t kSlots = 20000;  // 20 buckets of 1,024 slots
  ASSERT_EQ(sizes.size(), 20u);
  gpucol::PairBuckets buckets;
  ASSERT_TRUE(gpucol::PairBuckets::fits(kSlots));
  buckets.reset(kSlots, 1);
  std::vector<std::uint64_t> keys;
  for (std::uint32_t bucket = 0; bucket < 20; ++bucket)
    for (std::uint32_t k = 0; k < sizes[bucket]; ++k) {
      const std::uint32_t a = bucket * 1024 + k % 500, b = kSlots - 1 - k / 500;  // a < b, all distinct
      keys.push_back((std::uint64_t(a) << 32) | b);
    }
  buckets.addToPiece(0, keys);
  const std::size_t keyCount = keys.size();
  std::vector<std::uint64_t>().swap(keys);
  const std::size_t countedBefore = buckets.bytes();
  gpucol::PackedPairs out;
  const gpucol::test::HeapOfStep heap = gpucol::test::measureHeap([&] { buckets.packInto(out); });
  ASSERT_EQ(out.size(), keyCount);
  // All that packInto allocates stays until release(): the buffers (in bytes()) and the coded list.
  const std::ptrdiff_t counted = std::ptrdiff_t(buckets.bytes() - countedBefore + out.bytes());
  EXPECT_NEAR(double(heap.kept), double(counted), 1024.0);
  EXPECT_LE(heap.mark, counted + 1024) << "held beyond what bytes() counts while packing";
}

TEST(PairBucketsMemory, PackingNeverHoldsMoreThanItCounts) {
  // One thread sorts every bucket in turn, so its buffers grow at each bucket larger than those before.
  // The growth shows at the peak when it comes last (the coded list is then nearly whole): a large bucket
  // just after a slightly smaller one at one end, and the same mirrored, so one of the two has it last
  // whichever way the buckets are taken.
  tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<std::uint32_t> sizes(20, 100);
  sizes[18] = 9000, sizes[19] = 10000;
  expectPackingHeldWhatItCounts(sizes);
  std::vector<std::uint32_t> mirrored(sizes.rbegin(), sizes.rend());
  expectPackingHeldWhatItCounts(mirrored);
}

}  // namespace
