#pragma once
// The memory tests' view of the heap: this executable replaces the global operator new and delete
// (counting_heap.cpp) with ones that count the bytes live and their high-water mark, so the broad phase's
// own memory figures can be checked against what was really allocated through operator new.
#include <cstddef>

namespace gpucol::test {

/// Bytes allocated through operator new and not yet freed.
std::size_t heapLive();
/// The most bytes live since the last resetHeapMark().
std::size_t heapMark();
/// Starts the high-water mark again at what is live now.
void resetHeapMark();

/// What a piece of work allocated: the change in live bytes, and the high-water mark above the start.
struct HeapOfStep {
  std::ptrdiff_t kept = 0;
  std::ptrdiff_t mark = 0;
};

/// Runs `work` and says what it allocated.
template <typename Work>
HeapOfStep measureHeap(Work&& work) {
  const std::size_t before = heapLive();
  resetHeapMark();
  work();
  return {std::ptrdiff_t(heapLive()) - std::ptrdiff_t(before), std::ptrdiff_t(heapMark() - before)};
}

}  // namespace gpucol::test
