#include "broadphase/brute_force_pair_finder.h"

namespace gpucol {

std::vector<std::uint64_t> BruteForcePairFinder::pairsOf(const ProxyArrays& p) {
  // Deliberately naive and independent of the grid code: double comparisons, nested loops, keys in order.
  std::vector<std::uint64_t> pairs;
  for (std::uint32_t a = 0; a < p.count; ++a) {
    if (!(p.flags[a] & kProxyActive)) continue;
    for (std::uint32_t b = a + 1; b < p.count; ++b) {
      if (!(p.flags[b] & kProxyActive)) continue;
      const BoxCorners x = p.box(a), y = p.box(b);
      bool overlap = true;
      for (int k = 0; k < 3; ++k)
        overlap = overlap && double(x.lo[k]) <= double(y.hi[k]) && double(y.lo[k]) <= double(x.hi[k]);
      const bool filter = (p.group[a] & p.mask[b]) && (p.group[b] & p.mask[a]);
      if (overlap && filter) pairs.push_back((std::uint64_t(a) << 32) | b);
    }
  }
  return pairs;
}

void BruteForcePairFinder::findPairs(const ProxyArrays& proxies, const PairFinderOptions& /*options*/,
                                     std::vector<std::uint64_t>& pairs) {
  m_stats = PairFinderStats{};
  std::uint64_t active = 0;
  for (std::uint32_t s = 0; s < proxies.count; ++s) active += proxies.flags[s] & kProxyActive;
  m_stats.candidates = active * (active - (active > 0)) / 2;
  m_stats.rebinnedProxies = std::uint32_t(active);
  pairs = pairsOf(proxies);
}

}  // namespace gpucol
