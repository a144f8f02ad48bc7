// PackedPairs round-trips any ascending, duplicate-free keys (pair keys and arbitrary 64-bit ones) across
// segment boundaries, walks from any segment, counts its heap bytes, and codes a pile's keys short.
#include "broadphase/packed_pairs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace {

using gpucol::PackedPairs;

std::vector<std::uint64_t> sortedUnique(std::vector<std::uint64_t> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

/// Pair keys (a < b) among `slots` slots, b within `reach` of a.
std::vector<std::uint64_t> randomPairKeys(std::mt19937_64& rng, std::size_t n, std::uint32_t slots,
                                          std::uint32_t reach) {
  std::vector<std::uint64_t> v(n);
  for (auto& k : v) {
    const std::uint32_t a = std::uint32_t(rng() % (slots - 1));
    const std::uint32_t b = std::min<std::uint32_t>(slots - 1, a + 1 + std::uint32_t(rng() % reach));
    k = (std::uint64_t(a) << 32) | b;
  }
  return sortedUnique(v);
}

TEST(PackedPairs, RoundTripsPairKeysAcrossSegments) {
  std::mt19937_64 rng(7);
  const std::size_t seg = PackedPairs::kSegmentKeys;
  for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(2), seg - 1, seg, seg + 1, 3 * seg + 17,
                        std::size_t(40000)}) {
    for (std::uint32_t reach : {2u, 50u, 1u << 20}) {
      std::vector<std::uint64_t> keys = randomPairKeys(rng, n, 1u << 21, reach);
      PackedPairs packed;
      packed.assign(keys);
      ASSERT_EQ(packed.size(), keys.size());
      ASSERT_EQ(packed.empty(), keys.empty());
      ASSERT_EQ(packed.toVector(), keys) << "n " << n << " reach " << reach;
    }
  }
}

TEST(PackedPairs, RoundTripsAnyAscendingKeys) {
  // Keys with a >= b, the largest slots, and jumps across the whole 64-bit range: the 32-bit wrap-around
  // deltas must still decode to the same keys.
  std::mt19937_64 rng(11);
  std::vector<std::uint64_t> keys{0,
                                  1,
                                  0xffffffffull,
                                  (1ull << 32),
                                  (5ull << 32) | 3,
                                  (5ull << 32) | 5,
                                  (5ull << 32) | 0xffffffffull,
                                  (0xfffffffeull << 32) | 7,
                                  0xffffffff00000000ull,
                                  0xffffffffffffffffull};
  for (int i = 0; i < 20000; ++i) keys.push_back(rng());
  keys = sortedUnique(keys);
  PackedPairs packed;
  packed.assign(keys);
  EXPECT_EQ(packed.toVector(), keys);
}

TEST(PackedPairs, PlainListsRoundTripAt8BytesAKey) {
  std::mt19937_64 rng(13);
  const std::vector<std::uint64_t> keys =
      randomPairKeys(rng, 3 * PackedPairs::kSegmentKeys + 5, 1u << 20, 1u << 20);
  PackedPairs plain, coded;
  plain.assign(keys, true);
  coded.assign(keys);
  EXPECT_EQ(plain.toVector(), keys);
  EXPECT_TRUE(plain.isPlain());
  EXPECT_FALSE(coded.isPlain());
  EXPECT_TRUE(PackedPairs().isPlain());
  EXPECT_TRUE(std::equal(keys.begin(), keys.end(), plain.plainKeys()));
  for (const PackedPairs* list : {&plain, &coded}) {  // forEach walks a plain list's array directly
    std::vector<std::uint64_t> walked;
    list->forEach([&](std::uint64_t key) { walked.push_back(key); });
    EXPECT_EQ(walked, keys);
  }
  EXPECT_GE(plain.bytes(), 8 * (keys.size() - plain.segments()));
  EXPECT_LT(coded.bytes(), plain.bytes());
  EXPECT_TRUE(PackedPairs::worthCoding(151, 100));
  EXPECT_FALSE(PackedPairs::worthCoding(150, 100));
}

TEST(PackedPairs, ReaderStartsAtAnySegment) {
  std::mt19937_64 rng(3);
  const std::vector<std::uint64_t> keys = randomPairKeys(rng, 5 * PackedPairs::kSegmentKeys, 1u << 17, 300);
  PackedPairs packed;
  packed.assign(keys);
  ASSERT_GE(packed.segments(), 2u);
  for (std::size_t s = 0; s < packed.segments(); ++s) {
    const std::size_t from = s * PackedPairs::kSegmentKeys;
    ASSERT_EQ(packed.segmentFirst(s), keys[from]);
    std::vector<std::uint64_t> walked;
    for (PackedPairs::Reader r(packed, s); !r.done(); r.next()) walked.push_back(r.key());
    ASSERT_EQ(walked, std::vector<std::uint64_t>(keys.begin() + std::ptrdiff_t(from), keys.end()));
  }
  EXPECT_TRUE(PackedPairs::Reader(packed, packed.segments()).done());
}

TEST(PackedPairs, CodesAPilesKeysShortAndCountsItsBytes) {
  // A pile: each slot overlaps a few slots with nearby numbers (made in order, resting near each other).
  std::vector<std::uint64_t> keys;
  for (std::uint32_t a = 0; a < 100000; ++a)
    for (std::uint32_t d : {1u, 2u, 7u, 40u, 90u}) keys.push_back((std::uint64_t(a) << 32) | (a + d));
  PackedPairs packed;
  packed.assign(keys);
  ASSERT_EQ(packed.toVector(), keys);
  // Per key: one byte for the delta, plus one for a's delta where a row starts: 1.2 bytes, within 2.
  EXPECT_LT(packed.bytes(), 2 * keys.size());
  EXPECT_GT(packed.bytes(), keys.size());  // a byte per key at least: the count is not made up
  PackedPairs other;
  packed.swap(other);
  EXPECT_TRUE(packed.empty());
  EXPECT_EQ(packed.bytes(), 0u);
  EXPECT_EQ(other.size(), keys.size());
  other.clear();
  EXPECT_EQ(other.bytes(), 0u);
  EXPECT_TRUE(PackedPairs::Reader(other).done());
}

}  // namespace
