#pragma once

namespace gpucol {

/// A hint to bring the line holding `p` into the cache; nothing where the compiler has no such builtin.
/// Used where the traversal and the near phase read tree nodes and vertices in a data-dependent order.
inline void prefetch(const void* p) {
#if defined(__GNUC__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

}  // namespace gpucol
