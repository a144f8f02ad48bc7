// The radix sort against std::stable_sort on the sorted bits, serial and in chunks, on random keys of the
// widths its callers use.
#include "sorting/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace gpucol {
namespace {

template <class Key>
void expectStableSortOrder(std::size_t n, unsigned lowBit, unsigned keyBits, unsigned maxDigitBits,
                           std::size_t chunks) {
  std::mt19937_64 random(n * 131 + keyBits * 7 + chunks);
  const Key keyMask =
      keyBits + lowBit >= 8 * sizeof(Key) ? Key(~Key(0)) : Key((Key(1) << (keyBits + lowBit)) - 1);
  std::vector<Key> keys(n);
  for (Key& k : keys) k = Key(random()) & keyMask;
  std::vector<Key> expected = keys;
  const Key sortedMask = Key(keyMask >> lowBit << lowBit);
  std::stable_sort(expected.begin(), expected.end(),
                   [&](Key a, Key b) { return (a & sortedMask) < (b & sortedMask); });
  std::vector<Key> scratch(n);
  const RadixDigits digits(keyBits, maxDigitBits);
  std::vector<std::uint32_t> counts(std::max<std::size_t>(1, chunks) * digits.buckets());
  const Key* sorted = radixSort(keys.data(), scratch.data(), n, lowBit, digits, counts.data(), chunks);
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), sorted))
      << n << " keys of " << keyBits << " bits above " << lowBit << ", " << chunks << " chunks";
}

TEST(RadixSort, MatchesStableSortOnRandomKeys) {
  for (std::size_t n :
       {std::size_t(0), std::size_t(1), std::size_t(7), std::size_t(1000), std::size_t(70000)}) {
    for (std::size_t chunks : {std::size_t(1), std::size_t(3), std::size_t(16)}) {
      expectStableSortOrder<std::uint64_t>(n, 0, 40, 11, chunks);
      expectStableSortOrder<std::uint64_t>(n, 17, 34, 13, chunks);
      expectStableSortOrder<std::uint32_t>(n, 0, 27, 11, chunks);
      expectStableSortOrder<std::uint32_t>(n, 0, 5, 11, chunks);
    }
  }
}

TEST(RadixSort, SkipsDigitsEveryKeyShares) {
  // High bits all zero: the passes over them leave the keys where they are, and the result is still sorted.
  std::vector<std::uint64_t> keys = {5, 3, 9, 3, 0, 7}, scratch(keys.size());
  std::uint32_t counts[1 << 4];
  const std::uint64_t* sorted =
      radixSort(keys.data(), scratch.data(), keys.size(), 0, RadixDigits(16, 4), counts);
  EXPECT_EQ(std::vector<std::uint64_t>(sorted, sorted + keys.size()),
            (std::vector<std::uint64_t>{0, 3, 3, 5, 7, 9}));
}

TEST(RadixDigits, FewestPassesOfEvenWidth) {
  EXPECT_EQ(RadixDigits(0, 11).passes, 0u);
  EXPECT_EQ(RadixDigits(30, 13).passes, 3u);
  EXPECT_EQ(RadixDigits(30, 13).bits, 10u);
  EXPECT_EQ(RadixDigits(38, 13).bits, 13u);
  EXPECT_EQ(RadixDigits(34, 11).passes, 4u);
  EXPECT_EQ(RadixDigits(34, 11).bits, 9u);
}

}  // namespace
}  // namespace gpucol
