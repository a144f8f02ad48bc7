#pragma once

#include <cstdint>
#include <vector>

#include "bvh/aabb_tree.h"

namespace gpucol {

/// Depth-first descent of one tree with an explicit stack: `boxWanted(min, max)` decides for every node box
/// (and every triangle box of a leaf holding several) whether to go on, and `visitTriangle(t)` receives each
/// triangle whose box was wanted, in the tree's depth-first order. Used for the single-tree queries of Bullet's
/// interfaces (processAllTriangles, the plane test); tree-vs-tree is tree_traversal.h.
template <class BoxWanted, class VisitTriangle>
void visitTreeTriangles(const AabbTree& tree, BoxWanted&& boxWanted, VisitTriangle&& visitTriangle) {
  std::vector<std::uint32_t> stack;
  stack.reserve(2 * std::size_t(tree.depth()) + 2);
  stack.push_back(0);
  const LargeArrayVector<AabbNode>& nodes = tree.nodes();
  while (!stack.empty()) {
    const std::uint32_t index = stack.back();
    stack.pop_back();
    const AabbNode& node = nodes[index];
    if (!boxWanted(node.min, node.max)) continue;
    if (node.count == 0) {
      stack.push_back(node.first);  // right child, visited after the left one
      stack.push_back(index + 1);   // left child: the next node of the array
    } else if (node.count == 1) {
      visitTriangle(node.first);
    } else {
      for (std::uint32_t i = 0; i < node.count; ++i) {
        const AabbLeafEntry& entry = tree.leafEntries()[node.first + i];
        if (boxWanted(entry.min, entry.max)) visitTriangle(entry.triangle);
      }
    }
  }
}

}  // namespace gpucol
