#pragma once
// How many OpenCL contexts this process has created, readable without the OpenCL module: header-only, so the
// plugin reports it (gpucol::openClStarted) whether or not it was built with OpenCL. DESIGN.md's lazy start is
// shown by this staying 0 in a program whose batches never want OpenCL.
#include <atomic>
#include <cstdint>

namespace gpucol::opencl {

/// Count of OpenCL contexts created so far (OpenClContext's constructor adds one when setup succeeds).
inline std::atomic<std::uint32_t>& openClContextsCreated() {
  static std::atomic<std::uint32_t> count{0};
  return count;
}

}  // namespace gpucol::opencl
