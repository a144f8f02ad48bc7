#include "broadphase/pair_buckets.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

#include "memory/exact_vector.h"
#include "sorting/radix_sort.h"

namespace gpucol {
namespace {

/// The lower slot's bits left in an entry beside the higher slot's `slotBits` (the rest name the bucket):
/// about one bucket per 1,024 slots, at most kMaxBuckets (a small scene in 256 buckets held a segment's
/// bookkeeping per 4 proxies), and at least 8: a thread sorts a bucket in two buffers of 4 bytes
/// per entry, which for a single bucket are 8 bytes for every pair of the scene beside the pieces' 4 (a pile
/// of 1,000 boxes and 4,250 pairs peaked at 165 bytes per proxy).
std::uint32_t shiftFor(std::uint32_t slotBits) {
  constexpr std::uint32_t kMinBucketBits = 3, kMaxBucketBits = 8;
  const std::uint32_t bucketBits =
      std::min({kMaxBucketBits, slotBits, std::max(kMinBucketBits, slotBits > 10 ? slotBits - 10 : 0)});
  return slotBits - bucketBits;
}

/// Sorts e[0, n) of `bits` significant bits with the radix sort of sorting/radix_sort.h, in digits of at most
/// 11 bits, through `s` (a bucket is a few thousand entries; a comparison sort of them all took longer).
void sortEntries(std::uint32_t* e, std::uint32_t* s, std::size_t n, std::uint32_t bits) {
  if (n < 64) {
    std::sort(e, e + n);
    return;
  }
  std::array<std::size_t, 2048> count;
  const std::uint32_t* sorted = radixSort(e, s, n, 0, RadixDigits(bits, 11), count.data());
  if (sorted != e) std::copy(sorted, sorted + n, e);
}

}  // namespace

bool PairBuckets::fits(std::uint32_t slotCount) {
  const std::uint32_t slotBits = slotBitsFor(slotCount);
  return shiftFor(slotBits) + slotBits <= 32;
}

void PairBuckets::reset(std::uint32_t slotCount, std::size_t pieces) {
  release();
  m_slotBits = slotBitsFor(slotCount);
  m_shift = shiftFor(m_slotBits);
  m_buckets = slotCount == 0 ? 1 : std::uint32_t((std::uint64_t(slotCount) - 1) >> m_shift) + 1;
  m_pieces.resize(pieces);
}

void PairBuckets::addToPiece(std::size_t i, const std::vector<std::uint64_t>& keys) {
  if (keys.empty()) return;
  Part& part = m_pieces[i].emplace_back();
  // A counting sort by bucket, into entries allocated at their number.
  part.bucketStart.assign(m_buckets + 1, 0);
  for (std::uint64_t key : keys) ++part.bucketStart[(key >> 32 >> m_shift) + 1];
  for (std::uint32_t b = 0; b < m_buckets; ++b) part.bucketStart[b + 1] += part.bucketStart[b];
  std::vector<std::uint32_t> next(part.bucketStart.begin(), part.bucketStart.end() - 1);
  part.entries.resize(keys.size());
  const std::uint64_t lowMask = (std::uint64_t(1) << m_shift) - 1;
  for (std::uint64_t key : keys) {
    const std::uint64_t a = key >> 32;
    part.entries[next[a >> m_shift]++] = std::uint32_t(((a & lowMask) << m_slotBits) | (key & 0xffffffffu));
  }
}

std::size_t PairBuckets::partKeys() const {
  // A start per bucket is 4 bytes beside the part's 4 per key: at least 16 keys per bucket.
  constexpr std::size_t kMinPartKeys = 512, kKeysPerBucket = 16;
  return std::max(kMinPartKeys, kKeysPerBucket * m_buckets);
}

void PairBuckets::packInto(PackedPairs& out, bool plain) {
  out.clear();
  // A plain list: one array at its size, each bucket sorted into its place.
  std::vector<std::uint64_t> keys;
  std::vector<std::size_t> keysAt;
  if (plain) {
    keysAt.assign(m_buckets + 1, 0);
    forEachPart([&](const Part& part) {
      for (std::uint32_t b = 0; b < m_buckets; ++b)
        keysAt[b + 1] += part.bucketStart[b + 1] - part.bucketStart[b];
    });
    for (std::uint32_t b = 0; b < m_buckets; ++b) keysAt[b + 1] += keysAt[b];
    keys.resize(keysAt[m_buckets]);
  } else {
    out.resetSegments(m_buckets);
  }
  const std::uint32_t entryBits = m_shift + m_slotBits;
  const std::uint64_t slotMask = (std::uint64_t(1) << m_slotBits) - 1;
  tbb::parallel_for(std::uint32_t(0), m_buckets, [&](std::uint32_t bucket) {
    std::size_t n = 0;
    forEachPart([&](const Part& part) { n += part.bucketStart[bucket + 1] - part.bucketStart[bucket]; });
    if (n == 0) return;
    Buffers& buffers = m_buffers.local();
    resizeExact(buffers.entries, n);
    resizeExact(buffers.scratch, n);
    std::uint32_t* e = buffers.entries.data();
    forEachPart([&](const Part& part) {
      const std::uint32_t* from = part.entries.data();
      e = std::copy(from + part.bucketStart[bucket], from + part.bucketStart[bucket + 1], e);
    });
    sortEntries(buffers.entries.data(), buffers.scratch.data(), n, entryBits);
    const std::uint64_t base = std::uint64_t(bucket) << m_shift;
    const std::uint32_t* sorted = buffers.entries.data();
    auto keyAt = [&](std::size_t k) {
      return ((base | (sorted[k] >> m_slotBits)) << 32) | (sorted[k] & slotMask);
    };
    if (plain)
      for (std::size_t k = 0; k < n; ++k) keys[keysAt[bucket] + k] = keyAt(k);
    else
      out.setSegment(bucket, n, keyAt);
  });
  if (plain)
    out.adopt(std::move(keys));
  else
    out.finishSegments();
}

std::size_t PairBuckets::size() const {
  std::size_t n = 0;
  forEachPart([&](const Part& part) { n += part.entries.size(); });
  return n;
}

std::size_t PairBuckets::bytes() const {
  std::size_t bytes = m_pieces.capacity() * sizeof(Piece);
  for (const Piece& piece : m_pieces) bytes += piece.capacity() * sizeof(Part);
  forEachPart(
      [&](const Part& part) { bytes += (part.entries.capacity() + part.bucketStart.capacity()) * 4; });
  for (const Buffers& buffers : m_buffers)
    bytes += (buffers.entries.capacity() + buffers.scratch.capacity()) * 4;
  return bytes;
}

void PairBuckets::release() {
  std::vector<Piece>().swap(m_pieces);
  m_buffers.clear();
}

}  // namespace gpucol
