#pragma once
// The one radix sort of the CPU code: the broad phase's pair keys (grid_pair_finder.cpp) and bucket entries
// (pair_buckets.cpp), the middle phase's candidates (tree_traversal.cpp) and the OpenCL mesh pipeline's host
// sort of candidate keys (opencl/host/mesh_host_sort.cpp). Integer keys sort in a few linear passes where a
// comparison sort takes n log n steps, and the passes are stable, so the result is the same whatever the
// threads do.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <utility>

namespace gpucol {

/// How a key's bits split into the passes of a radix sort: the fewest digits of at most `maxDigitBits`, all
/// of one width, as narrow as that count of passes allows (a narrower digit clears and scans fewer counters).
struct RadixDigits {
  /// Digits for keys of `keyBits` significant bits.
  RadixDigits(unsigned keyBits, unsigned maxDigitBits)
      : passes((keyBits + maxDigitBits - 1) / maxDigitBits),
        bits(passes == 0 ? 0 : (keyBits + passes - 1) / passes) {}
  unsigned passes;  ///< Passes over the keys (0 for keys without significant bits).
  unsigned bits;    ///< Bits per digit.
  /// Counters per pass and chunk.
  std::size_t buckets() const { return std::size_t(1) << bits; }
};

/// Sorts keys[0, n) ascending by their bits lowBit .. lowBit + digits' bits (the bits below lowBit ride
/// along; keys equal in the sorted bits keep their input order): an LSD radix sort, each pass a count of
/// the digits, their offsets, and a scatter between `keys` and `scratch` (n entries). Returns the buffer that
/// holds the result, `keys` or `scratch`. `counts` holds chunks * digits.buckets() entries. With chunks > 1
/// each pass counts and scatters in that many fixed chunks in parallel (oneTBB), every chunk to offsets of
/// its own, so the order is the serial one. A pass whose digit is the same in every key is skipped: it
/// would leave the order as it is.
template <class Key, class Count>
Key* radixSort(Key* keys, Key* scratch, std::size_t n, unsigned lowBit, RadixDigits digits, Count* counts,
               std::size_t chunks = 1) {
  if (n == 0) return keys;
  const std::size_t buckets = digits.buckets();
  const Key mask = Key(buckets - 1);
  chunks = std::max<std::size_t>(1, std::min(chunks, n));
  const std::size_t chunkSize = (n + chunks - 1) / chunks;
  auto forChunks = [&](auto&& f) {
    if (chunks == 1) {
      f(std::size_t(0), std::size_t(0), n);
      return;
    }
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      f(c, std::min(n, c * chunkSize), std::min(n, (c + 1) * chunkSize));
    });
  };
  Key* from = keys;
  Key* to = scratch;
  for (unsigned p = 0; p < digits.passes; ++p) {
    const unsigned shift = lowBit + p * digits.bits;
    forChunks([&](std::size_t c, std::size_t begin, std::size_t end) {
      Count* count = counts + c * buckets;
      std::fill(count, count + buckets, Count(0));
      for (std::size_t i = begin; i < end; ++i) ++count[(from[i] >> shift) & mask];
    });
    const std::size_t first = std::size_t((from[0] >> shift) & mask);
    std::size_t withFirst = 0;
    for (std::size_t c = 0; c < chunks; ++c) withFirst += std::size_t(counts[c * buckets + first]);
    if (withFirst == n) continue;
    Count sum = 0;  // digit-major, chunk-minor: the chunks of one digit follow each other in order
    for (std::size_t d = 0; d < buckets; ++d)
      for (std::size_t c = 0; c < chunks; ++c) sum += std::exchange(counts[c * buckets + d], sum);
    forChunks([&](std::size_t c, std::size_t begin, std::size_t end) {
      Count* next = counts + c * buckets;
      for (std::size_t i = begin; i < end; ++i) to[next[(from[i] >> shift) & mask]++] = from[i];
    });
    std::swap(from, to);
  }
  return from;
}

}  // namespace gpucol
