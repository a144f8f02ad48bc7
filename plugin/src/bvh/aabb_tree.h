#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "gpucol/triangle_mesh.h"
#include "memory/large_array_allocator.h"

namespace gpucol {

/// One node of an AabbTree: an axis-aligned box in the mesh's own frame and two indices (32 bytes).
/// Inner node: `count == 0`, the left child is the next node of the array and `first` is the right child.
/// Leaf with one triangle: `count == 1` and `first` is the triangle index itself (no indirection, thesis §5.3.2).
/// Leaf with several triangles: `count > 1` and `first` is the offset of its entries in AabbTree::leafEntries().
struct AabbNode {
  float min[3];         ///< Lower corner of the box.
  float max[3];         ///< Upper corner of the box.
  std::uint32_t first;  ///< Right child (inner), triangle (leaf of one) or first leaf entry (leaf of several).
  std::uint32_t count;  ///< 0 for an inner node, else the number of triangles in the leaf.

  /// True when the node is a leaf.
  bool isLeaf() const { return count != 0; }
};
static_assert(sizeof(AabbNode) == 32, "AabbNode must stay 32 bytes: memoryBytes() promises <= 64 bytes per triangle");

/// A triangle of a leaf that holds several, with its own box so that the traversal tests triangle boxes and
/// gives the same candidates whatever the leaf size (28 bytes).
struct AabbLeafEntry {
  float min[3];            ///< Lower corner of the triangle's box.
  float max[3];            ///< Upper corner of the triangle's box.
  std::uint32_t triangle;  ///< Triangle index in the mesh.
};

/// The tree of non-updated AABBs of a triangle mesh (thesis §3.2.2, §3.3, §5.3.2): built once, top-down, in
/// the mesh's own frame and never refit; a rigid motion is applied to the boxes at query time instead.
/// Nodes live in one flat array in depth-first order, root at index 0.
class AabbTree {
 public:
  /// Builds the tree of a mesh in its own frame. trianglesPerLeaf >= 1 (1 is the thesis's choice and the default).
  /// Throws std::invalid_argument for trianglesPerLeaf < 1, an empty mesh or more than 2^31 - 1 triangles.
  static AabbTree build(const TriangleMesh& mesh, int trianglesPerLeaf = 1);

  /// Builds the tree of raw arrays: `xyz` holds 3 floats per vertex, `indices` 3 vertex indices per triangle.
  /// A non-finite coordinate, an index out of range or a partial triple throws std::invalid_argument naming it.
  static AabbTree build(const std::vector<float>& xyz, const std::vector<std::uint32_t>& indices,
                        int trianglesPerLeaf = 1);

  /// All nodes, root at index 0 (on huge pages where the system gives them: the traversal reads them at
  /// random).
  const LargeArrayVector<AabbNode>& nodes() const { return m_nodes; }
  /// One node.
  const AabbNode& node(std::size_t index) const { return m_nodes[index]; }
  /// Number of nodes (2 * leaves - 1).
  std::size_t nodeCount() const { return m_nodes.size(); }
  /// Entries of the leaves that hold more than one triangle (empty when trianglesPerLeaf is 1).
  const std::vector<AabbLeafEntry>& leafEntries() const { return m_leafEntries; }
  /// Number of triangles the tree was built from.
  std::size_t triangleCount() const { return m_triangleCount; }
  /// The trianglesPerLeaf the tree was built with.
  int trianglesPerLeaf() const { return m_trianglesPerLeaf; }
  /// Number of levels: 1 for a single leaf.
  int depth() const { return m_depth; }

  /// Lower corner of the root box (the mesh's bounding box).
  Eigen::Vector3f rootMin() const { return Eigen::Vector3f(m_nodes[0].min[0], m_nodes[0].min[1], m_nodes[0].min[2]); }
  /// Upper corner of the root box.
  Eigen::Vector3f rootMax() const { return Eigen::Vector3f(m_nodes[0].max[0], m_nodes[0].max[1], m_nodes[0].max[2]); }

  /// Number of triangles in the leaf `nodeIndex` (0 for an inner node).
  std::uint32_t leafTriangleCount(std::size_t nodeIndex) const { return m_nodes[nodeIndex].count; }
  /// The i-th triangle of the leaf `nodeIndex`, i < leafTriangleCount(nodeIndex).
  std::uint32_t leafTriangle(std::size_t nodeIndex, std::uint32_t i) const {
    const AabbNode& n = m_nodes[nodeIndex];
    return n.count == 1 ? n.first : m_leafEntries[n.first + i].triangle;
  }

  /// Bytes held by the tree's arrays (nodes and leaf entries, by capacity); at most 64 per triangle.
  std::size_t memoryBytes() const {
    return m_nodes.capacity() * sizeof(AabbNode) + m_leafEntries.capacity() * sizeof(AabbLeafEntry);
  }

 private:
  AabbTree() = default;

  LargeArrayVector<AabbNode> m_nodes;
  std::vector<AabbLeafEntry> m_leafEntries;
  std::size_t m_triangleCount = 0;
  int m_trianglesPerLeaf = 1;
  int m_depth = 0;
};

}  // namespace gpucol
