#pragma once
// Growing a scratch vector to an exact capacity without ever holding its old and new arrays at once. Each
// thread of a search holds its scratch at the largest size it needed until the search ends, and the step's
// reported peak (GridBroadphaseStats::peakBytes) counts capacities: resize alone could double a capacity, and
// freeing the old array in the same expression as the new allocation keeps it alive until the expression
// ends (tests/memory caught 10-42 KB above the reported peak from that).
#include <cstddef>
#include <vector>

namespace gpucol {

/// Makes room for n elements in v, with a capacity of exactly n when it must grow; the old array is freed
/// before the new one is allocated.
template <typename T, typename Allocator>
inline void reserveExact(std::vector<T, Allocator>& v, std::size_t n) {
  if (n > v.capacity()) {
    std::vector<T, Allocator>().swap(v);  // its own statement: the emptied temporary frees the array here
    v.reserve(n);
  }
}

/// reserveExact, then n elements.
template <typename T, typename Allocator>
inline void resizeExact(std::vector<T, Allocator>& v, std::size_t n) {
  reserveExact(v, n);
  v.resize(n);
}

}  // namespace gpucol
