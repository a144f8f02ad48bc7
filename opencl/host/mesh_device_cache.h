#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "bvh/aabb_tree.h"
#include "gpucol/triangle_mesh.h"
#include "memory/large_array_allocator.h"
#include "opencl/host/opencl_context.h"

namespace gpucol::opencl {

/// Where one mesh lies in the resident arenas: first node, leaf entry and triangle.
struct MeshSlot {
  std::uint32_t nodes = 0;      ///< First node of its tree in the node arena.
  std::uint32_t entries = 0;    ///< First leaf entry in the entry arena.
  std::uint32_t triangles = 0;  ///< First triangle in the triangle soup arena (9 floats each).
};

/// The meshes of the mesh pipeline kept on the device (triangle soup, tree nodes, leaf entries),
/// uploaded once per mesh and tree shape (thesis §5.4.1 re-sent triangles every step; this keeps them
/// resident).
///
/// The triangles go as a soup, each its three corners' coordinates in a row (9 floats, 36 bytes), as
/// MeshShape keeps them for the CPU path: the near phase reads a triangle in one place instead of three
/// indices and then three vertices elsewhere (two dependent cache misses per triangle on large meshes).
///
/// All meshes share three arenas, so that one kernel launch can reach every mesh of a batch; a mesh is found
/// by its slot's offsets. Entries are keyed by the mesh's shared pointer through a std::weak_ptr (owner
/// order), so a dead mesh can never be mistaken for a new one at the same address, and by the tree's leaf
/// size. A mesh whose last owner is gone is dropped at the next acquire(): its arena ranges are given back by
/// copying the live ranges into fresh arenas (on the device, no host transfer). Not thread-safe: the pipeline
/// serialises.
class MeshDeviceCache {
 public:
  /// An empty cache on `context`.
  explicit MeshDeviceCache(OpenClContext& context) : m_context(context) {}

  /// Drops every mesh whose last owner is gone, then the slot of `mesh` with `tree` (built from it),
  /// uploading them when not resident. Returns the bytes written to the device in `uploadedBytes` (added).
  MeshSlot acquire(const std::shared_ptr<const TriangleMesh>& mesh, const AabbTree& tree,
                   std::uint64_t& uploadedBytes);

  /// Drops every mesh whose owners are all gone; returns how many were dropped.
  std::size_t dropExpired();

  /// Number of meshes resident.
  std::size_t size() const { return m_meshes.size(); }

  /// Triangle soup arena (9 floats per triangle: corners 0, 1, 2, each x, y, z).
  const cl::Buffer& triangles() const { return m_triangleArena.buffer; }
  /// Node arena (GpucolTreeNode, children relative to the tree's first node).
  const cl::Buffer& nodes() const { return m_nodeArena.buffer; }
  /// Leaf entry arena (GpucolLeafEntry, relative to the tree's first entry).
  const cl::Buffer& entries() const { return m_entryArena.buffer; }

 private:
  /// Host memory a CPU device's arena lives in (huge pages where the system gives them).
  using HostBytes = std::vector<unsigned char, LargeArrayAllocator<unsigned char>>;

  /// One growable device arena; `used` bytes hold live data. On a CPU device a large arena's buffer uses
  /// `host` as its storage (CL_MEM_USE_HOST_PTR), which must outlive every command on the buffer.
  struct Arena {
    cl::Buffer buffer;
    std::shared_ptr<HostBytes> host;
    std::size_t capacity = 0;
    std::size_t used = 0;
  };

  struct Key {
    std::weak_ptr<const TriangleMesh> mesh;
    int trianglesPerLeaf;
  };
  struct KeyLess {
    bool operator()(const Key& l, const Key& r) const {
      if (l.mesh.owner_before(r.mesh)) return true;
      if (r.mesh.owner_before(l.mesh)) return false;
      return l.trianglesPerLeaf < r.trianglesPerLeaf;
    }
  };
  /// Byte ranges of one mesh in the three arenas.
  struct Ranges {
    std::size_t offset[3];
    std::size_t bytes[3];
  };

  /// Appends `bytes` of `data` to `arena`, growing it (device-side copy of the old contents); returns the
  /// byte offset.
  std::size_t append(Arena& arena, const void* data, std::size_t bytes);
  void compact();
  /// A new, empty arena of `capacity` bytes.
  Arena makeArena(std::size_t capacity) const;

  OpenClContext& m_context;
  Arena m_triangleArena, m_nodeArena, m_entryArena;
  std::vector<float> m_soup;  // the soup of the mesh being uploaded
  std::map<Key, Ranges, KeyLess> m_meshes;
};

}  // namespace gpucol::opencl
