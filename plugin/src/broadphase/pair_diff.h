#pragma once
// Diff of two sorted pair-key lists: the step that turns "the pairs overlapping now" into the few calls
// that keep an incremental pair cache in sync (DESIGN.md, data flow: diff with last step →
// addOverlappingPair / removeOverlappingPair). Surviving pairs are not touched, so Bullet keeps their
// collision algorithms and persistent manifolds.
#include <cstdint>
#include <vector>

namespace gpucol {

/// Merges the sorted, duplicate-free lists `before` and `now` in one linear walk, in key order:
/// onAdded(key) for keys only in `now`, onRemoved(key) for keys only in `before`, onKept(key) for both.
template <typename Added, typename Removed, typename Kept>
void diffSortedPairs(const std::vector<std::uint64_t>& before, const std::vector<std::uint64_t>& now,
                     Added&& onAdded, Removed&& onRemoved, Kept&& onKept) {
  std::size_t i = 0, j = 0;
  while (i < before.size() || j < now.size()) {
    if (j == now.size() || (i < before.size() && before[i] < now[j])) {
      onRemoved(before[i++]);
    } else if (i == before.size() || now[j] < before[i]) {
      onAdded(now[j++]);
    } else {
      onKept(now[j]);
      ++i, ++j;
    }
  }
}

}  // namespace gpucol
