#include "opencl/host/scan.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "gpucol_kernels/kernels.h"

namespace gpucol::opencl {

namespace {
/// Chunks shorter than this make the recursive level as long as the work it saves.
constexpr std::size_t kMinChunk = 32;
}  // namespace

OpenClScan::OpenClScan(OpenClContext& context, Method method) : m_context(context) {
  translateClErrors("setting up the OpenCL scan", [&] {
    cl::Program program = m_context.program("scan", kernels::scan);
    m_scanBlocks = cl::Kernel(program, "scan_blocks");
    m_addOffsets = cl::Kernel(program, "scan_add_block_offsets");
    m_chunkTotals = cl::Kernel(program, "scan_chunk_totals");
    m_scanChunks = cl::Kernel(program, "scan_chunks");
    m_chunked = method == Method::Chunked || (method == Method::Auto && !m_context.gpuShaped());
    m_chunkGroupSize =
        std::min(m_context.workGroupSize(m_chunkTotals), m_context.workGroupSize(m_scanChunks));
    const std::size_t units = m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
    m_targetChunks = std::max<std::size_t>(1, units * m_chunkGroupSize);
    // Two values of local memory per work-item.
    m_blockItems = m_context.workGroupSize(m_scanBlocks, 2 * sizeof(cl_uint));
    m_addGroupSize = m_context.workGroupSize(m_addOffsets);
    m_overflow = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, sizeof(cl_uint));
  });
}

std::uint32_t OpenClScan::exclusiveScan(const cl::Buffer& data, std::size_t n) {
  if (n == 0) {
    return 0;
  }
  if (n > 0xffffffffu) {
    throw std::length_error("OpenClScan: " + std::to_string(n) + " values exceed the uint32 index range");
  }
  return translateClErrors("OpenCL exclusive scan", [&] {
    cl::CommandQueue& queue = m_context.queue();
    const cl_uint zero = 0;
    queue.enqueueFillBuffer(m_overflow, zero, 0, sizeof(cl_uint));
    const std::uint32_t total = m_chunked ? scanLevelChunked(data, n, 0, true) : scanLevel(data, n, 0, true);
    cl_uint overflow = 0;
    queue.enqueueReadBuffer(m_overflow, CL_TRUE, 0, sizeof(cl_uint), &overflow);
    if (overflow != 0) {
      throw std::overflow_error("OpenClScan: the sum of " + std::to_string(n) + " values exceeds 2^32 - 1");
    }
    return total;
  });
}

void OpenClScan::exclusiveScanQueued(const cl::Buffer& data, std::size_t n) {
  if (n == 0) {
    return;
  }
  if (n > 0xffffffffu) {
    throw std::length_error("OpenClScan: " + std::to_string(n) + " values exceed the uint32 index range");
  }
  translateClErrors("OpenCL exclusive scan", [&] {
    if (m_chunked) {
      scanLevelChunked(data, n, 0, false);
    } else {
      scanLevel(data, n, 0, false);
    }
  });
}

std::size_t OpenClScan::bytes() const {
  std::size_t total = sizeof(cl_uint);  // m_overflow
  for (std::size_t capacity : m_levelCapacity) total += capacity * sizeof(cl_uint);
  return total;
}

const cl::Buffer& OpenClScan::levelBuffer(std::size_t level, std::size_t count) {
  if (m_levelSums.size() <= level) {
    m_levelSums.resize(level + 1);
    m_levelCapacity.resize(level + 1, 0);
  }
  if (m_levelCapacity[level] < count) {
    m_levelSums[level] = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, count * sizeof(cl_uint));
    m_levelCapacity[level] = count;
  }
  return m_levelSums[level];
}

std::uint32_t OpenClScan::scanLevelChunked(const cl::Buffer& data, std::size_t n, std::size_t level,
                                           bool readTotal) {
  cl::CommandQueue& queue = m_context.queue();
  const std::size_t chunkLength = std::max(kMinChunk, (n + m_targetChunks - 1) / m_targetChunks);
  const std::size_t chunks = (n + chunkLength - 1) / chunkLength;
  const std::size_t global = (chunks + m_chunkGroupSize - 1) / m_chunkGroupSize * m_chunkGroupSize;
  const cl::Buffer sums = levelBuffer(level, chunks);
  setKernelArgs(m_chunkTotals, 0, data, static_cast<cl_uint>(n), static_cast<cl_uint>(chunkLength), sums,
                m_overflow);
  queue.enqueueNDRangeKernel(m_chunkTotals, cl::NullRange, cl::NDRange(global),
                             cl::NDRange(m_chunkGroupSize));
  std::uint32_t total = 0;
  if (chunks == 1) {
    // One chunk: its total is the answer and its offset is zero.
    if (readTotal) queue.enqueueReadBuffer(sums, CL_TRUE, 0, sizeof(cl_uint), &total);
    const cl_uint zero = 0;
    queue.enqueueFillBuffer(sums, zero, 0, sizeof(cl_uint));
  } else {
    total = scanLevelChunked(sums, chunks, level + 1, readTotal);
  }
  setKernelArgs(m_scanChunks, 0, data, static_cast<cl_uint>(n), static_cast<cl_uint>(chunkLength), sums);
  queue.enqueueNDRangeKernel(m_scanChunks, cl::NullRange, cl::NDRange(global), cl::NDRange(m_chunkGroupSize));
  return total;
}

std::uint32_t OpenClScan::scanLevel(const cl::Buffer& data, std::size_t n, std::size_t level, bool readTotal) {
  cl::CommandQueue& queue = m_context.queue();
  const std::size_t blockLength = 2 * m_blockItems;
  const std::size_t blocks = (n + blockLength - 1) / blockLength;
  const cl::Buffer sums = levelBuffer(level, blocks);
  setKernelArgs(m_scanBlocks, 0, data, static_cast<cl_uint>(n), sums, m_overflow,
                cl::Local(blockLength * sizeof(cl_uint)));
  queue.enqueueNDRangeKernel(m_scanBlocks, cl::NullRange, cl::NDRange(blocks * m_blockItems),
                             cl::NDRange(m_blockItems));
  if (blocks == 1) {
    cl_uint total = 0;
    if (readTotal) queue.enqueueReadBuffer(sums, CL_TRUE, 0, sizeof(cl_uint), &total);
    return total;
  }
  const std::uint32_t total = scanLevel(sums, blocks, level + 1, readTotal);
  const std::size_t global = (n + m_addGroupSize - 1) / m_addGroupSize * m_addGroupSize;
  setKernelArgs(m_addOffsets, 0, data, static_cast<cl_uint>(n), sums, static_cast<cl_uint>(blockLength));
  queue.enqueueNDRangeKernel(m_addOffsets, cl::NullRange, cl::NDRange(global), cl::NDRange(m_addGroupSize));
  return total;
}

std::uint32_t OpenClScan::exclusiveScan(std::vector<std::uint32_t>& values) {
  if (values.empty()) {
    return 0;
  }
  return translateClErrors("OpenCL exclusive scan of a host vector", [&] {
    cl::Buffer buffer(m_context.context(), CL_MEM_READ_WRITE, values.size() * sizeof(cl_uint));
    m_context.queue().enqueueWriteBuffer(buffer, CL_TRUE, 0, values.size() * sizeof(cl_uint), values.data());
    const std::uint32_t total = exclusiveScan(buffer, values.size());
    m_context.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, values.size() * sizeof(cl_uint), values.data());
    return total;
  });
}

}  // namespace gpucol::opencl
