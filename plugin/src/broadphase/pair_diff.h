#pragma once
// Diff of two sorted pair-key lists: the step that turns "the pairs overlapping now" into the few calls
// that keep an incremental pair cache in sync (DESIGN.md, data flow: diff with last step →
// addOverlappingPair / removeOverlappingPair). Surviving pairs are not touched, so Bullet keeps their
// collision algorithms and persistent manifolds.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "broadphase/packed_pairs.h"

namespace gpucol {

/// Walks sorted keys held plain (a vector, or a range of one) the way PackedPairs::Reader walks a coded list.
class SortedKeyReader {
 public:
  explicit SortedKeyReader(const std::vector<std::uint64_t>& keys)
      : m_at(keys.data()), m_end(keys.data() + keys.size()) {}
  SortedKeyReader(const std::uint64_t* begin, const std::uint64_t* end) : m_at(begin), m_end(end) {}
  bool done() const { return m_at == m_end; }
  std::uint64_t key() const { return *m_at; }
  void next() { ++m_at; }
  /// Moves this reader and `other` past the keys they share from here on (both at equal keys, or done).
  void skipShared(SortedKeyReader& other) {
    const std::uint64_t *a = m_at, *b = other.m_at;
    // Four at a time while they agree: a step keeps most of its pairs, so runs are long.
    while (m_end - a >= 4 && other.m_end - b >= 4 &&
           ((a[0] ^ b[0]) | (a[1] ^ b[1]) | (a[2] ^ b[2]) | (a[3] ^ b[3])) == 0)
      a += 4, b += 4;
    while (a != m_end && b != other.m_end && *a == *b) ++a, ++b;
    m_at = a, other.m_at = b;
  }

 private:
  const std::uint64_t* m_at;
  const std::uint64_t* m_end;
};

/// The onKept of a diff that has nothing to do for kept keys: two plain readers then skip shared runs in a
/// tight loop (SortedKeyReader::skipShared) instead of one key at a time.
struct IgnoreKept {
  void operator()(std::uint64_t) const {}
};

/// Merges two readers (done/key/next) over sorted, duplicate-free keys in one linear walk, in key order:
/// onAdded(key) for keys only in `now`, onRemoved(key) for keys only in `before`, onKept(key) for both.
template <typename BeforeReader, typename NowReader, typename Added, typename Removed, typename Kept>
void diffSortedReaders(BeforeReader before, NowReader now, Added&& onAdded, Removed&& onRemoved,
                       Kept&& onKept) {
  constexpr bool skipRuns = std::is_same_v<std::decay_t<Kept>, IgnoreKept> &&
                            std::is_same_v<BeforeReader, SortedKeyReader> &&
                            std::is_same_v<NowReader, SortedKeyReader>;
  while (!before.done() && !now.done()) {
    const std::uint64_t b = before.key(), n = now.key();
    if (b < n) {
      onRemoved(b);
      before.next();
    } else if (n < b) {
      onAdded(n);
      now.next();
    } else if constexpr (skipRuns) {
      before.skipShared(now);
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

/// A reader that stops at the first key not below `end`.
template <typename Reader>
class BoundedReader {
 public:
  BoundedReader(Reader reader, std::uint64_t end, bool unbounded)
      : m_reader(reader), m_end(end), m_unbounded(unbounded) {}
  bool done() const { return m_reader.done() || (!m_unbounded && m_reader.key() >= m_end); }
  std::uint64_t key() const { return m_reader.key(); }
  void next() { m_reader.next(); }

 private:
  Reader m_reader;
  std::uint64_t m_end;
  bool m_unbounded;
};

/// Keys of both lists from which diffCodedInParts walks its parts in parallel.
constexpr std::size_t kParallelDiffKeys = 4 * PackedPairs::kSegmentKeys;

/// Parts of the key range that diffCodedInParts walks: one per segment of `now`, or one when it has none.
inline std::size_t diffParts(const PackedPairs& now) {
  return std::max<std::size_t>(1, now.segments());
}

/// The diff of two coded lists cut into diffParts(now) parts of the key range (`now`'s segments), walked in
/// parallel (long lists): walkPart(part, begin, before, now) gets readers over both lists' keys of part
/// `part`, which starts at key `begin` (the key range's start for part 0) and ends where the next starts.
/// The readers are SortedKeyReaders when both lists are plain, else BoundedReaders over coded ones.
template <typename WalkPart>
void diffCodedInParts(const PackedPairs& before, const PackedPairs& now, WalkPart&& walkPart) {
  const std::size_t parts = diffParts(now);
  const bool plain = before.isPlain() && now.isPlain();
  auto walk = [&](std::size_t part) {
    const std::uint64_t begin = part == 0 ? 0 : now.segmentFirst(part);
    const bool last = part + 1 >= parts;
    const std::uint64_t end = last ? 0 : now.segmentFirst(part + 1);
    if (plain) {
      // Plain arrays: the part's keys of `before` found by binary search, walked with raw pointers.
      const std::uint64_t *b = before.plainKeys(), *bEnd = b + before.size();
      const std::uint64_t *n = now.plainKeys(), *nEnd = n + now.size();
      const std::uint64_t* from = part == 0 ? b : std::lower_bound(b, bEnd, begin);
      const std::uint64_t* to = last ? bEnd : std::lower_bound(from, bEnd, end);
      const std::uint64_t* nowFrom = n + std::min(now.size(), part * PackedPairs::kSegmentKeys);
      const std::uint64_t* nowTo = last ? nEnd : nowFrom + PackedPairs::kSegmentKeys;
      walkPart(part, begin, SortedKeyReader(from, to), SortedKeyReader(nowFrom, nowTo));
      return;
    }
    // The segment of `before` that holds `begin`: the last one starting at or below it.
    std::size_t lo = 0, hi = before.segments();
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      (before.segmentFirst(mid) <= begin ? lo : hi) = mid;
    }
    BoundedReader<PackedPairs::Reader> b(PackedPairs::Reader(before, lo), end, last);
    while (!b.done() && b.key() < begin) b.next();
    walkPart(part, begin, b, BoundedReader<PackedPairs::Reader>(PackedPairs::Reader(now, part), end, last));
  };
  // Short lists in one thread: handing their few parts to threads cost more than the walk (sleeping scene).
  if (before.size() + now.size() < kParallelDiffKeys) {
    for (std::size_t part = 0; part < parts; ++part) walk(part);
  } else {
    tbb::parallel_for(std::size_t(0), parts, walk);
  }
}

}  // namespace gpucol
