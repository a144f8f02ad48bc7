#include "opencl/host/radix_sort.h"

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "opencl_test_device.h"

namespace gpucol::opencl {
namespace {

// Reference: std::stable_sort of (key, value) by the key's low keyBits bits.
void expectSortMatchesStableSort(OpenClRadixSort& sorter, std::size_t n, unsigned keyBits,
                                 std::uint64_t keyRange, std::uint32_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<std::uint64_t> key(0, keyRange);
  std::vector<std::uint64_t> keys(n);
  std::vector<std::uint32_t> values(n);
  for (std::size_t i = 0; i < n; ++i) {
    keys[i] = key(random);
    values[i] = static_cast<std::uint32_t>(i);  // original position: checks stability
  }
  const std::uint64_t mask = keyBits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << keyBits) - 1;
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) {
    order[i] = i;
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return (keys[a] & mask) < (keys[b] & mask); });

  std::vector<std::uint64_t> sortedKeys = keys;
  std::vector<std::uint32_t> sortedValues = values;
  sorter.sort(sortedKeys, sortedValues, keyBits);
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if ((sortedKeys[i] != keys[order[i]] || sortedValues[i] != values[order[i]]) && mismatches++ < 5) {
      ADD_FAILURE() << "n = " << n << ", keyBits = " << keyBits << ": position " << i << " holds ("
                    << sortedKeys[i] << ", " << sortedValues[i] << "), expected (" << keys[order[i]] << ", "
                    << values[order[i]] << ")";
    }
  }
  EXPECT_EQ(mismatches, 0u) << "n = " << n;
  // Keys alone (sortKeys): the same keys in the same order.
  std::vector<std::uint64_t> keysAlone = keys;
  sorter.sortKeys(keysAlone, keyBits);
  mismatches = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (keysAlone[i] != keys[order[i]] && mismatches++ < 5) {
      ADD_FAILURE() << "keys alone, n = " << n << ", keyBits = " << keyBits << ": position " << i << " holds "
                    << keysAlone[i] << ", expected " << keys[order[i]];
    }
  }
  EXPECT_EQ(mismatches, 0u) << "keys alone, n = " << n;
}

TEST(OpenClRadixSort, MatchesStableSortOnAwkwardLengths) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClRadixSort sorter(context);
  std::uint32_t seed = 7;
  for (std::size_t n : {0, 1, 2, 3, 17, 255, 256, 257, 1023, 1024, 1025, 4095, 4096, 4097, 65537}) {
    expectSortMatchesStableSort(sorter, n, 64, ~std::uint64_t{0}, seed++);
    // Few distinct keys: long runs of equal keys, where stability shows.
    expectSortMatchesStableSort(sorter, n, 64, 5, seed++);
  }
}

TEST(OpenClRadixSort, SortsOnlyTheRequestedLowBits) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClRadixSort sorter(context);
  // Odd widths (an odd number of passes ends in the scratch buffer and is copied back) and high bits
  // that the sort must ignore.
  expectSortMatchesStableSort(sorter, 10007, 1, ~std::uint64_t{0}, 11);
  expectSortMatchesStableSort(sorter, 10007, 13, ~std::uint64_t{0}, 12);
  expectSortMatchesStableSort(sorter, 10007, 34, ~std::uint64_t{0}, 13);
  EXPECT_THROW(sorter.sort(cl::Buffer(), cl::Buffer(), 10, 0), std::invalid_argument);
  EXPECT_THROW(sorter.sort(cl::Buffer(), cl::Buffer(), 10, 65), std::invalid_argument);
}

TEST(OpenClRadixSort, KeysAloneTakeNoValueScratch) {
  GPUCOL_REQUIRE_OPENCL(context);
  const std::size_t n = 100000;
  std::vector<std::uint64_t> keys(n);
  for (std::size_t i = 0; i < n; ++i) keys[i] = (i * 2654435761u) % 1000003u;
  std::vector<std::uint32_t> values(n, 0);
  std::vector<std::uint64_t> keysWithValues = keys;
  OpenClRadixSort alone(context), withValues(context);
  alone.sortKeys(keys, 20);
  withValues.sort(keysWithValues, values, 20);
  EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  EXPECT_EQ(keys, keysWithValues);
  EXPECT_EQ(withValues.bytes() - alone.bytes(), n * 4) << "value arrays were made for keys alone";
  EXPECT_GE(alone.bytes(), n * 8) << "the second key array";
  alone.releaseScratch();
  EXPECT_LT(alone.bytes(), n) << "only the scan's scratch stays";
}

TEST(OpenClRadixSort, MatchesStableSortOnAMillionPairs) {
  GPUCOL_REQUIRE_OPENCL(context);
  OpenClRadixSort sorter(context);
  expectSortMatchesStableSort(sorter, 1000000, 32, 0xffffffffu, 21);
}

}  // namespace
}  // namespace gpucol::opencl
