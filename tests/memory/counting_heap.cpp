// The counting operator new and delete of counting_heap.h.
#include "counting_heap.h"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

std::atomic<std::size_t> g_live{0};
std::atomic<std::size_t> g_mark{0};

/// Each block carries its size in a header of kHeader bytes (a multiple of every fundamental alignment).
constexpr std::size_t kHeader = alignof(std::max_align_t);

void* countedAlloc(std::size_t bytes, std::size_t align) {
  const std::size_t header = std::max(kHeader, align);
  void* base = align > kHeader ? std::aligned_alloc(align, (header + bytes + align - 1) / align * align)
                               : std::malloc(header + bytes);
  if (!base) return nullptr;
  unsigned char* user = static_cast<unsigned char*>(base) + header;
  reinterpret_cast<std::size_t*>(user)[-1] = bytes;
  reinterpret_cast<std::size_t*>(user)[-2] = header;
  const std::size_t live = g_live.fetch_add(bytes) + bytes;
  std::size_t mark = g_mark.load();
  while (live > mark && !g_mark.compare_exchange_weak(mark, live)) {
  }
  return user;
}

void countedFree(void* p) noexcept {
  if (!p) return;
  unsigned char* user = static_cast<unsigned char*>(p);
  g_live.fetch_sub(reinterpret_cast<std::size_t*>(user)[-1]);
  std::free(user - reinterpret_cast<std::size_t*>(user)[-2]);
}

void* countedNew(std::size_t bytes, std::size_t align) {
  void* p = countedAlloc(bytes, align);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace

void* operator new(std::size_t n) {
  return countedNew(n, kHeader);
}
void* operator new[](std::size_t n) {
  return countedNew(n, kHeader);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return countedAlloc(n, kHeader);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return countedAlloc(n, kHeader);
}
void* operator new(std::size_t n, std::align_val_t a) {
  return countedNew(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return countedNew(n, std::size_t(a));
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return countedAlloc(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return countedAlloc(n, std::size_t(a));
}
void operator delete(void* p) noexcept {
  countedFree(p);
}
void operator delete[](void* p) noexcept {
  countedFree(p);
}
void operator delete(void* p, std::size_t) noexcept {
  countedFree(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  countedFree(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  countedFree(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  countedFree(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  countedFree(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  countedFree(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  countedFree(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  countedFree(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  countedFree(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  countedFree(p);
}

namespace gpucol::test {

std::size_t heapLive() {
  return g_live.load();
}

std::size_t heapMark() {
  return g_mark.load();
}

void resetHeapMark() {
  g_mark.store(g_live.load());
}

}  // namespace gpucol::test
