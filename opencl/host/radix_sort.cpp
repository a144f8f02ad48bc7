#include "opencl/host/radix_sort.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "gpucol_kernels/kernels.h"

namespace gpucol::opencl {

namespace {
constexpr unsigned kRadixBits = 4;  // at most log2(RADIX) of radix_sort.cl
constexpr unsigned kRadix = 1u << kRadixBits;
constexpr std::size_t kMinChunk = 16;
constexpr std::size_t kMaxTile = 256;
}  // namespace

OpenClRadixSort::OpenClRadixSort(OpenClContext& context) : m_context(context), m_scan(context) {
  translateClErrors("setting up the OpenCL radix sort", [&] {
    cl::Program program = m_context.program("radix_sort", kernels::radix_sort);
    m_count = cl::Kernel(program, "radix_count");
    m_scatter = cl::Kernel(program, "radix_scatter");
    m_tileCount = cl::Kernel(program, "radix_tile_count");
    m_tileScatter = cl::Kernel(program, "radix_tile_scatter");
    m_tiles = m_context.gpuShaped();
    // A tile is one work-group, kMaxTile elements at most (TILE_MAX of radix_sort.cl).
    m_tileSize = std::min({kMaxTile, m_context.workGroupSize(m_tileCount), m_context.workGroupSize(m_tileScatter)});
    m_tiles = m_tiles && m_tileSize >= kRadix;  // the tile kernels need RADIX work-items per group
    m_groupSize = std::min(m_context.workGroupSize(m_count), m_context.workGroupSize(m_scatter));
    // Enough chunks to fill the device a few times over; more would only lengthen the counts to scan.
    const std::size_t units = m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
    m_targetChunks = std::max<std::size_t>(1, units * m_groupSize);
  });
}

void OpenClRadixSort::sort(const cl::Buffer& keys, const cl::Buffer& values, std::size_t n,
                           unsigned keyBits) {
  sortPasses(keys, &values, n, keyBits);
}

void OpenClRadixSort::sortKeys(const cl::Buffer& keys, std::size_t n, unsigned keyBits) {
  sortPasses(keys, nullptr, n, keyBits);
}

void OpenClRadixSort::sortPasses(const cl::Buffer& keys, const cl::Buffer* values, std::size_t n,
                                 unsigned keyBits) {
  if (keyBits == 0 || keyBits > 64) {
    throw std::invalid_argument("OpenClRadixSort: keyBits must be in 1..64, got " + std::to_string(keyBits));
  }
  if (n > 0xffffffffu) {
    throw std::length_error("OpenClRadixSort: " + std::to_string(n) +
                            " elements exceed the uint32 index range");
  }
  if (n <= 1) {
    return;
  }
  translateClErrors("OpenCL radix sort", [&] {
    cl::CommandQueue& queue = m_context.queue();
    // Short chunks keep many items busy; kMinChunk bounds the counts array at 16 / kMinChunk per element.
    // Tiles: one chunk per work-group of m_tileSize elements, one element per work-item.
    const std::size_t chunkLength =
        m_tiles ? m_tileSize : std::max(kMinChunk, (n + m_targetChunks - 1) / m_targetChunks);
    const std::size_t chunks = (n + chunkLength - 1) / chunkLength;
    const std::size_t global = m_tiles ? chunks * m_tileSize : (chunks + m_groupSize - 1) / m_groupSize * m_groupSize;
    const std::size_t local = m_tiles ? m_tileSize : m_groupSize;
    if (m_countsCapacity < chunks * kRadix) {
      m_counts = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, chunks * kRadix * sizeof(cl_uint));
      m_countsCapacity = chunks * kRadix;
    }
    if (m_keysCapacity < n) {
      m_keysTemp = cl::Buffer();  // freed before its successor is made
      m_keysTemp = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_ulong));
      m_keysCapacity = n;
    }
    if (values != nullptr && m_valuesCapacity < n) {
      m_valuesTemp = cl::Buffer();
      m_valuesTemp = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_uint));
      m_valuesCapacity = n;
    }
    cl::Buffer keysFrom = keys;
    cl::Buffer valuesFrom = values != nullptr ? *values : cl::Buffer();
    cl::Buffer keysTo = m_keysTemp;
    cl::Buffer valuesTo = values != nullptr ? m_valuesTemp : cl::Buffer();
    unsigned passes = 0;
    for (unsigned shift = 0; shift < keyBits; shift += kRadixBits, ++passes) {
      // The last pass may look at fewer than 4 bits: bits past keyBits are never looked at.
      const unsigned bits = std::min(kRadixBits, keyBits - shift);
      const cl_uint digitMask = (1u << bits) - 1u;
      const std::size_t digits = std::size_t(digitMask) + 1;
      if (m_tiles) {
        setKernelArgs(m_tileCount, 0, keysFrom, static_cast<cl_uint>(n), static_cast<cl_uint>(shift), digitMask,
                      static_cast<cl_uint>(chunks), m_counts);
        queue.enqueueNDRangeKernel(m_tileCount, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
      } else {
        setKernelArgs(m_count, 0, keysFrom, static_cast<cl_uint>(n), static_cast<cl_uint>(shift), digitMask,
                      static_cast<cl_uint>(chunkLength), static_cast<cl_uint>(chunks), m_counts);
        queue.enqueueNDRangeKernel(m_count, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
      }
      // The counts add up to n, below 2^32: no total to read and no overflow to check, so no wait.
      m_scan.exclusiveScanQueued(m_counts, digits * chunks);
      // Null value buffers (keys alone) are passed as null pointers, which the kernels skip.
      if (m_tiles) {
        setKernelArgs(m_tileScatter, 0, keysFrom, valuesFrom, keysTo, valuesTo, static_cast<cl_uint>(n),
                      static_cast<cl_uint>(shift), digitMask, static_cast<cl_uint>(bits),
                      static_cast<cl_uint>(chunks), m_counts);
        queue.enqueueNDRangeKernel(m_tileScatter, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
      } else {
        setKernelArgs(m_scatter, 0, keysFrom, valuesFrom, keysTo, valuesTo, static_cast<cl_uint>(n),
                      static_cast<cl_uint>(shift), digitMask, static_cast<cl_uint>(chunkLength),
                      static_cast<cl_uint>(chunks), m_counts);
        queue.enqueueNDRangeKernel(m_scatter, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
      }
      std::swap(keysFrom, keysTo);
      std::swap(valuesFrom, valuesTo);
    }
    if (passes % 2 == 1) {
      queue.enqueueCopyBuffer(keysFrom, keys, 0, 0, n * sizeof(cl_ulong));
      if (values != nullptr) queue.enqueueCopyBuffer(valuesFrom, *values, 0, 0, n * sizeof(cl_uint));
    }
  });
}

std::size_t OpenClRadixSort::bytes() const {
  return m_keysCapacity * sizeof(cl_ulong) + m_valuesCapacity * sizeof(cl_uint) +
         m_countsCapacity * sizeof(cl_uint) + m_scan.bytes();
}

void OpenClRadixSort::releaseScratch() {
  m_keysTemp = cl::Buffer();
  m_valuesTemp = cl::Buffer();
  m_counts = cl::Buffer();
  m_keysCapacity = m_valuesCapacity = m_countsCapacity = 0;
}

void OpenClRadixSort::sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values,
                           unsigned keyBits) {
  if (keys.size() != values.size()) {
    throw std::invalid_argument("OpenClRadixSort: keys and values differ in length");
  }
  if (keys.size() <= 1) {
    return;
  }
  translateClErrors("OpenCL radix sort of host vectors", [&] {
    const std::size_t n = keys.size();
    cl::Buffer k(m_context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_ulong));
    cl::Buffer v(m_context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_uint));
    cl::CommandQueue& queue = m_context.queue();
    queue.enqueueWriteBuffer(k, CL_FALSE, 0, n * sizeof(cl_ulong), keys.data());
    queue.enqueueWriteBuffer(v, CL_FALSE, 0, n * sizeof(cl_uint), values.data());
    sort(k, v, n, keyBits);
    queue.enqueueReadBuffer(k, CL_FALSE, 0, n * sizeof(cl_ulong), keys.data());
    queue.enqueueReadBuffer(v, CL_TRUE, 0, n * sizeof(cl_uint), values.data());
  });
}

void OpenClRadixSort::sortKeys(std::vector<std::uint64_t>& keys, unsigned keyBits) {
  if (keys.size() <= 1) {
    return;
  }
  translateClErrors("OpenCL radix sort of a host vector of keys", [&] {
    const std::size_t n = keys.size();
    cl::Buffer k(m_context.context(), CL_MEM_READ_WRITE, n * sizeof(cl_ulong));
    cl::CommandQueue& queue = m_context.queue();
    queue.enqueueWriteBuffer(k, CL_FALSE, 0, n * sizeof(cl_ulong), keys.data());
    sortKeys(k, n, keyBits);
    queue.enqueueReadBuffer(k, CL_TRUE, 0, n * sizeof(cl_ulong), keys.data());
  });
}

}  // namespace gpucol::opencl
