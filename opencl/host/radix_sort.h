#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "opencl/host/opencl_context.h"
#include "opencl/host/scan.h"

namespace gpucol::opencl {

/// Stable radix sort of (uint64 key, uint32 value) pairs, or of keys alone, on an OpenCL device, 4 bits per
/// pass, digit offsets from OpenClScan. On a CPU device each work-item counts and scatters one chunk in order;
/// in a GPU's shape (OpenClContext::gpuShaped) each work-group sorts a tile in local memory and writes it
/// coalesced. Keeps its
/// scratch buffers between calls (grown, shrunk only by releaseScratch); one object per thread.
class OpenClRadixSort {
 public:
  /// Builds (or takes from the cache) the sort program of `context`.
  explicit OpenClRadixSort(OpenClContext& context);

  /// Sorts keys[0..n) (cl_ulong) ascending, carrying values[0..n) (cl_uint) along; equal keys keep their
  /// order. Only the low `keyBits` bits of the keys are looked at (1..64): the caller passes the width it
  /// knows its keys fit in, and passes are ceil(keyBits / 4). Results are left in `keys` and `values`.
  void sort(const cl::Buffer& keys, const cl::Buffer& values, std::size_t n, unsigned keyBits = 64);

  /// As sort, for keys without values: no value arrays are made (8 bytes of scratch per key, not 12).
  void sortKeys(const cl::Buffer& keys, std::size_t n, unsigned keyBits = 64);

  /// Convenience for tests: sorts host vectors through the device.
  void sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned keyBits = 64);
  /// Convenience for tests: sorts a host vector of keys through the device (sortKeys).
  void sortKeys(std::vector<std::uint64_t>& keys, unsigned keyBits = 64);

  /// Device bytes of the scratch buffers it keeps: the second key and value arrays (8 and 4 bytes per
  /// element of the longest sort so far that needed them), the digit counts, and its scan's.
  std::size_t bytes() const;

  /// Drops the second key and value arrays and the digit counts (the next sort allocates them again).
  void releaseScratch();

 private:
  OpenClContext& m_context;
  OpenClScan m_scan;
  cl::Kernel m_count;
  cl::Kernel m_scatter;
  cl::Kernel m_tileCount;
  cl::Kernel m_tileScatter;
  bool m_tiles = false;            // the GPU's shape: tiles of m_tileSize elements
  std::size_t m_tileSize = 0;  void sortPasses(const cl::Buffer& keys, const cl::Buffer* values, std::size_t n, unsigned keyBits);
  std::size_t m_groupSize = 0;     // work-group size of both kernels (asked of the device)
  std::size_t m_targetChunks = 0;  // chunks (work-items) per pass to aim for
  cl::Buffer m_counts;
  std::size_t m_countsCapacity = 0;
  cl::Buffer m_keysTemp;
  std::size_t m_keysCapacity = 0;
  cl::Buffer m_valuesTemp;
  std::size_t m_valuesCapacity = 0;
};

}  // namespace gpucol::opencl
