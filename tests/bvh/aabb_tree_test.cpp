#include "bvh/aabb_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "bvh/bvh_test_util.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

using test::Soup;

/// Tight box of one triangle, from the float vertices (what the tree must contain, exactly).
void triangleBox(const Soup& soup, std::size_t t, float lo[3], float hi[3]) {
  for (int axis = 0; axis < 3; ++axis) {
    lo[axis] = std::numeric_limits<float>::infinity();
    hi[axis] = -std::numeric_limits<float>::infinity();
  }
  for (int k = 0; k < 3; ++k) {
    const std::size_t v = soup.indices[3 * t + k];
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::min(lo[axis], soup.xyz[3 * v + axis]);
      hi[axis] = std::max(hi[axis], soup.xyz[3 * v + axis]);
    }
  }
}

/// Checks every structural promise of the tree against the soup it was built from, without trusting the builder:
/// node boxes are exactly the union of their children / triangles, the layout is the documented pre-order one,
/// every triangle sits in exactly one leaf, leaves respect trianglesPerLeaf, depth and memory are as stated.
void validateTree(const AabbTree& tree, const Soup& soup, int trianglesPerLeaf) {
  const std::size_t n = soup.triangleCount();
  ASSERT_EQ(tree.triangleCount(), n);
  ASSERT_GE(tree.nodeCount(), 1u);
  EXPECT_LE(tree.memoryBytes(), 64 * n) << "memory bound of 64 bytes per triangle";
  EXPECT_EQ(tree.trianglesPerLeaf(), trianglesPerLeaf);

  std::vector<int> seen(n, 0);
  std::vector<int> depthOf(tree.nodeCount(), 0);
  std::vector<int> parentCount(tree.nodeCount(), 0);
  depthOf[0] = 1;
  std::size_t leaves = 0;
  int maxDepth = 0;
  // Pre-order layout: parents come before children, so one forward sweep sees every parent first.
  for (std::size_t i = 0; i < tree.nodeCount(); ++i) {
    const AabbNode& node = tree.node(i);
    ASSERT_GT(depthOf[i], 0) << "node " << i << " is not reachable from the root";
    maxDepth = std::max(maxDepth, depthOf[i]);
    float lo[3], hi[3];
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = std::numeric_limits<float>::infinity();
      hi[axis] = -std::numeric_limits<float>::infinity();
    }
    if (node.isLeaf()) {
      ++leaves;
      ASSERT_LE(node.count, static_cast<std::uint32_t>(trianglesPerLeaf));
      ASSERT_EQ(tree.leafTriangleCount(i), node.count);
      for (std::uint32_t k = 0; k < node.count; ++k) {
        const std::uint32_t t = tree.leafTriangle(i, k);
        ASSERT_LT(t, n);
        ++seen[t];
        float tlo[3], thi[3];
        triangleBox(soup, t, tlo, thi);
        if (node.count > 1) {
          const AabbLeafEntry& entry = tree.leafEntries()[node.first + k];
          for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(entry.min[axis], tlo[axis]);
            EXPECT_EQ(entry.max[axis], thi[axis]);
          }
        }
        for (int axis = 0; axis < 3; ++axis) {
          lo[axis] = std::min(lo[axis], tlo[axis]);
          hi[axis] = std::max(hi[axis], thi[axis]);
        }
      }
    } else {
      const std::size_t left = i + 1, right = node.first;
      ASSERT_LT(left, tree.nodeCount());
      ASSERT_LT(right, tree.nodeCount());
      ASSERT_GT(right, left);
      for (std::size_t child : {left, right}) {
        ++parentCount[child];
        depthOf[child] = depthOf[i] + 1;
        const AabbNode& c = tree.node(child);
        for (int axis = 0; axis < 3; ++axis) {
          lo[axis] = std::min(lo[axis], c.min[axis]);
          hi[axis] = std::max(hi[axis], c.max[axis]);
        }
      }
    }
    // Containment, and tightness: a node box is exactly the union, so no box is looser than it needs to be.
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(node.min[axis], lo[axis]) << "node " << i << " axis " << axis;
      ASSERT_EQ(node.max[axis], hi[axis]) << "node " << i << " axis " << axis;
    }
  }
  for (std::size_t i = 1; i < tree.nodeCount(); ++i) ASSERT_EQ(parentCount[i], 1) << "node " << i;
  for (std::size_t t = 0; t < n; ++t) ASSERT_EQ(seen[t], 1) << "triangle " << t << " must be in exactly one leaf";
  EXPECT_EQ(tree.nodeCount(), 2 * leaves - 1);
  EXPECT_EQ(tree.depth(), maxDepth);
}

TEST(AabbTree, RandomSoupsKeepEveryInvariant) {
  for (std::size_t count : {1u, 2u, 3u, 17u, 1000u, 6000u}) {
    const Soup soup = test::randomSoup(count, 10.0f, 0.5f, static_cast<std::uint32_t>(count));
    for (int perLeaf : {1, 2, 4, 7}) {
      SCOPED_TRACE(::testing::Message() << count << " triangles, " << perLeaf << " per leaf");
      const AabbTree tree = AabbTree::build(soup.xyz, soup.indices, perLeaf);
      validateTree(tree, soup, perLeaf);
      if (perLeaf == 1) {
        EXPECT_EQ(tree.nodeCount(), 2 * count - 1);
        EXPECT_TRUE(tree.leafEntries().empty());
      }
    }
  }
}

TEST(AabbTree, RealMeshesKeepEveryInvariant) {
  for (const char* file : {"armadillo-2766.ply", "bunny-3851.ply", "torus-1152.ply"}) {
    GPUCOL_REQUIRE_MESH(path, file);
    const TriangleMesh mesh = loadMesh(path);
    const Soup soup = test::soupOf(mesh);
    for (int perLeaf : {1, 2, 4}) {
      SCOPED_TRACE(::testing::Message() << file << ", " << perLeaf << " per leaf");
      const AabbTree tree = AabbTree::build(mesh, perLeaf);
      validateTree(tree, soup, perLeaf);
      // Balanced enough for a real mesh: far from the n levels a degenerate split would give.
      EXPECT_LE(tree.depth(), 4 * static_cast<int>(std::log2(static_cast<double>(mesh.triangleCount())) + 1));
    }
  }
}

/// The root split follows thesis §5.3.2: axis of greatest centroid variance, left side below the mean.
TEST(AabbTree, RootSplitsAtTheMeanOfTheAxisOfGreatestVariance) {
  Soup soup = test::randomSoup(3000, 1.0f, 0.05f, 7);
  // Stretch y so it is clearly the axis of greatest variance; skew it so the mean differs from the median.
  for (std::size_t i = 1; i < soup.xyz.size(); i += 3) soup.xyz[i] = 5.0f * soup.xyz[i] * std::fabs(soup.xyz[i]);
  const AabbTree tree = AabbTree::build(soup.xyz, soup.indices);
  // The centroid exactly as the builder computes it; at the root the items are in triangle order, so the double
  // sum below adds the same numbers in the same order and gives the builder's mean to the last bit.
  auto centroidY = [&](std::size_t t) {
    const float a = soup.xyz[3 * soup.indices[3 * t] + 1], b = soup.xyz[3 * soup.indices[3 * t + 1] + 1],
                c = soup.xyz[3 * soup.indices[3 * t + 2] + 1];
    return (a + b + c) * (1.0f / 3.0f);
  };
  double sum = 0;
  for (std::size_t t = 0; t < soup.triangleCount(); ++t) sum += centroidY(t);
  const double mean = sum / static_cast<double>(soup.triangleCount());
  const AabbNode& root = tree.node(0);
  ASSERT_FALSE(root.isLeaf());
  std::vector<bool> inLeft(soup.triangleCount(), false);
  std::size_t leftCount = 0;
  for (std::size_t i = 1; i < root.first; ++i) {
    if (!tree.node(i).isLeaf()) continue;
    inLeft[tree.leafTriangle(i, 0)] = true;
    ++leftCount;
  }
  for (std::size_t t = 0; t < soup.triangleCount(); ++t) {
    ASSERT_EQ(inLeft[t], centroidY(t) < mean) << "triangle " << t << " is on the wrong side of the mean";
  }
  EXPECT_NE(leftCount, soup.triangleCount() / 2) << "a skewed set should not split at the median";
}

TEST(AabbTree, IdenticalTrianglesGiveABalancedTree) {
  // Every centroid equal: the mean split leaves one side empty each time, so every split is a median split.
  Soup soup;
  soup.xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::size_t n = 20000;
  for (std::size_t t = 0; t < n; ++t) soup.indices.insert(soup.indices.end(), {0, 1, 2});
  const AabbTree tree = AabbTree::build(soup.xyz, soup.indices);
  validateTree(tree, soup, 1);
  EXPECT_EQ(tree.depth(), static_cast<int>(std::ceil(std::log2(static_cast<double>(n)))) + 1);
}

TEST(AabbTree, ExponentiallySpacedTrianglesStayLogarithmicallyDeep) {
  // Centroids at 1.05^i: the mean sits among the largest few, so mean splits alone would peel off a handful of
  // triangles per level and make the tree about n deep; the depth limit switches to median splits.
  Soup soup;
  const std::size_t n = 1500;
  for (std::size_t t = 0; t < n; ++t) {
    const float x = std::pow(1.05f, static_cast<float>(t));
    soup.xyz.insert(soup.xyz.end(), {x, 0, 0, x, 1, 0, x, 0, 1});
    soup.indices.insert(soup.indices.end(), {static_cast<std::uint32_t>(3 * t), static_cast<std::uint32_t>(3 * t + 1),
                                             static_cast<std::uint32_t>(3 * t + 2)});
  }
  const AabbTree tree = AabbTree::build(soup.xyz, soup.indices);
  validateTree(tree, soup, 1);
  const int log2n = static_cast<int>(std::ceil(std::log2(static_cast<double>(n))));
  EXPECT_LE(tree.depth(), 16 + 3 * log2n + 1);
}

TEST(AabbTree, BadInputThrowsWithAClearMessage) {
  const Soup soup = test::randomSoup(4, 1.0f, 0.1f, 1);
  EXPECT_THROW(AabbTree::build(soup.xyz, soup.indices, 0), std::invalid_argument);
  EXPECT_THROW(AabbTree::build(soup.xyz, {}, 1), std::invalid_argument);
  std::vector<std::uint32_t> badIndex = soup.indices;
  badIndex[4] = 1000;
  try {
    AabbTree::build(soup.xyz, badIndex);
    FAIL() << "an index out of range must throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1000"), std::string::npos) << e.what();
  }
  std::vector<float> nan = soup.xyz;
  nan[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(AabbTree::build(nan, soup.indices), std::invalid_argument);
  std::vector<std::uint32_t> partial = soup.indices;
  partial.pop_back();
  EXPECT_THROW(AabbTree::build(soup.xyz, partial), std::invalid_argument);
}

}  // namespace
}  // namespace gpucol
