#include "opencl/host/mesh_host_sort.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "opencl/host/device_array.h"
#include "sorting/radix_sort.h"

namespace gpucol::opencl {

namespace {

/// Widest digit: 8192 counters (32 KiB) per pass, as the CPU path's candidate sort (tree_traversal.cpp). The
/// key's bits are split into the fewest passes of at most this width (RadixDigits). 400 sorts of
/// random keys, medians of two runs: 17,667 keys of 34 bits (an armadillo-99976 pair's) 94.5-95.7 us in three
/// passes of 12 bits against 102.6-103.2 in four of 9 with an 11-bit limit; 35,792 of 38 bits
/// (armadillo-399904) 213.3-213.6 us in three of 13 against 209.7-212.4 in four of 10.
constexpr unsigned kMaxDigitBits = 13;

}  // namespace

void MeshHostSort::sortAndRank(const std::vector<std::uint64_t>& keys, unsigned keyBits,
                               std::vector<std::uint64_t>& sorted, std::vector<std::uint32_t>& rank) {
  const std::size_t n = keys.size();
  if (keyBits > 64) throw std::invalid_argument("MeshHostSort: keys wider than 64 bits");
  if (n > 0xffffffffu) throw std::length_error("MeshHostSort: more than 2^32 keys");
  sorted.resize(n);
  rank.resize(n);
  if (n == 0) return;
  const unsigned indexBits = opencl::indexBits(n);
  if (keyBits + indexBits > 64) {
    // Rare (a batch whose pair and triangle indices fill the key): pairs of key and index, compared.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(n);
    for (std::size_t i = 0; i < n; ++i) pairs[i] = {keys[i], std::uint32_t(i)};
    std::sort(pairs.begin(), pairs.end());
    for (std::size_t p = 0; p < n; ++p) {
      sorted[p] = pairs[p].first;
      rank[pairs[p].second] = std::uint32_t(p);
    }
    return;
  }
  // The index rides in the low bits to carry the rank out. Only the key's digits are sorted: the words start
  // in index order and every pass is stable, so equal keys keep it without passes over the index.
  m_packed.resize(n);
  m_scratch.resize(n);
  for (std::size_t i = 0; i < n; ++i) m_packed[i] = (keys[i] << indexBits) | i;
  const RadixDigits digits(keyBits, kMaxDigitBits);
  m_counts.resize(digits.buckets());
  if (radixSort(m_packed.data(), m_scratch.data(), n, indexBits, digits, m_counts.data()) != m_packed.data())
    std::swap(m_packed, m_scratch);
  const std::uint64_t indexMask = (std::uint64_t(1) << indexBits) - 1;
  for (std::size_t p = 0; p < n; ++p) {
    sorted[p] = m_packed[p] >> indexBits;
    rank[std::size_t(m_packed[p] & indexMask)] = std::uint32_t(p);
  }
}

}  // namespace gpucol::opencl
