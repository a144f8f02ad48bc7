#include "bvh/aabb_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace gpucol {
namespace {

/// What the builder moves around: a triangle's centroid and box, kept together so the partition of a node's
/// range works on one contiguous array instead of chasing triangle indices (40 bytes).
struct BuildItem {
  float centroid[3];
  float min[3];
  float max[3];
  std::uint32_t triangle;
};

/// A range of build items that becomes one node; `parent` gets the node's index when `isRight`.
struct BuildTask {
  std::uint32_t begin;
  std::uint32_t end;
  std::uint32_t parent;
  bool isRight;
  int depth;
};

/// Deepest level at which the mean split of thesis §5.3.2 is still used; below it every split is a median split.
/// The mean split alone can cut one triangle off per level (exponentially spaced centroids), which makes the
/// build O(n^2) and the tree n deep; real meshes stay far above this bound (armadillo-99976: depth 27 against
/// 16 + 2 * 17 = 50), so the thesis's tree is unchanged on them while the worst case stays O(n log n).
int meanSplitDepthLimit(std::size_t leafCount) {
  int log2 = 0;
  while ((std::size_t{1} << log2) < leafCount) ++log2;
  return 16 + 2 * log2;
}

std::vector<BuildItem> makeItems(const float* xyz, std::size_t vertexCount, const std::uint32_t* indices,
                                 std::size_t triangleCount) {
  std::vector<BuildItem> items(triangleCount);
  for (std::size_t t = 0; t < triangleCount; ++t) {
    BuildItem& item = items[t];
    const float* v[3];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t index = indices[3 * t + k];
      if (index >= vertexCount) {
        throw std::invalid_argument("AabbTree::build: triangle " + std::to_string(t) + " has vertex index " +
                                    std::to_string(index) + " but there are only " + std::to_string(vertexCount) +
                                    " vertices");
      }
      v[k] = xyz + 3 * std::size_t{index};
    }
    for (int axis = 0; axis < 3; ++axis) {
      const float a = v[0][axis], b = v[1][axis], c = v[2][axis];
      item.min[axis] = std::min(a, std::min(b, c));
      item.max[axis] = std::max(a, std::max(b, c));
      item.centroid[axis] = (a + b + c) * (1.0f / 3.0f);
    }
    item.triangle = static_cast<std::uint32_t>(t);
  }
  return items;
}

}  // namespace

AabbTree AabbTree::build(const TriangleMesh& mesh, int trianglesPerLeaf) {
  return build(mesh.positions(), mesh.indices(), trianglesPerLeaf);
}

AabbTree AabbTree::build(const std::vector<float>& xyz, const std::vector<std::uint32_t>& indices,
                         int trianglesPerLeaf) {
  if (trianglesPerLeaf < 1) {
    throw std::invalid_argument("AabbTree::build: trianglesPerLeaf must be >= 1, got " +
                                std::to_string(trianglesPerLeaf));
  }
  if (xyz.size() % 3 != 0 || indices.size() % 3 != 0) {
    throw std::invalid_argument("AabbTree::build: " + std::to_string(xyz.size()) + " coordinates and " +
                                std::to_string(indices.size()) + " indices are not whole triples");
  }
  const std::size_t triangleCount = indices.size() / 3;
  if (triangleCount == 0) throw std::invalid_argument("AabbTree::build: the mesh has no triangles");
  // 2n - 1 nodes must be addressable by the 32-bit child index of AabbNode.
  if (triangleCount > (std::size_t{1} << 31) - 1) {
    throw std::invalid_argument("AabbTree::build: " + std::to_string(triangleCount) +
                                " triangles exceed the 2^31 - 1 a 32-bit node index can address");
  }
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    if (!std::isfinite(xyz[i])) {
      throw std::invalid_argument("AabbTree::build: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
    }
  }

  std::vector<BuildItem> items = makeItems(xyz.data(), xyz.size() / 3, indices.data(), triangleCount);
  const std::size_t perLeaf = static_cast<std::size_t>(trianglesPerLeaf);

  AabbTree tree;
  tree.m_triangleCount = triangleCount;
  tree.m_trianglesPerLeaf = trianglesPerLeaf;
  // A binary tree over at most n leaves has at most 2n - 1 nodes; one allocation, trimmed at the end.
  tree.m_nodes.reserve(2 * triangleCount - 1);

  const int meanSplitLimit = meanSplitDepthLimit((triangleCount + perLeaf - 1) / perLeaf);
  // Explicit stack, depth first: the left child is pushed last, so it is popped next and lands right after
  // its parent in the array; the right child writes its index into the parent when its turn comes.
  std::vector<BuildTask> stack;
  stack.push_back({0, static_cast<std::uint32_t>(triangleCount), 0, false, 1});
  while (!stack.empty()) {
    const BuildTask task = stack.back();
    stack.pop_back();
    const std::uint32_t nodeIndex = static_cast<std::uint32_t>(tree.m_nodes.size());
    tree.m_nodes.emplace_back();
    if (task.isRight) tree.m_nodes[task.parent].first = nodeIndex;
    tree.m_depth = std::max(tree.m_depth, task.depth);

    // One pass for the node's box (step 2a of §5.3.2) and the centroid statistics (step 2b). The sums are in
    // double: in float, 10^5 centroids far from the origin lose the digits the variance is made of.
    float lo[3], hi[3];
    double sum[3] = {0, 0, 0}, sumSquares[3] = {0, 0, 0};
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::numeric_limits<float>::infinity();
      hi[axis] = -std::numeric_limits<float>::infinity();
    }
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      const BuildItem& item = items[i];
      for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = std::min(lo[axis], item.min[axis]);
        hi[axis] = std::max(hi[axis], item.max[axis]);
        const double c = item.centroid[axis];
        sum[axis] += c;
        sumSquares[axis] += c * c;
      }
    }
    {
      AabbNode& node = tree.m_nodes[nodeIndex];
      for (int axis = 0; axis < 3; ++axis) {
        node.min[axis] = lo[axis];
        node.max[axis] = hi[axis];
      }
    }

    const std::uint32_t count = task.end - task.begin;
    if (count <= perLeaf) {
      AabbNode& node = tree.m_nodes[nodeIndex];
      node.count = count;
      if (count == 1) {
        node.first = items[task.begin].triangle;
      } else {
        node.first = static_cast<std::uint32_t>(tree.m_leafEntries.size());
        for (std::uint32_t i = task.begin; i < task.end; ++i) {
          const BuildItem& item = items[i];
          tree.m_leafEntries.push_back({{item.min[0], item.min[1], item.min[2]},
                                        {item.max[0], item.max[1], item.max[2]},
                                        item.triangle});
        }
      }
      continue;
    }

    // Split axis: greatest variance of the centroids; split position: their mean (thesis §5.3.2, 2b-2c).
    const double n = count;
    int axis = 0;
    double mean[3], bestVariance = -1;
    for (int a = 0; a < 3; ++a) {
      mean[a] = sum[a] / n;
      const double variance = sumSquares[a] / n - mean[a] * mean[a];
      if (variance > bestVariance) {
        bestVariance = variance;
        axis = a;
      }
    }
    BuildItem* const begin = items.data() + task.begin;
    BuildItem* const end = items.data() + task.end;
    BuildItem* mid = end;
    if (task.depth < meanSplitLimit) {
      const double splitAt = mean[axis];
      mid = std::partition(begin, end, [axis, splitAt](const BuildItem& item) { return item.centroid[axis] < splitAt; });
    }
    if (mid == begin || mid == end) {
      // One side would be empty (all centroids equal along the axis, or past the depth limit): split at the
      // median, which halves the range whatever the coordinates, so identical triangles still give log2(n) levels.
      mid = begin + count / 2;
      std::nth_element(begin, mid, end, [axis](const BuildItem& l, const BuildItem& r) {
        return l.centroid[axis] < r.centroid[axis];
      });
    }
    const std::uint32_t split = static_cast<std::uint32_t>(mid - items.data());
    stack.push_back({split, task.end, nodeIndex, true, task.depth + 1});
    stack.push_back({task.begin, split, nodeIndex, false, task.depth + 1});
  }

  tree.m_nodes.shrink_to_fit();
  tree.m_leafEntries.shrink_to_fit();
  return tree;
}

}  // namespace gpucol
