#pragma once
// The reference pair finder: every pair of active proxies tested one by one, in double precision, with no
// grid and no mapping function, so that it shares no code with the finders it checks. The tests compare the
// CPU and OpenCL finders against it on random and real scenes (as Jolt keeps BroadPhaseBruteForce beside its
// fast broad phase); nothing in the plugin runs it.
#include <cstdint>
#include <string>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// All pairs of active proxies whose boxes overlap (touching counts) and pass Bullet's group/mask test, found
/// by testing every pair: the reference the other finders must match bit for bit.
class BruteForcePairFinder final : public PairFinder {
 public:
  /// The sorted pair keys of `proxies` (the options are not used).
  static std::vector<std::uint64_t> pairsOf(const ProxyArrays& proxies);

  /// Replaces `pairs` with pairsOf(proxies).
  void findPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                 std::vector<std::uint64_t>& pairs) override;
  /// Candidates tested and nothing else.
  const PairFinderStats& stats() const override { return m_stats; }
  /// "brute-force".
  std::string name() const override { return "brute-force"; }
  /// Reads boxes from the arrays or the records alike (ProxyArrays::box).
  bool readsBoxRecords() const override { return true; }

 private:
  PairFinderStats m_stats;
};

}  // namespace gpucol
