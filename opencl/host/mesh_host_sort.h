// The host's half of the OpenCL mesh pipeline's deterministic order: candidate keys read back in the
// traversal's order are put in key order, and each one's place in that order is kept for the near
// phase's hits.
#pragma once

#include <cstdint>
#include <vector>

namespace gpucol::opencl {

/// Sorts candidate keys on the host and ranks them, reusing its buffers between batches.
class MeshHostSort {
 public:
  /// Writes `keys` ascending to `sorted` and, for every i, `rank[i]` = the place of keys[i] in `sorted`
  /// (equal keys keep their input order). Every key must be below 2^keyBits (keyBits <= 64). The radix sort
  /// of sorting/radix_sort.h on the key's digits of key and index packed in one 64-bit word when they fit
  /// (keyBits + index bits <= 64); otherwise a comparison sort of (key, index).
  void sortAndRank(const std::vector<std::uint64_t>& keys, unsigned keyBits,
                   std::vector<std::uint64_t>& sorted, std::vector<std::uint32_t>& rank);

 private:
  std::vector<std::uint64_t> m_packed, m_scratch;
  std::vector<std::uint32_t> m_counts;
};

}  // namespace gpucol::opencl
