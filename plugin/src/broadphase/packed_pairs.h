#pragma once
// A sorted pair-key list held delta-coded: what the broad phase keeps of the last step for its diff with
// the pair cache and for the pairs stage 11 carries over. Raw, a key takes 8 bytes; a pile holds several per
// proxy, and the step that holds the last list beside this step's went over the memory target (README,
// "At most 100 bytes per proxy plus 8 per pair"). Coded, a key takes about 2 bytes in a pile and 3-4 in a
// sparse cloud.
//
// Coding: the keys (a << 32 | b) are cut into segments of at most kSegmentKeys, each coded on its own (so
// that segments are coded, decoded and walked in parallel). A segment keeps its first key whole; each
// further key is one LEB128 varint, (b - previous b - 1) << 1 when its a is the previous key's, else
// ((b - a - 1) << 1) | 1 followed by a varint of (a - previous a - 1). All in 32-bit wrap-around arithmetic,
// so any ascending, duplicate-free keys round-trip (pair keys have a < b, which keeps the codes short).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace gpucol {

class PackedPairs {
 public:
  /// Keys per segment (the unit of parallel coding and walking).
  static constexpr std::size_t kSegmentKeys = 4096;

  /// Keys held.
  std::size_t size() const { return m_size; }
  bool empty() const { return m_size == 0; }
  /// Heap bytes held: the segment table and every segment's code.
  std::size_t bytes() const;
  /// Empties and frees.
  void clear();
  void swap(PackedPairs& other) noexcept;

  /// Replaces the contents with keys[0, n), which must ascend with no repeats; each segment is allocated at
  /// its size (counted first), segments coded in parallel.
  void assign(const std::uint64_t* keys, std::size_t n);
  void assign(const std::vector<std::uint64_t>& keys) { assign(keys.data(), keys.size()); }

  std::size_t segments() const { return m_segments.size(); }
  /// First key of segment `i`.
  std::uint64_t segmentFirst(std::size_t i) const { return m_segments[i].first; }

  /// Forward walk over the keys from the start of a segment.
  class Reader {
   public:
    explicit Reader(const PackedPairs& pairs, std::size_t segment = 0);
    bool done() const { return m_done; }
    /// The current key (not done()).
    std::uint64_t key() const { return (std::uint64_t(m_a) << 32) | m_b; }
    void next() {
      if (m_left == 0) {
        ++m_segment;
        enterSegment();
        return;
      }
      --m_left;
      const std::uint64_t v = readVarint();
      if (v & 1) {
        m_a += 1 + std::uint32_t(readVarint());
        m_b = m_a + 1 + std::uint32_t(v >> 1);
      } else {
        m_b += 1 + std::uint32_t(v >> 1);
      }
    }

   private:
    std::uint64_t readVarint() {
      std::uint64_t v = *m_code & 0x7f;
      for (int shift = 7; *m_code++ & 0x80; shift += 7) v |= std::uint64_t(*m_code & 0x7f) << shift;
      return v;
    }
    void enterSegment();
    const PackedPairs* m_pairs;
    std::size_t m_segment;
    const std::uint8_t* m_code = nullptr;
    std::uint32_t m_left = 0;  // keys of this segment after the current one
    std::uint32_t m_a = 0, m_b = 0;
    bool m_done = false;
  };

  /// Calls f(key) for every key, in order.
  template <typename F>
  void forEach(F&& f) const {
    for (Reader r(*this); !r.done(); r.next()) f(r.key());
  }
  /// The keys, decoded.
  std::vector<std::uint64_t> toVector() const;

 private:
  struct Segment {
    std::uint64_t first = 0;
    std::uint32_t count = 0;          // keys, the first included
    std::vector<std::uint8_t> code;  // the count - 1 keys after the first
  };
  std::vector<Segment> m_segments;
  std::size_t m_size = 0;
};

}  // namespace gpucol
