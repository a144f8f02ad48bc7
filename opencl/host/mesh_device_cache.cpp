#include "opencl/host/mesh_device_cache.h"

#include <algorithm>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

#include "opencl/shared/mesh_pipeline_types.h"

namespace gpucol::opencl {

static_assert(sizeof(GpucolTreeNode) == sizeof(AabbNode) &&
                  offsetof(GpucolTreeNode, max) == offsetof(AabbNode, max) &&
                  offsetof(GpucolTreeNode, first) == offsetof(AabbNode, first) &&
                  offsetof(GpucolTreeNode, count) == offsetof(AabbNode, count),
              "GpucolTreeNode must have AabbNode's layout: the tree is uploaded as it is");
static_assert(sizeof(GpucolLeafEntry) == sizeof(AabbLeafEntry) &&
                  offsetof(GpucolLeafEntry, max) == offsetof(AabbLeafEntry, max) &&
                  offsetof(GpucolLeafEntry, triangle) == offsetof(AabbLeafEntry, triangle),
              "GpucolLeafEntry must have AabbLeafEntry's layout");

namespace {
// Arenas index their elements with 32-bit offsets in the kernels.
constexpr std::size_t kMaxElements = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kElementBytes[3] = {9 * sizeof(float), sizeof(AabbNode), sizeof(AabbLeafEntry)};
}  // namespace

MeshDeviceCache::Arena MeshDeviceCache::makeArena(std::size_t capacity) const {
  Arena arena;
  arena.capacity = capacity;
  if (capacity == 0) return arena;
  // The traversal and the near phase read nodes and triangles at random across arenas of tens of MB; on a
  // CPU device, in the driver's own allocation, those reads missed the TLB. Huge pages (as the CPU path's
  // trees have them, memory/large_array_allocator.h) were faster on PoCL (measurement history). Smaller
  // arenas, and every GPU's, stay in the driver's memory.
  if (!m_context.isGpu() && capacity >= kLargeArrayMapFrom) {
    arena.host = std::make_shared<HostBytes>(capacity);
    arena.buffer = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR, capacity,
                              arena.host->data());
  } else {
    arena.buffer = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, capacity);
  }
  return arena;
}

std::size_t MeshDeviceCache::append(Arena& arena, const void* data, std::size_t bytes) {
  const std::size_t offset = arena.used;
  if (bytes == 0) return offset;
  cl::CommandQueue& queue = m_context.queue();
  // The old arena (its host memory too) stays alive until the blocking write below, which the in-order queue
  // runs after the copy.
  Arena old;
  if (arena.used + bytes > arena.capacity) {
    // Grown by half again, so that adding meshes one by one costs amortised linear copying.
    Arena grown = makeArena(std::max(arena.used + bytes, arena.capacity + arena.capacity / 2));
    if (arena.used > 0) queue.enqueueCopyBuffer(arena.buffer, grown.buffer, 0, 0, arena.used);
    grown.used = arena.used;
    old = std::move(arena);
    arena = std::move(grown);
  }
  // Blocking: the host arrays belong to the mesh and tree, which the caller may drop after the batch.
  queue.enqueueWriteBuffer(arena.buffer, CL_TRUE, offset, bytes, data);
  arena.used += bytes;
  return offset;
}

MeshSlot MeshDeviceCache::acquire(const std::shared_ptr<const TriangleMesh>& mesh, const AabbTree& tree,
                                  std::uint64_t& uploadedBytes) {
  if (!mesh) throw std::invalid_argument("MeshDeviceCache: null mesh");
  if (tree.triangleCount() != mesh->triangleCount()) {
    throw std::invalid_argument("MeshDeviceCache: the tree was not built from this mesh (" +
                                std::to_string(tree.triangleCount()) + " triangles against " +
                                std::to_string(mesh->triangleCount()) + ")");
  }
  dropExpired();
  const Key key{mesh, tree.trianglesPerLeaf()};
  auto found = m_meshes.find(key);
  if (found == m_meshes.end()) {
    // Blocking writes (append): the soup buffer is reused for the next mesh.
    const std::vector<float>& positions = mesh->positions();
    const std::vector<std::uint32_t>& indices = mesh->indices();
    m_soup.resize(3 * indices.size());
    for (std::size_t i = 0; i < indices.size(); ++i) {
      for (int k = 0; k < 3; ++k) m_soup[3 * i + k] = positions[3 * std::size_t(indices[i]) + k];
    }
    const void* data[3] = {m_soup.data(), tree.nodes().data(), tree.leafEntries().data()};
    const std::size_t bytes[3] = {m_soup.size() * sizeof(float), tree.nodes().size() * sizeof(AabbNode),
                                  tree.leafEntries().size() * sizeof(AabbLeafEntry)};
    Arena* arenas[3] = {&m_triangleArena, &m_nodeArena, &m_entryArena};
    Ranges ranges;
    for (int k = 0; k < 3; ++k) {
      if ((arenas[k]->used + bytes[k]) / kElementBytes[k] > kMaxElements) {
        throw std::length_error("MeshDeviceCache: the resident meshes exceed 2^32 elements of one kind");
      }
      ranges.offset[k] = append(*arenas[k], data[k], bytes[k]);
      ranges.bytes[k] = bytes[k];
      uploadedBytes += bytes[k];
    }
    found = m_meshes.emplace(key, ranges).first;
  }
  const Ranges& r = found->second;
  MeshSlot slot;
  slot.triangles = std::uint32_t(r.offset[0] / kElementBytes[0]);
  slot.nodes = std::uint32_t(r.offset[1] / kElementBytes[1]);
  slot.entries = std::uint32_t(r.offset[2] / kElementBytes[2]);
  return slot;
}

std::size_t MeshDeviceCache::dropExpired() {
  std::size_t dropped = 0;
  for (auto it = m_meshes.begin(); it != m_meshes.end();) {
    if (it->first.mesh.expired()) {
      it = m_meshes.erase(it);
      ++dropped;
    } else {
      ++it;
    }
  }
  if (dropped > 0) compact();
  return dropped;
}

void MeshDeviceCache::compact() {
  // The live ranges, in arena order, copied into fresh arenas of exactly their size; the old buffers go when
  // the queue is done with them (OpenCL keeps a buffer alive while commands use it).
  Arena* arenas[3] = {&m_triangleArena, &m_nodeArena, &m_entryArena};
  cl::CommandQueue& queue = m_context.queue();
  // Old arenas whose buffers use host memory: kept until the copies out of them are done.
  std::vector<Arena> old;
  for (int k = 0; k < 3; ++k) {
    std::size_t live = 0;
    for (const auto& entry : m_meshes) live += entry.second.bytes[k];
    Arena fresh = makeArena(live);
    for (auto& entry : m_meshes) {
      Ranges& r = entry.second;
      if (r.bytes[k] > 0)
        queue.enqueueCopyBuffer(arenas[k]->buffer, fresh.buffer, r.offset[k], fresh.used, r.bytes[k]);
      r.offset[k] = fresh.used;
      fresh.used += r.bytes[k];
    }
    if (arenas[k]->host) old.push_back(std::move(*arenas[k]));
    *arenas[k] = std::move(fresh);
  }
  if (!old.empty()) queue.finish();
}

}  // namespace gpucol::opencl
