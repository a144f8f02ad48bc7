#pragma once
// Small host-side helpers shared by the OpenCL stages (broad phase pair finder, mesh pipeline, host sort).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "opencl/host/cl_api.h"

namespace gpucol::opencl {

/// A device buffer that grows on demand (by a quarter more than asked, so steady growth reallocates rarely)
/// and is reused between calls; it shrinks only when released.
struct DeviceArray {
  cl::Buffer buffer;      ///< The buffer (empty until the first ensure).
  std::size_t bytes = 0;  ///< Its size.
  /// The buffer, reallocated when it holds fewer than `wanted` bytes (at least 16: OpenCL refuses empty
  /// ones).
  const cl::Buffer& ensure(const cl::Context& context, std::size_t wanted) {
    wanted = std::max<std::size_t>(wanted, 16);
    if (bytes < wanted) allocate(context, wanted, wanted + wanted / 4);
    return buffer;
  }
  /// As ensure, but the first buffer is exactly `wanted` bytes, for arrays sized by the slot count, which a
  /// steady scene keeps; once such an array has had to grow, it takes the quarter more as well.
  const cl::Buffer& ensureFitted(const cl::Context& context, std::size_t wanted) {
    if (bytes == 0) {
      allocate(context, std::max<std::size_t>(wanted, 16), std::max<std::size_t>(wanted, 16));
      return buffer;
    }
    return ensure(context, wanted);
  }
  /// As ensure, but what the buffer held is kept (copied on the device into the larger one).
  const cl::Buffer& ensureKeeping(const cl::Context& context, cl::CommandQueue& queue, std::size_t wanted) {
    const cl::Buffer old = buffer;
    const std::size_t oldBytes = bytes;
    ensure(context, wanted);
    if (oldBytes > 0 && bytes != oldBytes) queue.enqueueCopyBuffer(old, buffer, 0, 0, oldBytes);
    return buffer;
  }
  /// Drops the buffer (the device frees it once the commands that use it are done); the next ensure
  /// allocates afresh.
  void release() {
    buffer = cl::Buffer();
    bytes = 0;
  }

 private:
  /// A buffer of `size` bytes, or of the device's largest allocation when `size` is above it but `wanted` is
  /// not; past that a length_error that names both sizes (a GPU's limit is a fraction of its memory, and a
  /// driver's own failure would say only CL_INVALID_BUFFER_SIZE).
  void allocate(const cl::Context& context, std::size_t wanted, std::size_t size) {
    const std::size_t limit =
        context.getInfo<CL_CONTEXT_DEVICES>().at(0).getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    if (wanted > limit) {
      throw std::length_error("OpenCL buffer of " + std::to_string(wanted) +
                              " bytes exceeds the device's largest allocation (CL_DEVICE_MAX_MEM_ALLOC_SIZE, " +
                              std::to_string(limit) + " bytes)");
    }
    size = std::min(size, limit);
    buffer = cl::Buffer(context, CL_MEM_READ_WRITE, size);
    bytes = size;
  }
};

/// Bits needed to write every index below `count` (at least 1, so that a mask is never empty).
inline unsigned indexBits(std::uint64_t count) {
  unsigned bits = 1;
  while (bits < 64 && ((count - 1) >> bits) != 0) ++bits;
  return bits;
}

}  // namespace gpucol::opencl
