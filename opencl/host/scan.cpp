#include "opencl/host/scan.h"

#include "gpucol_kernels/kernels.h"

#include <stdexcept>
#include <string>

namespace gpucol::opencl {

OpenClScan::OpenClScan(OpenClContext& context) : m_context(context) {
  translateClErrors("setting up the OpenCL scan", [&] {
    cl::Program program = m_context.program("scan", kernels::scan);
    m_scanBlocks = cl::Kernel(program, "scan_blocks");
    m_addOffsets = cl::Kernel(program, "scan_add_block_offsets");
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
    const std::uint32_t total = scanLevel(data, n, 0);
    cl_uint overflow = 0;
    queue.enqueueReadBuffer(m_overflow, CL_TRUE, 0, sizeof(cl_uint), &overflow);
    if (overflow != 0) {
      throw std::overflow_error("OpenClScan: the sum of " + std::to_string(n) +
                                " values exceeds 2^32 - 1");
    }
    return total;
  });
}

std::uint32_t OpenClScan::scanLevel(const cl::Buffer& data, std::size_t n, std::size_t level) {
  cl::CommandQueue& queue = m_context.queue();
  const std::size_t blockLength = 2 * m_blockItems;
  const std::size_t blocks = (n + blockLength - 1) / blockLength;
  if (m_levelSums.size() <= level) {
    m_levelSums.resize(level + 1);
    m_levelCapacity.resize(level + 1, 0);
  }
  if (m_levelCapacity[level] < blocks) {
    m_levelSums[level] = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, blocks * sizeof(cl_uint));
    m_levelCapacity[level] = blocks;
  }
  const cl::Buffer sums = m_levelSums[level];
  m_scanBlocks.setArg(0, data);
  m_scanBlocks.setArg(1, static_cast<cl_uint>(n));
  m_scanBlocks.setArg(2, sums);
  m_scanBlocks.setArg(3, m_overflow);
  m_scanBlocks.setArg(4, cl::Local(blockLength * sizeof(cl_uint)));
  queue.enqueueNDRangeKernel(m_scanBlocks, cl::NullRange, cl::NDRange(blocks * m_blockItems),
                             cl::NDRange(m_blockItems));
  if (blocks == 1) {
    cl_uint total = 0;
    queue.enqueueReadBuffer(sums, CL_TRUE, 0, sizeof(cl_uint), &total);
    return total;
  }
  const std::uint32_t total = scanLevel(sums, blocks, level + 1);
  const std::size_t global = (n + m_addGroupSize - 1) / m_addGroupSize * m_addGroupSize;
  m_addOffsets.setArg(0, data);
  m_addOffsets.setArg(1, static_cast<cl_uint>(n));
  m_addOffsets.setArg(2, sums);
  m_addOffsets.setArg(3, static_cast<cl_uint>(blockLength));
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
