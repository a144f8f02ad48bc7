// Timings of the middle phase, disabled in the normal suite (timings on a shared machine are not pass/fail).
// Run: gpucol_test_bvh --gtest_also_run_disabled_tests --gtest_filter='BvhBenchmark.*'
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <vector>

#include "bvh/tree_traversal.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Best of `runs` timings of `work`, in milliseconds: the minimum is the least disturbed by other processes.
template <typename Work>
double bestOf(int runs, Work&& work) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < runs; ++i) {
    const Clock::time_point start = Clock::now();
    work();
    best = std::min(best, msSince(start));
  }
  return best;
}

/// Build time of our tree against Bullet's GImpact box set on the same mesh (btGImpactMeshShape over a
/// btTriangleIndexVertexArray; its first updateBound() builds the tree, later ones only refit).
TEST(BvhBenchmark, DISABLED_BuildAgainstGImpact) {
  for (const char* file : {"armadillo-27674.ply", "armadillo-99976.ply"}) {
    GPUCOL_REQUIRE_MESH(path, file);
    const TriangleMesh mesh = loadMesh(path);
    std::vector<float> xyz = mesh.positions();
    std::vector<int> indices(mesh.indices().begin(), mesh.indices().end());
    btIndexedMesh part;
    part.m_numTriangles = static_cast<int>(mesh.triangleCount());
    part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indices.data());
    part.m_triangleIndexStride = 3 * sizeof(int);
    part.m_numVertices = static_cast<int>(mesh.vertexCount());
    part.m_vertexBase = reinterpret_cast<const unsigned char*>(xyz.data());
    part.m_vertexStride = 3 * sizeof(float);
    part.m_vertexType = PHY_FLOAT;
    part.m_indexType = PHY_INTEGER;
    btTriangleIndexVertexArray array;
    array.addIndexedMesh(part, PHY_INTEGER);

    const int runs = 5;
    std::size_t nodes = 0, bytes = 0;
    int depth = 0;
    const double ours = bestOf(runs, [&] {
      const AabbTree tree = AabbTree::build(mesh);
      nodes = tree.nodeCount();
      bytes = tree.memoryBytes();
      depth = tree.depth();
    });
    const double gimpact = bestOf(runs, [&] {
      btGImpactMeshShape shape(&array);
      shape.updateBound();
    });
    std::cout << file << ": " << mesh.triangleCount() << " triangles, AabbTree::build " << ours
              << " ms (" << nodes << " nodes, depth " << depth << ", " << bytes << " bytes), "
              << "btGImpactMeshShape::updateBound " << gimpact << " ms, best of " << runs << "\n";
    EXPECT_EQ(nodes, 2 * mesh.triangleCount() - 1);
  }
}

/// The thesis's scene (Tables 6.1-6.5): two copies of armadillo-27674 centred on the vertex centroid, the second
/// moved along x by 0.3 x the largest side of the bounding box and turned 0.5 rad about y.
TEST(BvhBenchmark, DISABLED_ThesisScene) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-27674.ply");
  const TriangleMesh loaded = loadMesh(path);
  std::vector<float> xyz = loaded.positions();
  const std::size_t vertexCount = xyz.size() / 3;
  double centroid[3] = {0, 0, 0};
  for (std::size_t v = 0; v < vertexCount; ++v) {
    for (int axis = 0; axis < 3; ++axis) centroid[axis] += xyz[3 * v + axis];
  }
  for (int axis = 0; axis < 3; ++axis) centroid[axis] /= static_cast<double>(vertexCount);
  for (std::size_t v = 0; v < vertexCount; ++v) {
    for (int axis = 0; axis < 3; ++axis) xyz[3 * v + axis] = static_cast<float>(xyz[3 * v + axis] - centroid[axis]);
  }
  const AabbTree tree = AabbTree::build(xyz, loaded.indices());
  const float side = (tree.rootMax() - tree.rootMin()).maxCoeff();

  AffineMap map;
  map.linear = Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitY()).toRotationMatrix();
  map.translation = Eigen::Vector3f(0.3f * side, 0, 0);

  std::vector<TrianglePair> serial, parallel;
  TraversalStats serialStats, parallelStats;
  findCandidatePairs(tree, tree, map, serial, &serialStats, false);
  findCandidatePairs(tree, tree, map, parallel, &parallelStats, true);
  ASSERT_EQ(serial, parallel);
  ASSERT_EQ(serialStats.nodeTests, parallelStats.nodeTests);

  const int runs = 20;
  std::vector<TrianglePair> out;
  const double serialMs = bestOf(runs, [&] { findCandidatePairs(tree, tree, map, out, nullptr, false); });
  const double parallelMs = bestOf(runs, [&] { findCandidatePairs(tree, tree, map, out, nullptr, true); });
  std::cout << "thesis scene, armadillo-27674 x2 (x + 0.3 * " << side << ", 0.5 rad about y): "
            << serialStats.nodeTests << " node tests, " << serial.size() << " candidate pairs, serial " << serialMs
            << " ms, parallel " << parallelMs << " ms, best of " << runs << "\n";
  for (int perLeaf : {2, 4, 8}) {
    const AabbTree leafy = AabbTree::build(xyz, loaded.indices(), perLeaf);
    TraversalStats stats;
    findCandidatePairs(leafy, leafy, map, out, &stats, false);
    EXPECT_EQ(out, serial);
    const double ms = bestOf(runs, [&] { findCandidatePairs(leafy, leafy, map, out, nullptr, false); });
    std::cout << "  " << perLeaf << " triangles per leaf: " << leafy.memoryBytes() << " bytes (vs "
              << tree.memoryBytes() << "), " << stats.nodeTests << " tests, serial " << ms << " ms\n";
  }
}

}  // namespace
}  // namespace gpucol
