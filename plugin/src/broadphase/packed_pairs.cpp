#include "broadphase/packed_pairs.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

namespace gpucol {
namespace {

std::size_t varintBytes(std::uint64_t v) {
  std::size_t n = 1;
  while (v >= 0x80) v >>= 7, ++n;
  return n;
}

std::uint8_t* writeVarint(std::uint8_t* out, std::uint64_t v) {
  while (v >= 0x80) *out++ = std::uint8_t(v | 0x80), v >>= 7;
  *out++ = std::uint8_t(v);
  return out;
}

/// Calls code(v) for the varints of keys[1, n) after keys[0] (the coding in packed_pairs.h).
template <typename Code>
void forEachCode(const std::uint64_t* keys, std::size_t n, Code&& code) {
  std::uint32_t a = std::uint32_t(keys[0] >> 32), b = std::uint32_t(keys[0]);
  for (std::size_t i = 1; i < n; ++i) {
    const std::uint32_t ka = std::uint32_t(keys[i] >> 32), kb = std::uint32_t(keys[i]);
    if (ka == a) {
      code(std::uint64_t(std::uint32_t(kb - b - 1)) << 1);
    } else {
      code((std::uint64_t(std::uint32_t(kb - ka - 1)) << 1) | 1);
      code(std::uint64_t(std::uint32_t(ka - a - 1)));
    }
    a = ka, b = kb;
  }
}

}  // namespace

std::size_t PackedPairs::bytes() const {
  std::size_t bytes = m_segments.capacity() * sizeof(Segment);
  for (const Segment& s : m_segments) bytes += s.code.capacity();
  return bytes;
}

void PackedPairs::clear() {
  std::vector<Segment>().swap(m_segments);
  m_size = 0;
}

void PackedPairs::swap(PackedPairs& other) noexcept {
  m_segments.swap(other.m_segments);
  std::swap(m_size, other.m_size);
}

void PackedPairs::assign(const std::uint64_t* keys, std::size_t n) {
  clear();  // the old code is not held beside the new
  const std::size_t count = (n + kSegmentKeys - 1) / kSegmentKeys;
  m_segments.resize(count);
  m_size = n;
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
    const std::uint64_t* first = keys + i * kSegmentKeys;
    const std::size_t keysHere = std::min(kSegmentKeys, n - i * kSegmentKeys);
    Segment& s = m_segments[i];
    s.first = first[0];
    s.count = std::uint32_t(keysHere);
    std::size_t size = 0;
    forEachCode(first, keysHere, [&](std::uint64_t v) { size += varintBytes(v); });
    s.code.resize(size);  // exactly: a vector sized from empty allocates what it is asked for
    std::uint8_t* out = s.code.data();
    forEachCode(first, keysHere, [&](std::uint64_t v) { out = writeVarint(out, v); });
  });
}

PackedPairs::Reader::Reader(const PackedPairs& pairs, std::size_t segment)
    : m_pairs(&pairs), m_segment(segment) {
  enterSegment();
}

void PackedPairs::Reader::enterSegment() {
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
