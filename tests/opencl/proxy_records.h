#pragma once
// Boxes and filters as a caller's records (BoxRecords) for the OpenCL pair finder's tests, as GridBroadphase
// keeps its proxies: records of a layout other than the device's copy (48 bytes, the fields in another
// order), in blocks of 16 laid end to end in one array aligned as a device wants its memory.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol::opencl {

class ProxyRecords {
 public:
  /// Where the finder is told the records lie: end to end (a device sharing the host's memory reads them in
  /// place), or block by block only (the finder copies them).
  enum class Blocks { EndToEnd, Apart };

  explicit ProxyRecords(std::size_t count) : m_count(count) {
    const std::size_t blocks = (count >> kBlockBits) + 1;
    m_records.reset(static_cast<Record*>(
        ::operator new(blocks*(std::size_t(1) << kBlockBits) * sizeof(Record), std::align_val_t(4096))));
    for (std::size_t b = 0; b < blocks; ++b)
      m_blocks.push_back(reinterpret_cast<const unsigned char*>(m_records.get() + (b << kBlockBits)));
  }
  /// Writes slot i's box and filter.
  void set(std::size_t i, const float lo[3], const float hi[3], std::int32_t group, std::int32_t mask) {
    Record& r = m_records.get()[i];
    r = Record{};
    r.tag = 0xdeadbeefu + i;
    for (int a = 0; a < 3; ++a) r.lo[a] = lo[a], r.hi[a] = hi[a];
    r.group = group, r.mask = mask;
  }
  /// The records as the finder's input, with the caller's filter and flags arrays (the same filters).
  ProxyArrays view(Blocks blocks, const std::int32_t* group, const std::int32_t* mask,
                   const std::uint8_t* flags) const {
    ProxyArrays p;
    p.count = std::uint32_t(m_count);
    p.group = group, p.mask = mask, p.flags = flags;
    p.records.blocks = m_blocks.data();
    p.records.blockBits = kBlockBits;
    p.records.stride = sizeof(Record);
    p.records.minOffset = offsetof(Record, lo);
    p.records.maxOffset = offsetof(Record, hi);
    p.records.groupOffset = offsetof(Record, group);
    p.records.maskOffset = offsetof(Record, mask);
    p.records.contiguousBytes =
        blocks == Blocks::EndToEnd ? (m_blocks.size() * sizeof(Record)) << kBlockBits : 0;
    return p;
  }
  /// Bytes of the records.
  std::size_t bytes() const { return (m_blocks.size() * sizeof(Record)) << kBlockBits; }

 private:
  struct Record {
    std::uint64_t tag;
    float lo[3];
    std::int32_t mask;
    float hi[3];
    std::int32_t group;
    std::uint32_t pad[2];
  };
  static_assert(sizeof(Record) == 48, "the test's record layout");
  struct AlignedDelete {
    void operator()(Record* r) const { ::operator delete(r, std::align_val_t(4096)); }
  };
  static constexpr std::uint32_t kBlockBits = 4;
  std::size_t m_count;
  std::unique_ptr<Record, AlignedDelete> m_records;
  std::vector<const unsigned char*> m_blocks;
};

}  // namespace gpucol::opencl
