#include "opencl/host/mesh_host_sort.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <utility>

#include "opencl/host/device_array.h"

namespace gpucol::opencl {

namespace {

/// Digit width: 2048 counters (16 KiB) stay in L1, and one armadillo-399904 pair's 38-bit keys with a 16-bit
/// index take five passes.
constexpr unsigned kDigitBits = 11;
constexpr std::size_t kBuckets = std::size_t(1) << kDigitBits;

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
  // The index in the low bits makes every word unique and the order stable, and carries the rank out.
  m_packed.resize(n);
  m_scratch.resize(n);
  for (std::size_t i = 0; i < n; ++i) m_packed[i] = (keys[i] << indexBits) | i;
  const unsigned totalBits = keyBits + indexBits;
  std::array<std::uint32_t, kBuckets> count;
  for (unsigned shift = 0; shift < totalBits; shift += kDigitBits) {
    count.fill(0);
    for (std::uint64_t w : m_packed) ++count[(w >> shift) & (kBuckets - 1)];
    // A digit shared by every word (the pair bits of a one-pair batch, the high bits of small meshes) leaves
    // the order as it is: the pass is skipped.
    if (count[(m_packed[0] >> shift) & (kBuckets - 1)] == n) continue;
    std::uint32_t offset = 0;
    for (std::uint32_t& c : count) {
      const std::uint32_t here = c;
      c = offset;
      offset += here;
    }
    for (std::uint64_t w : m_packed) m_scratch[count[(w >> shift) & (kBuckets - 1)]++] = w;
    std::swap(m_packed, m_scratch);
  }
  const std::uint64_t indexMask = (std::uint64_t(1) << indexBits) - 1;
  for (std::size_t p = 0; p < n; ++p) {
    sorted[p] = m_packed[p] >> indexBits;
    rank[std::size_t(m_packed[p] & indexMask)] = std::uint32_t(p);
  }
}

}  // namespace gpucol::opencl
