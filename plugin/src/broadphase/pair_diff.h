#pragma once
// Diff of two sorted pair-key lists: the step that turns "the pairs overlapping now" into the few calls
// that keep an incremental pair cache in sync (DESIGN.md, data flow: diff with last step →
// addOverlappingPair / removeOverlappingPair). Surviving pairs are not touched, so Bullet keeps their
// collision algorithms and persistent manifolds.
#include <cstdint>
#include <vector>

namespace gpucol {

/// Walks a sorted key vector the way PackedPairs::Reader walks a coded list.
class SortedKeyReader {
 public:
  explicit SortedKeyReader(const std::vector<std::uint64_t>& keys)
      : m_at(keys.data()), m_end(keys.data() + keys.size()) {}
  bool done() const { return m_at == m_end; }
  std::uint64_t key() const { return *m_at; }
  void next() { ++m_at; }

 private:
  const std::uint64_t* m_at;
  const std::uint64_t* m_end;
};

/// Merges two readers (done/key/next) over sorted, duplicate-free keys in one linear walk, in key order:
/// onAdded(key) for keys only in `now`, onRemoved(key) for keys only in `before`, onKept(key) for both.
template <typename BeforeReader, typename NowReader, typename Added, typename Removed, typename Kept>
void diffSortedReaders(BeforeReader before, NowReader now, Added&& onAdded, Removed&& onRemoved,
                       Kept&& onKept) {
  while (!before.done() && !now.done()) {
    const std::uint64_t b = before.key(), n = now.key();
    if (b < n) {
      onRemoved(b);
      before.next();
    } else if (n < b) {
      onAdded(n);
      now.next();
    } else {
      onKept(n);
      before.next(), now.next();
    }
  }
  for (; !before.done(); before.next()) onRemoved(before.key());
  for (; !now.done(); now.next()) onAdded(now.key());
}

/// diffSortedReaders over two sorted key vectors.
template <typename Added, typename Removed, typename Kept>
void diffSortedPairs(const std::vector<std::uint64_t>& before, const std::vector<std::uint64_t>& now,
                     Added&& onAdded, Removed&& onRemoved, Kept&& onKept) {
  diffSortedReaders(SortedKeyReader(before), SortedKeyReader(now), onAdded, onRemoved, onKept);
}

}  // namespace gpucol
