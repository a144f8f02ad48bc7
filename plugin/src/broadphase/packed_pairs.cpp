#include "broadphase/packed_pairs.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <iterator>
#include <utility>

namespace gpucol {

std::size_t PackedPairs::bytes() const {
  std::size_t bytes = m_segments.capacity() * sizeof(Segment);
  for (const Segment& s : m_segments) bytes += s.code.capacity();
  return bytes + m_plain.capacity() * sizeof(std::uint64_t);
}

void PackedPairs::clear() {
  std::vector<Segment>().swap(m_segments);
  std::vector<std::uint64_t>().swap(m_plain);
  m_size = 0;
}

void PackedPairs::swap(PackedPairs& other) noexcept {
  m_segments.swap(other.m_segments);
  m_plain.swap(other.m_plain);
  std::swap(m_size, other.m_size);
}

void PackedPairs::assign(const std::uint64_t* keys, std::size_t n, bool plain) {
  if (plain) {
    clear();
    m_plain.assign(keys, keys + n);  // exactly: assigned from empty
    m_size = n;
    return;
  }
  resetSegments((n + kSegmentKeys - 1) / kSegmentKeys);
  tbb::parallel_for(std::size_t(0), m_segments.size(), [&](std::size_t i) {
    const std::uint64_t* first = keys + i * kSegmentKeys;
    setSegment(i, std::min(kSegmentKeys, n - i * kSegmentKeys), [first](std::size_t k) { return first[k]; });
  });
  finishSegments();
}

void PackedPairs::adopt(std::vector<std::uint64_t>&& keys) {
  clear();
  m_plain.swap(keys);
  m_size = m_plain.size();
}

void PackedPairs::resetSegments(std::size_t count) {
  clear();  // the old code is not held beside the new
  m_segments.resize(count);
}

void PackedPairs::finishSegments() {
  m_segments.erase(
      std::remove_if(m_segments.begin(), m_segments.end(), [](const Segment& s) { return s.count == 0; }),
      m_segments.end());
  // The table at its size: made with a slot per bucket, it may have many more than segments left.
  if (m_segments.capacity() > m_segments.size())
    std::vector<Segment>(std::make_move_iterator(m_segments.begin()),
                         std::make_move_iterator(m_segments.end()))
        .swap(m_segments);
  m_size = 0;
  for (const Segment& s : m_segments) m_size += s.count;
}

PackedPairs::Reader::Reader(const PackedPairs& pairs, std::size_t segment)
    : m_pairs(&pairs), m_segment(segment) {
  enterSegment();
}

void PackedPairs::Reader::enterSegment() {
  const std::vector<std::uint64_t>& plain = m_pairs->m_plain;
  if (!plain.empty()) {
    // Walked in place; a reader that starts past the end is done.
    m_done = m_segment * kSegmentKeys >= plain.size();
    if (m_done) return;
    m_plainAt = plain.data() + m_segment * kSegmentKeys, m_plainEnd = plain.data() + plain.size();
    m_a = std::uint32_t(*m_plainAt >> 32), m_b = std::uint32_t(*m_plainAt);
    return;
  }
  if (m_segment >= m_pairs->m_segments.size()) {
    m_done = true;
    return;
  }
  const Segment& s = m_pairs->m_segments[m_segment];
  m_code = s.code.data();
  m_left = s.count - 1;
  m_a = std::uint32_t(s.first >> 32), m_b = std::uint32_t(s.first);
}

std::vector<std::uint64_t> PackedPairs::toVector() const {
  std::vector<std::uint64_t> keys;
  keys.reserve(m_size);
  forEach([&](std::uint64_t key) { keys.push_back(key); });
  return keys;
}

}  // namespace gpucol
