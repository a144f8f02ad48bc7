#pragma once
// Allocator of large arrays that are written once after allocation and then read at random or released soon:
//  - the broad phase's per-step scratch arrays, released at the end of every search so that only what the
//    next search reuses is held between steps (GridBroadphaseStats::memoryBytes);
//  - a mesh's tree nodes and triangle soup (40 MB for armadillo-399904), which the mesh pair query walks in
//    an order that jumps across the whole array.
// Two things make such arrays slow with the ordinary heap, and this allocator removes both:
//  - std::vector::resize value-initialises (zeroes) new elements that are overwritten anyway: construct()
//    without arguments default-initialises instead (nothing for the plain types used here);
//  - the kernel backs memory with 4 KiB pages, so a fresh array faults page by page and random reads of a
//    large one miss the TLB: large arrays are mapped on 2 MiB boundaries with madvise(MADV_HUGEPAGE), so
//    where transparent huge pages are available (Linux, "madvise" or "always") they get 2 MiB pages. Heap
//    memory would not do: glibc serves large blocks from memory freed earlier (a mesh loader's buffers),
//    already backed by small pages.
// Small arrays come from the ordinary heap.
#include <cstddef>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace gpucol {

/// Arrays of at least this many bytes are mapped directly (huge pages where the system gives them).
constexpr std::size_t kLargeArrayMapFrom = std::size_t(4) << 20;

/// std::allocator with default-initialising construct() and huge-page mappings for large arrays.
template <typename T>
struct LargeArrayAllocator {
  using value_type = T;
  LargeArrayAllocator() = default;
  template <typename U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes >= kLargeArrayMapFrom) {
      constexpr std::size_t kHuge = std::size_t(2) << 20;
      // Over-map by one huge page and trim both ends so the array starts on a 2 MiB boundary.
      const std::size_t mapped = (bytes + kHuge - 1) / kHuge * kHuge + kHuge;
      void* raw = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (raw == MAP_FAILED) throw std::bad_alloc();
      const std::size_t start = reinterpret_cast<std::size_t>(raw);
      const std::size_t aligned = (start + kHuge - 1) / kHuge * kHuge;
      const std::size_t end = aligned + (bytes + kHuge - 1) / kHuge * kHuge;
      if (aligned > start) munmap(raw, aligned - start);
      if (start + mapped > end) munmap(reinterpret_cast<void*>(end), start + mapped - end);
      madvise(reinterpret_cast<void*>(aligned), end - aligned, MADV_HUGEPAGE);  // a hint: failure is fine
      return reinterpret_cast<T*>(aligned);
    }
#endif
    return std::allocator<T>().allocate(n);
  }

  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes >= kLargeArrayMapFrom) {
      constexpr std::size_t kHuge = std::size_t(2) << 20;
      munmap(p, (bytes + kHuge - 1) / kHuge * kHuge);
      return;
    }
#endif
    std::allocator<T>().deallocate(p, n);
  }

  /// Default-initialises (resize() leaves plain values unwritten); other constructions as usual.
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }

  template <typename U>
  bool operator==(const LargeArrayAllocator<U>&) const noexcept {
    return true;
  }
  template <typename U>
  bool operator!=(const LargeArrayAllocator<U>&) const noexcept {
    return false;
  }
};

/// A vector whose large storage is mapped on huge pages and whose resize() does not zero.
template <typename T>
using LargeArrayVector = std::vector<T, LargeArrayAllocator<T>>;

}  // namespace gpucol
