// PairBuckets against a plain sort: pieces of unsorted pair keys, each added in parts, come out as one
// sorted, coded list, for slot counts from a handful (no bucket bits) to 2^20 (32-bit entries exactly).
#include "broadphase/pair_buckets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace {

TEST(PairBuckets, PiecesComeOutSortedAndCoded) {
  std::mt19937_64 rng(17);
  int trial = 0;
  for (std::uint32_t slots : {2u, 3u, 200u, 256u, 257u, 5000u, 100000u, 1u << 20}) {
    for (std::size_t total : {std::size_t(0), std::size_t(1), std::size_t(50), std::size_t(30000)}) {
      // Distinct pair keys (a < b) over `slots` slots, some slots with long rows (a huge box's pairs).
      std::vector<std::uint64_t> keys;
      for (std::size_t i = 0; i < total; ++i) {
        const std::uint32_t a = i % 7 == 0 ? 0 : std::uint32_t(rng() % (slots - 1));
        const std::uint32_t b = a + 1 + std::uint32_t(rng() % (slots - 1 - a));
        keys.push_back((std::uint64_t(a) << 32) | b);
      }
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
      std::vector<std::uint64_t> shuffled = keys;
      std::shuffle(shuffled.begin(), shuffled.end(), rng);
      // Split at random points into pieces, some empty.
      const std::size_t pieces = 1 + rng() % 9;
      std::vector<std::size_t> cut{0, shuffled.size()};
      for (std::size_t p = 1; p < pieces; ++p) cut.push_back(shuffled.empty() ? 0 : rng() % shuffled.size());
      std::sort(cut.begin(), cut.end());
      gpucol::PairBuckets buckets;
      ASSERT_TRUE(gpucol::PairBuckets::fits(slots));
      buckets.reset(slots, cut.size() - 1);
      // Each piece added in one to three parts (a producer hands its keys over as its list fills).
      for (std::size_t p = 0; p + 1 < cut.size(); ++p) {
        const std::size_t parts = 1 + rng() % 3;
        for (std::size_t k = 0; k < parts; ++k) {
          const std::size_t length = cut[p + 1] - cut[p];
          auto at = [&](std::size_t i) {
            return shuffled.begin() + std::ptrdiff_t(cut[p] + length * i / parts);
          };
          buckets.addToPiece(p, std::vector<std::uint64_t>(at(k), at(k + 1)));
        }
      }
      ASSERT_EQ(buckets.size(), keys.size());
      gpucol::PackedPairs out;
      const bool plain = ++trial % 2 == 0;  // coded or plain segments alike
      buckets.packInto(out, plain);
      ASSERT_EQ(out.toVector(), keys) << slots << " slots, " << total << " keys";
      // 4 B per key in the pieces at least, until released.
      EXPECT_GE(buckets.bytes(), 4 * keys.size());
      buckets.release();
      EXPECT_EQ(buckets.bytes(), 0u);
      EXPECT_EQ(buckets.size(), 0u);
    }
  }
}

TEST(PairBuckets, EntriesFitUpTo2To20Slots) {
  EXPECT_TRUE(gpucol::PairBuckets::fits(1u << 20));
  EXPECT_FALSE(gpucol::PairBuckets::fits((1u << 20) + 1));
}

}  // namespace
