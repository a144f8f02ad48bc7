// MeshHostSort (opencl/host/mesh_host_sort.h) against std::stable_sort of (key, index): random keys of every
// width, with repeats and with runs that share high digits (the skipped passes), on both of its paths (packed
// radix sort, and the comparison sort when key and index do not fit in 64 bits).
#include "opencl/host/mesh_host_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace gpucol::test {
namespace {

void expectSortedAndRanked(const std::vector<std::uint64_t>& keys, unsigned keyBits,
                           opencl::MeshHostSort& sorter, const std::string& where) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> reference(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) reference[i] = {keys[i], std::uint32_t(i)};
  std::stable_sort(reference.begin(), reference.end(),
                   [](const auto& l, const auto& r) { return l.first < r.first; });
  std::vector<std::uint64_t> sorted;
  std::vector<std::uint32_t> rank;
  sorter.sortAndRank(keys, keyBits, sorted, rank);
  ASSERT_EQ(sorted.size(), keys.size()) << where;
  ASSERT_EQ(rank.size(), keys.size()) << where;
  for (std::size_t p = 0; p < keys.size(); ++p) {
    ASSERT_EQ(sorted[p], reference[p].first) << where << " at " << p;
    ASSERT_EQ(rank[reference[p].second], p) << where << " rank of " << reference[p].second;
  }
}

TEST(MeshHostSort, MatchesAStableSortAtEveryWidth) {
  std::mt19937_64 rng(20261121);
  opencl::MeshHostSort sorter;  // one sorter throughout: its buffers are reused between calls
  for (unsigned keyBits : {1u, 5u, 11u, 22u, 38u, 47u, 50u, 63u, 64u}) {
    for (std::size_t n :
         {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(1000), std::size_t(70000)}) {
      const std::uint64_t mask = keyBits == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << keyBits) - 1;
      std::vector<std::uint64_t> keys(n);
      for (std::uint64_t& k : keys) k = rng() & mask;
      expectSortedAndRanked(keys, keyBits, sorter, std::to_string(keyBits) + " bits, " + std::to_string(n));
      // Repeats, and high digits shared by every key (one pair of small meshes in a wide key).
      for (std::uint64_t& k : keys) k = ((k & 0x3ff) | ~std::uint64_t(0xfffff)) & mask;
      expectSortedAndRanked(keys, keyBits, sorter,
                            std::to_string(keyBits) + " bits, shared high digits, " + std::to_string(n));
    }
  }
}

TEST(MeshHostSort, RefusesKeysWiderThan64Bits) {
  opencl::MeshHostSort sorter;
  std::vector<std::uint64_t> sorted;
  std::vector<std::uint32_t> rank;
  EXPECT_THROW(sorter.sortAndRank({1, 2}, 65, sorted, rank), std::invalid_argument);
}

}  // namespace
}  // namespace gpucol::test
