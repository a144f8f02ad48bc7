// The reference pair finder on scenes small enough to check by hand: touching boxes pair, holes and filters
// are honoured, keys come out sorted with the lower slot first, and the boxes read from records are the same.
#include "broadphase/brute_force_pair_finder.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace {

TEST(BruteForcePairFinder, TouchingHolesAndFilters) {
  // Slots: 0 and 1 touch along x; 2 overlaps 0 but is a hole; 3 overlaps 1 but its mask refuses 1's group;
  // 4 lies inside 0; 5 is far away.
  const float minX[] = {0, 1, 0.5f, 1.5f, 0.2f, 50}, maxX[] = {1, 2, 1.5f, 2.5f, 0.4f, 51};
  const float minY[] = {0, 0, 0, 0, 0.2f, 0}, maxY[] = {1, 1, 1, 1, 0.4f, 1};
  const std::int32_t group[] = {1, 1, 1, 2, 1, 1}, mask[] = {-1, -1, -1, ~1, -1, -1};
  const std::uint8_t flags[] = {gpucol::kProxyActive, gpucol::kProxyActive, 0,
                                gpucol::kProxyActive, gpucol::kProxyActive, gpucol::kProxyActive};
  gpucol::ProxyArrays p;
  p.count = 6;
  p.minX = minX, p.maxX = maxX, p.minY = minY, p.maxY = maxY, p.minZ = minY, p.maxZ = maxY;
  p.group = group, p.mask = mask, p.flags = flags;
  const std::vector<std::uint64_t> expected = {gpucol::makePairKey(0, 1), gpucol::makePairKey(0, 4)};
  EXPECT_EQ(gpucol::BruteForcePairFinder::pairsOf(p), expected);
  gpucol::BruteForcePairFinder finder;
  std::vector<std::uint64_t> pairs = {7};
  finder.findPairs(p, gpucol::PairFinderOptions{}, pairs);
  EXPECT_EQ(pairs, expected);
  EXPECT_EQ(finder.stats().candidates, 10u);  // 5 active proxies
  EXPECT_FALSE(finder.stats().usedGrid);
}

}  // namespace
