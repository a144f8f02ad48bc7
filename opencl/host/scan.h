#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "opencl/host/opencl_context.h"

namespace gpucol::opencl {

/// Exclusive prefix sum of uint32 values of any length on an OpenCL device (thesis §5.4.2, Alg. 5.4),
/// multi-pass: blocks of 2L values per work-group (Blelloch) on GPUs, or one serial chunk per work-item on
/// CPU devices, then the block or chunk totals scanned recursively. Reused by
/// the broad phase (per-cell pair counts, radix sort digit offsets) and the mesh pipeline. Keeps its
/// scratch buffers between calls (grown, never shrunk); one object per thread.
class OpenClScan {
 public:
  /// How blocks are scanned: Auto picks Blelloch on a GPU and Chunked on other devices.
  enum class Method { Auto, Blelloch, Chunked };

  /// Builds (or takes from the cache) the scan program of `context`.
  explicit OpenClScan(OpenClContext& context, Method method = Method::Auto);

  /// Replaces data[0..n) by its exclusive prefix sum, in place, and returns the total. Throws
  /// std::overflow_error when the total exceeds 2^32 - 1 (the values are then unspecified), OpenClError
  /// when a call fails. Enqueued on the context's queue; returns when the total is known.
  std::uint32_t exclusiveScan(const cl::Buffer& data, std::size_t n);

  /// As exclusiveScan, but only enqueued: no wait, no total, no overflow check. For values whose sum the
  /// caller knows to fit in 32 bits (a radix sort's digit counts of at most 2^32 - 1 elements), so that a
  /// discrete GPU's queue runs on without a round trip to the host.
  void exclusiveScanQueued(const cl::Buffer& data, std::size_t n);

  /// Convenience for tests and small inputs: scans a host vector through the device.
  std::uint32_t exclusiveScan(std::vector<std::uint32_t>& values);

  /// Device bytes of the scratch buffers it keeps (the block totals of every level, the overflow flag).
  std::size_t bytes() const;

 private:
  // One level of the scan and the levels above it; the top level's total is read (a wait) when readTotal.
  std::uint32_t scanLevel(const cl::Buffer& data, std::size_t n, std::size_t level, bool readTotal);
  std::uint32_t scanLevelChunked(const cl::Buffer& data, std::size_t n, std::size_t level, bool readTotal);
  const cl::Buffer& levelBuffer(std::size_t level, std::size_t count);

  OpenClContext& m_context;
  cl::Kernel m_scanBlocks;
  cl::Kernel m_addOffsets;
  cl::Kernel m_chunkTotals;
  cl::Kernel m_scanChunks;
  bool m_chunked = false;
  std::size_t m_chunkGroupSize = 0;
  std::size_t m_targetChunks = 0;  // work-items per chunked pass to aim for
  std::size_t m_blockItems = 0;    // L: items per work-group of scan_blocks
  std::size_t m_addGroupSize = 0;
  cl::Buffer m_overflow;
  std::vector<cl::Buffer> m_levelSums;  // block totals of each recursion level
  std::vector<std::size_t> m_levelCapacity;
};

}  // namespace gpucol::opencl
