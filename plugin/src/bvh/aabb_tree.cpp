#include "bvh/aabb_tree.h"

#include <tbb/parallel_invoke.h>

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
/// build O(n^2) and the tree n deep; real meshes stay far below this bound (armadillo-99976: depth 20 against
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

/// Writes the box of items [begin, end) into `node` (step 2a of thesis §5.3.2) and, when the range holds more
/// than `perLeaf` items, partitions it and returns the split index (steps 2b-2d); returns `end` for a leaf.
std::uint32_t boxAndSplit(std::vector<BuildItem>& items, std::uint32_t first, std::uint32_t last, int depth,
                          int meanSplitLimit, std::size_t perLeaf, AabbNode& node) {
  // One pass for the box and the centroid statistics. The sums are in double: in float, 10^5 centroids far
  // from the origin lose the digits the variance is made of.
  float lo[3], hi[3];
  double sum[3] = {0, 0, 0}, sumSquares[3] = {0, 0, 0};
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = std::numeric_limits<float>::infinity();
    hi[axis] = -std::numeric_limits<float>::infinity();
  }
  for (std::uint32_t i = first; i < last; ++i) {
    const BuildItem& item = items[i];
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::min(lo[axis], item.min[axis]);
      hi[axis] = std::max(hi[axis], item.max[axis]);
      const double c = item.centroid[axis];
      sum[axis] += c;
      sumSquares[axis] += c * c;
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    node.min[axis] = lo[axis];
    node.max[axis] = hi[axis];
  }
  const std::uint32_t count = last - first;
  if (count <= perLeaf) return last;

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
  BuildItem* const begin = items.data() + first;
  BuildItem* const end = items.data() + last;
  BuildItem* mid = end;
  if (depth < meanSplitLimit) {
    const double splitAt = mean[axis];
    mid = std::partition(begin, end, [axis, splitAt](const BuildItem& item) { return item.centroid[axis] < splitAt; });
  }
  if (mid == begin || mid == end) {
    // One side would be empty (all centroids equal along the axis, or past the depth limit): split at the
    // median, which halves the range whatever the coordinates, so identical triangles still give log2(n) levels.
    mid = begin + count / 2;
    std::nth_element(begin, mid, end,
                     [axis](const BuildItem& l, const BuildItem& r) { return l.centroid[axis] < r.centroid[axis]; });
  }
  return static_cast<std::uint32_t>(mid - items.data());
}

/// Ranges at least this large are split into two parallel tasks; below it one thread builds the whole subtree
/// (a few thousand triangles take tens of microseconds, well above the cost of a task).
constexpr std::uint32_t kParallelBuildGrain = 4096;

/// Builder of a tree with one triangle per leaf, where a range [begin, end) starting at node i has its left child
/// at i + 1 and its right child at i + 2 * (split - begin).
struct NodeRangeBuilder {
  std::vector<BuildItem>& items;
  LargeArrayVector<AabbNode>& nodes;
  int meanSplitLimit;

  /// Builds the subtree of [begin, end) at `nodeIndex` and returns its deepest level. Recursion happens only for
  /// ranges above kParallelBuildGrain, so its depth is bounded by the split depth limit, not by the input.
  int buildParallel(std::uint32_t begin, std::uint32_t end, std::uint32_t nodeIndex, int depth) const {
    if (end - begin < kParallelBuildGrain) return buildSerial(begin, end, nodeIndex, depth);
    const std::uint32_t split = boxAndSplit(items, begin, end, depth, meanSplitLimit, 1, nodes[nodeIndex]);
    const std::uint32_t right = nodeIndex + 2 * (split - begin);
    nodes[nodeIndex].first = right;
    int leftDepth = 0, rightDepth = 0;
    tbb::parallel_invoke([&] { leftDepth = buildParallel(begin, split, nodeIndex + 1, depth + 1); },
                         [&] { rightDepth = buildParallel(split, end, right, depth + 1); });
    return std::max(leftDepth, rightDepth);
  }

  /// The same with an explicit stack, on one thread.
  int buildSerial(std::uint32_t begin, std::uint32_t end, std::uint32_t nodeIndex, int depth) const {
    struct Task {
      std::uint32_t begin, end, node;
      int depth;
    };
    std::vector<Task> stack{{begin, end, nodeIndex, depth}};
    int deepest = depth;
    while (!stack.empty()) {
      const Task task = stack.back();
      stack.pop_back();
      deepest = std::max(deepest, task.depth);
      AabbNode& node = nodes[task.node];
      const std::uint32_t split = boxAndSplit(items, task.begin, task.end, task.depth, meanSplitLimit, 1, node);
      if (split == task.end) {
        node.count = 1;
        node.first = items[task.begin].triangle;
        continue;
      }
      node.first = task.node + 2 * (split - task.begin);
      stack.push_back({split, task.end, node.first, task.depth + 1});
      stack.push_back({task.begin, split, task.node + 1, task.depth + 1});
    }
    return deepest;
  }
};

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
  const int meanSplitLimit = meanSplitDepthLimit((triangleCount + perLeaf - 1) / perLeaf);

  AabbTree tree;
  tree.m_triangleCount = triangleCount;
  tree.m_trianglesPerLeaf = trianglesPerLeaf;
  if (perLeaf == 1) {
    // Exactly 2n - 1 nodes, and a subtree over c triangles has 2c - 1, so every node's index is known before its
    // subtree is built and the subtrees can be built in parallel into one array.
    tree.m_nodes.resize(2 * triangleCount - 1, AabbNode{});  // inner nodes keep count 0
    const NodeRangeBuilder builder{items, tree.m_nodes, meanSplitLimit};
    tree.m_depth = builder.buildParallel(0, static_cast<std::uint32_t>(triangleCount), 0, 1);
    return tree;
  }

  // Several triangles per leaf: the node count depends on the splits, so the build is serial and depth first.
  // The left child is pushed last, so it is popped next and lands right after its parent in the array; the right
  // child writes its index into the parent when its turn comes.
  tree.m_nodes.reserve(2 * triangleCount - 1);
  std::vector<BuildTask> stack;
  stack.push_back({0, static_cast<std::uint32_t>(triangleCount), 0, false, 1});
  while (!stack.empty()) {
    const BuildTask task = stack.back();
    stack.pop_back();
    const std::uint32_t nodeIndex = static_cast<std::uint32_t>(tree.m_nodes.size());
    tree.m_nodes.push_back(AabbNode{});  // inner nodes keep count 0
    if (task.isRight) tree.m_nodes[task.parent].first = nodeIndex;
    tree.m_depth = std::max(tree.m_depth, task.depth);
    const std::uint32_t split =
        boxAndSplit(items, task.begin, task.end, task.depth, meanSplitLimit, perLeaf, tree.m_nodes[nodeIndex]);
    if (split != task.end) {
      stack.push_back({split, task.end, nodeIndex, true, task.depth + 1});
      stack.push_back({task.begin, split, nodeIndex, false, task.depth + 1});
      continue;
    }
    AabbNode& node = tree.m_nodes[nodeIndex];
    node.count = task.end - task.begin;
    if (node.count == 1) {
      node.first = items[task.begin].triangle;
      continue;
    }
    node.first = static_cast<std::uint32_t>(tree.m_leafEntries.size());
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      const BuildItem& item = items[i];
      tree.m_leafEntries.push_back(
          {{item.min[0], item.min[1], item.min[2]}, {item.max[0], item.max[1], item.max[2]}, item.triangle});
    }
  }

  tree.m_nodes.shrink_to_fit();
  tree.m_leafEntries.shrink_to_fit();
  return tree;
}

}  // namespace gpucol
