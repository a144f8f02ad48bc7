#pragma once
// A sorted pair-key list held delta-coded: what the broad phase keeps of the last step for its diff with
// the pair cache and for the pairs stage 11 carries over. Raw, a key takes 8 bytes; a pile holds several per
// proxy, and the step that holds the last list beside this step's went over the memory target (docs/measured-results.md,
// "Broad phase": at most 100 bytes per proxy plus 8 per pair). Coded, a key takes about 2 bytes in a pile and 3-4 in a
// sparse cloud.
//
// Coding: the keys (a << 32 | b) are cut into segments of at most kSegmentKeys, each coded on its own (so
// that segments are coded, decoded and walked in parallel). A segment keeps its first key whole; each
// further key is one LEB128 varint, (b - previous b - 1) << 1 when its a is the previous key's, else
// ((b - a - 1) << 1) | 1 followed by a varint of (a - previous a - 1). All in 32-bit wrap-around arithmetic,
// so any ascending, duplicate-free keys round-trip (pair keys have a < b, which keeps the codes short).
//
// A list of at most 1.5 keys per proxy is kept plain (8 bytes a key, one array cut into segments of
// kSegmentKeys only for the walks; adopt() takes a list over without a copy): the target allows 8 bytes per
// pair, and coding costs time: decoding a sparse scene's keys (mostly a new row each) made its diff several
// times slower, and coding 1M mixed boxes' keys doubled the step's sort and diff (measurement history, "Figures
// moved from code comments"). Above 1.5 keys per proxy, plain lists would take the peak of a step that keeps
// few proxies moving (stage 11) past the target (worthCoding).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace gpucol {

/// Bits needed for slots below `count` (at least 1): the significant bits of either slot of a pair key.
inline std::uint32_t slotBitsFor(std::uint32_t count) {
  std::uint32_t bits = 1;
  while (bits < 32 && (std::uint64_t(1) << bits) < count) ++bits;
  return bits;
}

class PackedPairs {
 public:
  /// Keys per segment (the unit of parallel coding and walking).
  static constexpr std::size_t kSegmentKeys = 4096;

  /// Whether `keys` pair keys of `slots` proxy slots are worth coding: more than 1.5 keys per slot.
  static bool worthCoding(std::size_t keys, std::size_t slots) { return 2 * keys > 3 * slots; }

  /// Keys held.
  std::size_t size() const { return m_size; }
  bool empty() const { return m_size == 0; }
  /// Heap bytes held: the segment table and every segment's code.
  std::size_t bytes() const;
  /// Empties and frees.
  void clear();
  void swap(PackedPairs& other) noexcept;

  /// Replaces the contents with keys[0, n), which must ascend with no repeats, coded or (`plain`) not; each
  /// segment is allocated at its size (counted first), segments coded in parallel.
  void assign(const std::uint64_t* keys, std::size_t n, bool plain = false);
  void assign(const std::vector<std::uint64_t>& keys, bool plain = false) {
    assign(keys.data(), keys.size(), plain);
  }
  /// Replaces the contents with `keys` (ascending, no repeats), kept plain: the vector is taken over.
  void adopt(std::vector<std::uint64_t>&& keys);

  /// Frees the contents and makes `count` empty segments for setSegment.
  void resetSegments(std::size_t count);
  /// Codes segment `i` from the n ascending keys keyAt(0), ..., keyAt(n - 1), all above those of the segments
  /// before it and below those after it, at its size (counted first). Distinct segments may be set in
  /// parallel. A segment left empty is dropped by finishSegments.
  template <typename KeyAt>
  void setSegment(std::size_t i, std::size_t n, KeyAt&& keyAt);
  /// After setSegment: drops the empty segments and counts the keys.
  void finishSegments();

  /// Whether the keys are held plain (then plainKeys() has them all, in order); an empty list is plain.
  bool isPlain() const { return m_segments.empty(); }
  /// The keys of a plain list (isPlain()), size() of them.
  const std::uint64_t* plainKeys() const { return m_plain.data(); }

  std::size_t segments() const {
    return m_plain.empty() ? m_segments.size() : (m_plain.size() + kSegmentKeys - 1) / kSegmentKeys;
  }
  /// First key of segment `i`.
  std::uint64_t segmentFirst(std::size_t i) const {
    return m_plain.empty() ? m_segments[i].first : m_plain[i * kSegmentKeys];
  }

  /// Forward walk over the keys from the start of a segment.
  class Reader {
   public:
    explicit Reader(const PackedPairs& pairs, std::size_t segment = 0);
    bool done() const { return m_done; }
    /// The current key (not done()).
    std::uint64_t key() const { return (std::uint64_t(m_a) << 32) | m_b; }
    void next() {
      if (m_plainAt) {
        if (++m_plainAt == m_plainEnd) {
          m_done = true;
        } else {
          m_a = std::uint32_t(*m_plainAt >> 32), m_b = std::uint32_t(*m_plainAt);
        }
        return;
      }
      if (m_left == 0) {
        ++m_segment;
        enterSegment();
        return;
      }
      --m_left;
      const std::uint8_t c = *m_code;
      if (c < 0x80 && !(c & 1)) {  // the common code: one byte, the same row
        ++m_code;
        m_b += 1 + std::uint32_t(c >> 1);
        return;
      }
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
    const std::uint64_t* m_plainAt = nullptr;  // a plain list: the current key
    const std::uint64_t* m_plainEnd = nullptr;
    bool m_done = false;
  };

  /// Calls f(key) for every key, in order.
  template <typename F>
  void forEach(F&& f) const {
    if (isPlain()) {
      for (std::uint64_t key : m_plain) f(key);
      return;
    }
    for (Reader r(*this); !r.done(); r.next()) f(r.key());
  }
  /// The keys, decoded.
  std::vector<std::uint64_t> toVector() const;

 private:
  static std::size_t varintBytes(std::uint64_t v) {
    std::size_t n = 1;
    while (v >= 0x80) v >>= 7, ++n;
    return n;
  }
  static std::uint8_t* writeVarint(std::uint8_t* out, std::uint64_t v) {
    while (v >= 0x80) *out++ = std::uint8_t(v | 0x80), v >>= 7;
    *out++ = std::uint8_t(v);
    return out;
  }
  /// Calls code(v) for the varints of keys 1..n-1 after key 0 (the coding above).
  template <typename KeyAt, typename Code>
  static void forEachCode(std::size_t n, KeyAt& keyAt, Code&& code) {
    const std::uint64_t k0 = keyAt(0);
    std::uint32_t a = std::uint32_t(k0 >> 32), b = std::uint32_t(k0);
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint64_t k = keyAt(i);
      const std::uint32_t ka = std::uint32_t(k >> 32), kb = std::uint32_t(k);
      if (ka == a) {
        code(std::uint64_t(std::uint32_t(kb - b - 1)) << 1);
      } else {
        code((std::uint64_t(std::uint32_t(kb - ka - 1)) << 1) | 1);
        code(std::uint64_t(std::uint32_t(ka - a - 1)));
      }
      a = ka, b = kb;
    }
  }

  struct Segment {
    std::uint64_t first = 0;
    std::uint32_t count = 0;         // keys, the first included
    std::vector<std::uint8_t> code;  // the count - 1 keys after the first
  };
  std::vector<Segment> m_segments;
  std::vector<std::uint64_t> m_plain;  // the keys of a plain list (then no segments)
  std::size_t m_size = 0;
};

template <typename KeyAt>
void PackedPairs::setSegment(std::size_t i, std::size_t n, KeyAt&& keyAt) {
  Segment& s = m_segments[i];
  std::vector<std::uint8_t>().swap(s.code);
  s.count = 0;
  if (n == 0) return;
  if (n > 0xffffffffu) throw std::length_error("gpucol::PackedPairs: more than 2^32 - 1 keys in one segment");
  s.first = keyAt(0);
  s.count = std::uint32_t(n);
  std::size_t size = 0;
  forEachCode(n, keyAt, [&](std::uint64_t v) { size += varintBytes(v); });
  s.code.resize(size);  // exactly: a vector sized from empty allocates what it is asked for
  std::uint8_t* out = s.code.data();
  forEachCode(n, keyAt, [&](std::uint64_t v) { out = writeVarint(out, v); });
}

/// Stage 11's result (grid_pair_finder.h): the keys of `last` that `carried(key)` accepts (pairs of two
/// resting proxies), merged with `found` (ascending, none of them among those) into `pairs`. The carried keys
/// go straight into `pairs`, sized exactly, and `found` is merged in from the back: no second list.
template <typename Carried>
void mergeCarriedPairs(const PackedPairs& last, Carried&& carried, const std::vector<std::uint64_t>& found,
                       std::vector<std::uint64_t>& pairs) {
  std::size_t kept = 0;
  last.forEach([&](std::uint64_t key) { kept += carried(key); });
  pairs.clear();
  pairs.reserve(kept + found.size());
  last.forEach([&](std::uint64_t key) {
    if (carried(key)) pairs.push_back(key);
  });
  std::size_t fromCarried = kept, fromFound = found.size();
  pairs.resize(kept + fromFound);
  for (std::size_t to = pairs.size(); fromFound > 0;) {
    if (fromCarried > 0 && pairs[fromCarried - 1] > found[fromFound - 1])
      pairs[--to] = pairs[--fromCarried];
    else
      pairs[--to] = found[--fromFound];
  }
}

}  // namespace gpucol
