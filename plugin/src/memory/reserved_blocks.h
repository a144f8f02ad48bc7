#pragma once
// Storage for blocks of equal size that never move once handed out, laid end to end in one range of
// address space reserved up front, so that together they form one array whose start never changes. The
// broad phase keeps Bullet's proxies in such blocks: Bullet holds their addresses, and an OpenCL device that
// shares the host's memory reads every proxy's box in place through one buffer over the blocks.
//
// The range is only reserved (no access, no memory, not counted against the system's commit limit); each
// block's pages are committed when it is added. Where the system refuses the reservation (an address-space
// limit) or the range is full, blocks come from the heap one by one: nothing is lost, but the blocks are no
// longer one array (contiguousBytes() then says how far they are).
#include <algorithm>
#include <cstddef>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace gpucol {

class ReservedBlocks {
 public:
  /// Blocks of `blockBytes` bytes (a multiple of 64), address space reserved for `maxBlocks` of them.
  ReservedBlocks(std::size_t blockBytes, std::size_t maxBlocks) : m_blockBytes(blockBytes) {
#if defined(__linux__)
    m_page = std::size_t(sysconf(_SC_PAGESIZE));
    if (maxBlocks > 0 && blockBytes <= ~std::size_t(0) / maxBlocks - m_page) {
      const std::size_t bytes = roundToPage(blockBytes * maxBlocks);
      void* range = mmap(nullptr, bytes, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
      if (range != MAP_FAILED) {
        m_range = static_cast<unsigned char*>(range);
        m_rangeBytes = bytes;
      }
    }
#else
    (void)maxBlocks;
#endif
  }
  ~ReservedBlocks() {
    for (std::size_t i = m_inRange; i < m_blocks.size(); ++i)
      ::operator delete(m_blocks[i], std::align_val_t(64));
#if defined(__linux__)
    if (m_range != nullptr) munmap(m_range, m_rangeBytes);
#endif
  }
  ReservedBlocks(const ReservedBlocks&) = delete;
  ReservedBlocks& operator=(const ReservedBlocks&) = delete;

  /// A new block of uninitialised memory, aligned to 64 bytes; throws std::bad_alloc when no memory is left.
  void* add() {
    // The table grows before a block is committed, so that a failure here loses nothing; by half again, not
    // by one (a reserve of size() + 1 reallocated it on every block).
    if (m_blocks.size() == m_blocks.capacity())
      m_blocks.reserve(std::max<std::size_t>(8, m_blocks.size() * 3 / 2));
#if defined(__linux__)
    if (m_range != nullptr && m_inRange == m_blocks.size() &&
        (m_inRange + 1) * m_blockBytes <= m_rangeBytes) {
      const std::size_t end = roundToPage((m_inRange + 1) * m_blockBytes);
      if (end > m_committed) {
        if (mprotect(m_range + m_committed, end - m_committed, PROT_READ | PROT_WRITE) != 0)
          throw std::bad_alloc();  // the commit limit
        m_committed = end;
      }
      m_blocks.push_back(m_range + m_inRange * m_blockBytes);
      ++m_inRange;
      return m_blocks.back();
    }
#endif
    m_blocks.push_back(static_cast<unsigned char*>(::operator new(m_blockBytes, std::align_val_t(64))));
    return m_blocks.back();
  }

  /// Blocks added so far.
  std::size_t size() const { return m_blocks.size(); }
  /// Block i (below size()).
  void* block(std::size_t i) const { return m_blocks[i]; }
  /// Every block's start, in order (valid until the next add()).
  const unsigned char* const* table() const { return m_blocks.data(); }
  /// The start of block 0 (nullptr before the first).
  const void* base() const { return m_blocks.empty() ? nullptr : m_blocks[0]; }
  /// Bytes from base() that are blocks laid end to end: block i starts at base() + i * blockBytes for every
  /// i below contiguousBytes() / blockBytes.
  std::size_t contiguousBytes() const {
    return (m_inRange > 0 ? m_inRange : std::min<std::size_t>(m_blocks.size(), 1)) * m_blockBytes;
  }
  /// Bytes per block.
  std::size_t blockBytes() const { return m_blockBytes; }
  /// Bytes of the table of blocks (the blocks themselves are size() * blockBytes()).
  std::size_t tableBytes() const { return m_blocks.capacity() * sizeof(void*); }

 private:
  std::size_t roundToPage(std::size_t bytes) const { return (bytes + m_page - 1) / m_page * m_page; }

  std::size_t m_blockBytes;
  std::size_t m_page = 4096;
  unsigned char* m_range = nullptr;  // the reserved range, or nullptr where the system refused it
  std::size_t m_rangeBytes = 0;
  std::size_t m_committed = 0;  // bytes of the range made accessible
  std::size_t m_inRange = 0;    // the first blocks, which lie in the range
  std::vector<unsigned char*> m_blocks;
};

}  // namespace gpucol
