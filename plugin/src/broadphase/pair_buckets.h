#pragma once
// The slab search's pairs on their way into a PackedPairs without a full list of 8-byte keys: each slab's
// unsorted list is split, each time it holds partKeys() keys and when the slab is done, into buckets by the
// lower slot's high bits, each key kept as a 32-bit entry (the rest of the lower slot and the higher slot);
// then each bucket is gathered from every slab, sorted and coded as one segment. A step held the pairs
// gathered (8 B each) beside the per-slab lists or the sort's second buffer (8 B more) and the last step's
// list; now it holds 4 B per pair in the buckets and the coded lists (docs/measured-results.md, "Broad
// phase": at most 100 bytes per proxy plus 8 per pair).
#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "broadphase/packed_pairs.h"

namespace gpucol {

class PairBuckets {
 public:
  /// Buckets at most (the lower slot's top 8 bits).
  static constexpr std::uint32_t kMaxBuckets = 256;

  /// Whether the keys of slots below `slotCount` fit 32-bit entries (up to 2^20 slots).
  static bool fits(std::uint32_t slotCount);
  /// Empties the buckets and makes room for `pieces` lists of keys of slots below `slotCount` (fits()).
  void reset(std::uint32_t slotCount, std::size_t pieces);
  /// Splits `keys` (pair keys, any order, none added before) into the buckets as a part of piece `i`; a piece
  /// may be added to several times, distinct pieces in parallel. `keys` is not changed.
  void addToPiece(std::size_t i, const std::vector<std::uint64_t>& keys);
  /// Keys a part should hold at least, so that its bookkeeping (a start per bucket) stays small beside it:
  /// a producer may hand its keys over whenever it has this many, instead of growing its list.
  std::size_t partKeys() const;
  /// Sorts each bucket and codes it (or, `plain`, copies it) into `out` as one segment (in parallel over
  /// buckets); the pieces stay until release(), so that bytes() then is the high-water mark of the whole.
  void packInto(PackedPairs& out, bool plain = false);
  /// Keys held.
  std::size_t size() const;
  /// Heap bytes held: the pieces and the threads' bucket buffers.
  std::size_t bytes() const;
  /// Frees everything.
  void release();

 private:
  /// Keys handed over at once by addToPiece.
  struct Part {
    std::vector<std::uint32_t> entries;      // by bucket: (lower slot's low bits << slotBits) | higher slot
    std::vector<std::uint32_t> bucketStart;  // first entry of each bucket (+ the end)
  };
  /// A piece's parts in the order added.
  using Piece = std::vector<Part>;

  /// f(part) for every part of every piece.
  template <typename F>
  void forEachPart(F&& f) const {
    for (const Piece& piece : m_pieces)
      for (const Part& part : piece) f(part);
  }
  /// One thread's buffers for the bucket it sorts.
  struct Buffers {
    std::vector<std::uint32_t> entries, scratch;
  };

  std::uint32_t m_slotBits = 1;  // bits of the higher slot in an entry
  std::uint32_t m_shift = 0;     // the lower slot's bits in an entry: its bucket is lower slot >> m_shift
  std::uint32_t m_buckets = 1;
  std::vector<Piece> m_pieces;
  tbb::enumerable_thread_specific<Buffers> m_buffers;
};

}  // namespace gpucol
