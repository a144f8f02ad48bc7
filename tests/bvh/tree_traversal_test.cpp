#include "bvh/tree_traversal.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "bvh/bvh_test_util.h"
#include "support/test_paths.h"

namespace gpucol {
namespace {

using test::Soup;

struct BoxD {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
};

bool overlapsD(const BoxD& l, const BoxD& r) {
  return (l.min.array() <= r.max.array()).all() && (r.min.array() <= l.max.array()).all();
}

BoxD triangleBoxD(const Soup& soup, std::size_t t) {
  BoxD box{soup.vertex(t, 0), soup.vertex(t, 0)};
  for (int k = 1; k < 3; ++k) {
    box.min = box.min.cwiseMin(soup.vertex(t, k));
    box.max = box.max.cwiseMax(soup.vertex(t, k));
  }
  return box;
}

/// The brute-force references of one query, every triangle pair tested in double, in both frames (A's, with
/// B's boxes carried in, and B's, with A's carried in by the traversal's inverse map).
struct Reference {
  std::vector<TrianglePair> carriedExact;     ///< Leaf (= triangle) boxes carried in double, no widening.
  std::vector<TrianglePair> carriedWidened;   ///< The same, widened by twice the traversal's documented epsilon.
  std::vector<TrianglePair>
      tightTriangles;  ///< Each triangle moved into the other's frame in double, then boxed.
};

/// One frame's boxes of the other mesh's triangles: carried as boxes (exact and widened) and moved as
/// triangles.
struct CarriedBoxes {
  std::vector<BoxD> exact, widened, tight;
};

CarriedBoxes carryTriangles(const Soup& soup, const BoxMap& boxMap) {
  const Eigen::Matrix3d m = boxMap.map.linear.cast<double>();
  const Eigen::Vector3d t = boxMap.map.translation.cast<double>();
  const Eigen::Vector3d widen = 2.0 * boxMap.inflation.cast<double>();
  CarriedBoxes out;
  for (std::size_t j = 0; j < soup.triangleCount(); ++j) {
    const BoxD box = triangleBoxD(soup, j);
    const Eigen::Vector3d c = m * (0.5 * (box.min + box.max)) + t;
    const Eigen::Vector3d e = m.cwiseAbs() * (0.5 * (box.max - box.min));
    out.exact.push_back({c - e, c + e});
    out.widened.push_back({c - e - widen, c + e + widen});
    const Eigen::Vector3d p = m * soup.vertex(j, 0) + t;
    BoxD tight{p, p};
    for (int k = 1; k < 3; ++k) {
      const Eigen::Vector3d q = m * soup.vertex(j, k) + t;
      tight.min = tight.min.cwiseMin(q);
      tight.max = tight.max.cwiseMax(q);
    }
    out.tight.push_back(tight);
  }
  return out;
}

Reference bruteForce(const Soup& a, const Soup& b, const AabbTree& treeA, const AabbTree& treeB,
                     const AffineMap& map) {
  std::vector<BoxD> boxesA(a.triangleCount()), boxesB(b.triangleCount());
  for (std::size_t i = 0; i < a.triangleCount(); ++i) boxesA[i] = triangleBoxD(a, i);
  for (std::size_t j = 0; j < b.triangleCount(); ++j) boxesB[j] = triangleBoxD(b, j);
  // B's frame's map is the traversal's own (the inverse rounded to float), checked here against the inverse.
  const BoxMap intoB = boxMapIntoB(treeA, map);
  const Eigen::Matrix3d inverse = map.linear.cast<double>().inverse();
  EXPECT_TRUE(intoB.map.linear.cast<double>().isApprox(inverse, 1e-6));
  EXPECT_TRUE(intoB.map.translation.cast<double>().isApprox(-inverse * map.translation.cast<double>(), 1e-6));
  EXPECT_TRUE(intoB.inflation.allFinite());
  const CarriedBoxes bInA = carryTriangles(b, boxMapIntoA(treeB, map));
  const CarriedBoxes aInB = carryTriangles(a, intoB);
  Reference ref;
  for (std::size_t i = 0; i < a.triangleCount(); ++i) {
    for (std::size_t j = 0; j < b.triangleCount(); ++j) {
      const TrianglePair pair{static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)};
      auto inBoth = [&](const std::vector<BoxD>& bCarried, const std::vector<BoxD>& aCarried) {
        return overlapsD(boxesA[i], bCarried[j]) && overlapsD(boxesB[j], aCarried[i]);
      };
      if (inBoth(bInA.exact, aInB.exact)) ref.carriedExact.push_back(pair);
      if (inBoth(bInA.widened, aInB.widened)) ref.carriedWidened.push_back(pair);
      if (inBoth(bInA.tight, aInB.tight)) ref.tightTriangles.push_back(pair);
    }
  }
  return ref;
}

bool isSortedUnique(const std::vector<TrianglePair>& pairs) {
  return std::adjacent_find(pairs.begin(), pairs.end(),
                            [](const TrianglePair& l, const TrianglePair& r) { return !(l < r); }) == pairs.end();
}

/// Runs every check of one query; returns the number of candidates so callers can make sure some poses hit.
std::size_t checkQuery(const Soup& a, const Soup& b, const AffineMap& map) {
  const AabbTree treeA = AabbTree::build(a.xyz, a.indices);
  const AabbTree treeB = AabbTree::build(b.xyz, b.indices);
  const Reference ref = bruteForce(a, b, treeA, treeB, map);

  std::vector<TrianglePair> parallel, serial;
  TraversalStats parallelStats, serialStats;
  findCandidatePairs(treeA, treeB, map, parallel, &parallelStats, true);
  findCandidatePairs(treeA, treeB, map, serial, &serialStats, false);
  EXPECT_TRUE(isSortedUnique(parallel));
  EXPECT_EQ(parallel, serial) << "parallel and serial traversals must give the same list";
  EXPECT_EQ(parallelStats.nodeTests, serialStats.nodeTests) << "each node pair is tested once, whatever the order";

  // (a) Exactly the leaf-box overlaps in both frames, up to the conservative widening only.
  EXPECT_TRUE(std::includes(parallel.begin(), parallel.end(), ref.carriedExact.begin(), ref.carriedExact.end()))
      << "a pair whose carried leaf boxes overlap was missed";
  EXPECT_TRUE(std::includes(ref.carriedWidened.begin(), ref.carriedWidened.end(), parallel.begin(), parallel.end()))
      << "a pair beyond the documented widening was reported";
  // (b) Never loses a pair whose tight triangle boxes overlap in both frames (as those of intersecting
  // triangles do).
  EXPECT_TRUE(std::includes(parallel.begin(), parallel.end(), ref.tightTriangles.begin(), ref.tightTriangles.end()))
      << "a pair whose moved triangles' boxes overlap was missed";

  // Leaf size is a memory/speed option only: the candidates are the same.
  for (int perLeaf : {2, 4}) {
    const AabbTree leafyA = AabbTree::build(a.xyz, a.indices, perLeaf);
    const AabbTree leafyB = AabbTree::build(b.xyz, b.indices, perLeaf);
    std::vector<TrianglePair> leafy;
    findCandidatePairs(leafyA, leafyB, map, leafy, nullptr, true);
    EXPECT_EQ(leafy, parallel) << perLeaf << " triangles per leaf";
  }
  return parallel.size();
}

/// A random pose of B against A: rotation times non-uniform scale, B's box centre placed within `spread` times
/// A's size of A's box centre, so that the meshes interpenetrate partly.
AffineMap randomPose(const Soup& a, const Soup& b, std::mt19937& rng, bool scale, double spread) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> scaleFactor(0.5, 2.0);
  auto bounds = [](const Soup& s, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    lo = Eigen::Vector3d::Constant(1e300);
    hi = -lo;
    for (std::size_t v = 0; v < s.xyz.size() / 3; ++v) {
      const Eigen::Vector3d p(s.xyz[3 * v], s.xyz[3 * v + 1], s.xyz[3 * v + 2]);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  };
  Eigen::Vector3d loA, hiA, loB, hiB;
  bounds(a, loA, hiA);
  bounds(b, loB, hiB);
  // Scale B so its size is comparable with A's, whatever units the two files use.
  const double unitsB = (hiA - loA).norm() / (hiB - loB).norm();
  Eigen::Matrix3d linear = test::randomRotation(rng) * unitsB;
  if (scale) linear = linear * Eigen::Vector3d(scaleFactor(rng), scaleFactor(rng), scaleFactor(rng)).asDiagonal();
  const Eigen::Vector3d target =
      0.5 * (loA + hiA) + spread * (hiA - loA).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
  AffineMap map;
  map.linear = linear.cast<float>();
  map.translation = (target - linear * (0.5 * (loB + hiB))).cast<float>();
  return map;
}

TEST(TreeTraversal, RandomSoupsMatchBruteForce) {
  std::mt19937 rng(11);
  std::size_t hits = 0;
  for (int round = 0; round < 6; ++round) {
    const Soup a = test::randomSoup(700, 1.0f, 0.15f, 100 + round);
    const Soup b = test::randomSoup(500, 1.0f, 0.2f, 200 + round);
    hits += checkQuery(a, b, randomPose(a, b, rng, round % 2 == 1, 0.3)) > 0 ? 1 : 0;
  }
  EXPECT_GE(hits, 5u) << "the poses must actually overlap for the comparison to mean anything";
}

TEST(TreeTraversal, RealMeshesInRandomPosesMatchBruteForce) {
  GPUCOL_REQUIRE_MESH(armadilloPath, "armadillo-2766.ply");
  GPUCOL_REQUIRE_MESH(bunnyPath, "bunny-948.ply");
  GPUCOL_REQUIRE_MESH(torusPath, "torus-1152.ply");
  const Soup armadillo = test::soupOf(loadMesh(armadilloPath));
  const Soup bunny = test::soupOf(loadMesh(bunnyPath));
  const Soup torus = test::soupOf(loadMesh(torusPath));
  std::mt19937 rng(2011);
  std::size_t hits = 0, poses = 0;
  const std::pair<const Soup*, const Soup*> cases[] = {{&armadillo, &bunny}, {&bunny, &torus}, {&torus, &armadillo}};
  for (const auto& [a, b] : cases) {
    for (int round = 0; round < 4; ++round) {
      SCOPED_TRACE(::testing::Message() << "pose " << round);
      hits += checkQuery(*a, *b, randomPose(*a, *b, rng, round >= 2, 0.25)) > 0 ? 1 : 0;
      ++poses;
    }
  }
  EXPECT_GE(hits, poses - 2) << "most poses must overlap for the comparison to mean anything";
}

TEST(TreeTraversal, SameMeshSamePoseFindsAtLeastEveryTriangleWithItself) {
  GPUCOL_REQUIRE_MESH(path, "bunny-948.ply");
  const TriangleMesh mesh = loadMesh(path);
  const AabbTree tree = AabbTree::build(mesh);
  std::vector<TrianglePair> out;
  findCandidatePairs(tree, tree, AffineMap(), out);
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    ASSERT_TRUE(std::binary_search(out.begin(), out.end(), TrianglePair{t, t})) << "triangle " << t;
  }
}

TEST(TreeTraversal, ThreadCountDoesNotChangeTheOutput) {
  // A mesh against itself turned slightly: tens of thousands of candidates, so the breadth-first front grows past
  // its parallel threshold and the parallel_for path really runs, with 1, 3 and 8 workers.
  GPUCOL_REQUIRE_MESH(path, "bunny-3851.ply");
  const TriangleMesh mesh = loadMesh(path);
  const AabbTree tree = AabbTree::build(mesh);
  AffineMap map;
  map.linear = Eigen::AngleAxisf(0.2f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3f centre = 0.5f * (tree.rootMin() + tree.rootMax());
  map.translation = centre - map.linear * centre;  // turn about the mesh's centre, not the file's origin
  std::vector<TrianglePair> serial;
  TraversalStats serialStats;
  findCandidatePairs(tree, tree, map, serial, &serialStats, false);
  ASSERT_GT(serial.size(), 3 * mesh.triangleCount());
  for (int threads : {1, 3, 8}) {
    tbb::task_arena arena(threads);
    std::vector<TrianglePair> out;
    TraversalStats stats;
    arena.execute([&] { findCandidatePairs(tree, tree, map, out, &stats, true); });
    EXPECT_EQ(out, serial) << threads << " threads";
    EXPECT_EQ(stats.nodeTests, serialStats.nodeTests) << threads << " threads";
  }
}

/// The tree of one triangle given by its 9 coordinates.
AabbTree oneTriangleTree(const std::vector<float>& xyz) {
  return AabbTree::build(xyz, std::vector<std::uint32_t>{0, 1, 2});
}

TEST(TreeTraversal, TouchingBoxesCount) {
  // Two unit right triangles in the z = 0 plane; B moved by exactly 1 along x, so the boxes share the face x = 1.
  const AabbTree tree = oneTriangleTree({0, 0, 0, 1, 0, 0, 0, 1, 0});
  AffineMap map;
  map.translation = Eigen::Vector3f(1, 0, 0);
  std::vector<TrianglePair> out;
  findCandidatePairs(tree, tree, map, out);
  ASSERT_EQ(out.size(), 1u);
  // A triangle collapsed onto B's origin with an identity map: the widening is exactly zero (R_B = 0, t = 0), so
  // this checks the comparison itself: a box that is one point on A's corner touches it.
  const AabbTree pointTree = oneTriangleTree({0, 0, 0, 0, 0, 0, 0, 0, 0});
  ASSERT_EQ(carriedBoxInflation(pointTree, AffineMap()), Eigen::Vector3f::Zero());
  findCandidatePairs(tree, pointTree, AffineMap(), out);
  ASSERT_EQ(out.size(), 1u);
  // Far apart: the root test fails and is the only test.
  map.translation = Eigen::Vector3f(1.01f, 0, 0);
  TraversalStats stats;
  findCandidatePairs(tree, tree, map, out, &stats);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(stats.nodeTests, 1u);
}

TEST(TreeTraversal, TheSecondFrameRemovesPairsThatOneFrameKeeps) {
  // Two thin slivers in the z = 0 plane, parallel and 0.85 apart: A along the diagonal of its unit square, B
  // along its own x axis, turned 45 degrees about z and moved 0.85 along the diagonal's normal (1, -1) /
  // sqrt(2). In A's frame B's box is a square of side 0.71 that reaches into A's box; in B's frame A's box
  // turned by 45 degrees reaches only 0.71 from A's diagonal, short of B. One frame alone would report the
  // pair.
  const AabbTree treeA = oneTriangleTree({0, 0, 0, 1, 1, 0, 1, 1, 0.01f});
  const AabbTree treeB = oneTriangleTree({0, 0, 0, 1, 0, 0, 1, 0, 0.01f});
  AffineMap map;
  map.linear = Eigen::AngleAxisf(float(M_PI / 4), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  map.translation = 0.85f * Eigen::Vector3f(1, -1, 0).normalized();
  // Each frame's test on the two roots (= the two triangles' boxes), as the traversal defines it.
  auto overlapsAfterCarry = [](const AabbNode& still, const AabbNode& moved, const BoxMap& m) {
    const Eigen::Vector3f lo(moved.min[0], moved.min[1], moved.min[2]),
        hi(moved.max[0], moved.max[1], moved.max[2]);
    const Eigen::Vector3f c = m.map.linear * (0.5f * (lo + hi)) + m.map.translation;
    const Eigen::Vector3f e = m.map.linear.cwiseAbs() * (0.5f * (hi - lo)) + m.inflation;
    return (Eigen::Vector3f(still.min[0], still.min[1], still.min[2]).array() <= (c + e).array()).all() &&
           ((c - e).array() <= Eigen::Vector3f(still.max[0], still.max[1], still.max[2]).array()).all();
  };
  ASSERT_TRUE(overlapsAfterCarry(treeA.node(0), treeB.node(0), boxMapIntoA(treeB, map)))
      << "the case needs A's frame to keep the pair";
  ASSERT_FALSE(overlapsAfterCarry(treeB.node(0), treeA.node(0), boxMapIntoB(treeA, map)))
      << "and B's frame to drop it";
  std::vector<TrianglePair> out;
  findCandidatePairs(treeA, treeB, map, out);
  EXPECT_TRUE(out.empty());
  EXPECT_FALSE(rootBoxesOverlap(treeA, treeB, map));
}

TEST(TreeTraversal, AnInverseBeyondFloatLeavesTheTestToAsFrame) {
  // B shrunk by 1e-39 (a subnormal factor): the inverse map would need 1e39, beyond float, so B's frame's
  // test must pass everything rather than compare against infinities and NaNs; B, now a point inside A's box,
  // is found.
  const AabbTree tree = oneTriangleTree({0, 0, 0, 1, 0, 0, 0, 1, 0});
  AffineMap map;
  map.linear = Eigen::Matrix3f::Identity() * 1e-39f;
  map.translation = Eigen::Vector3f(0.25f, 0.25f, 0.0f);
  const BoxMap intoB = boxMapIntoB(tree, map);
  EXPECT_TRUE(std::isinf(intoB.inflation.x()));
  std::vector<TrianglePair> out;
  findCandidatePairs(tree, tree, map, out);
  EXPECT_EQ(out.size(), 1u);
  EXPECT_TRUE(rootBoxesOverlap(tree, tree, map));
}

TEST(TreeTraversal, FarFromTheOriginStillNeverMissesAPair) {
  // B's triangles carried by a large translation into A, which sits far from A's own origin: float rounding of
  // the carried boxes is then large in absolute terms and only the widening keeps the touching pairs.
  std::mt19937 rng(5);
  Soup a = test::randomSoup(400, 1.0f, 0.2f, 31);
  const float offset = 3.0e4f;
  for (std::size_t i = 0; i < a.xyz.size(); i += 3) a.xyz[i] += offset;
  const Soup b = test::randomSoup(400, 1.0f, 0.2f, 32);
  for (int round = 0; round < 4; ++round) {
    AffineMap map;
    map.linear = test::randomRotation(rng).cast<float>();
    map.translation = Eigen::Vector3f(offset, 0, 0);
    EXPECT_GT(checkQuery(a, b, map), 0u);
  }
}

}  // namespace
}  // namespace gpucol
