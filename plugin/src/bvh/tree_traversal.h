#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "bvh/aabb_tree.h"
#include "gpucol/collide_meshes.h"

namespace gpucol {

/// Maps mesh-B coordinates into mesh-A coordinates: p_A = linear * p_B + translation. linear is a general 3x3
/// (rotation times non-uniform scale factors), so boxes are carried with the |M| trick: centre' = M c + t, extents' = |M| e.
struct AffineMap {
  Eigen::Matrix3f linear = Eigen::Matrix3f::Identity();        ///< Rotation times scale, B to A.
  Eigen::Vector3f translation = Eigen::Vector3f::Zero();       ///< Origin of B in A's frame.
};

/// Counters of one traversal.
struct TraversalStats {
  std::uint64_t nodeTests = 0;  ///< Box-box overlap tests, root test and triangle-box tests of multi-triangle leaves included.
};

/// Relative widening of a carried box, times the magnitude bound of the carried coordinates (see carriedBoxInflation).
/// Carrying a box in float rounds about 8 times (centre and extent of the stored box, three products and sums per
/// row, the final centre +- extent), each by at most 2^-24 of the largest magnitude involved; 16 * 2^-24 covers
/// that twice, so a carried float box always contains the exactly carried triangle.
constexpr float kCarryRelativeEpsilon = 16.0f / 16777216.0f;

/// Absolute widening of B's carried boxes along each of A's axes for one call: kCarryRelativeEpsilon times a bound
/// on every carried coordinate, sum_j |M_ij| * R_B + |t_i|, where R_B is the largest coordinate magnitude of B's
/// root box. Exposed so tests can check the traversal against the same definition in double.
Eigen::Vector3f carriedBoxInflation(const AabbTree& b, const AffineMap& bToA);

/// One frame's side of the box test: the map that carries the other tree's boxes into this frame, with the
/// widening that makes each carried float box contain the exactly carried one.
struct BoxMap {
  AffineMap map;
  Eigen::Vector3f inflation = Eigen::Vector3f::Zero();
};

/// How far apart two triangles may be and still be candidates, along each axis of A's and of B's mesh frame: the
/// sum of the shapes' margins over each frame's local scaling (zero: only boxes that overlap).
struct CandidateReach {
  Eigen::Vector3f inA = Eigen::Vector3f::Zero();  ///< Along A's mesh axes.
  Eigen::Vector3f inB = Eigen::Vector3f::Zero();  ///< Along B's mesh axes.
};

/// The test in A's frame: B's boxes carried in by bToA, widened by carriedBoxInflation(b, bToA) and `reachInA`.
BoxMap boxMapIntoA(const AabbTree& b, const AffineMap& bToA,
                   const Eigen::Vector3f& reachInA = Eigen::Vector3f::Zero());

/// The test in B's frame: A's boxes carried in by the inverse of bToA (inverted in double, then rounded to
/// float, so each entry is within an ulp or two of the exact inverse's, which the widening covers as it
/// covers the carry's own rounding), widened by carriedBoxInflation(a, inverse). Where the inverse does not
/// fit in float (a local scaling near float's limits), a zero map with infinite widening: every carried box
/// is all of space and the test in A's frame alone decides. `reachInB` widens it further.
BoxMap boxMapIntoB(const AabbTree& a, const AffineMap& bToA,
                   const Eigen::Vector3f& reachInB = Eigen::Vector3f::Zero());

/// True when the root boxes of a and b overlap in both frames, widened by `reach` (the traversal's first test;
/// a pair whose roots miss has no candidates).
bool rootBoxesOverlap(const AabbTree& a, const AabbTree& b, const AffineMap& bToA,
                      const CandidateReach& reach = CandidateReach());

/// All (triangle of A, triangle of B) whose leaf boxes overlap in both meshes' frames: in A's (B's box
/// carried in) and in B's (A's box carried in by the inverse map); touching counts. Triangles that intersect
/// pass both tests, since each carried box contains its triangle. The box of a box turned by the pose is
/// loose in the other frame (the thesis pose's 0.5 rad about y widens it by cos + sin = 1.36 on x and z), and
/// the second frame's test removes 17-18% of the node tests and 19-21% of the candidates that A's frame alone
/// keeps on the thesis scene (16.5% of the tests on armadillo-2766). Sorted by (triangleA, triangleB), no
/// duplicates. Parallel with oneTBB over the traversal front when `parallel`. `stats`, when given, has its
/// counters increased (so one struct can sum several calls). Follows thesis Alg. 5.1 (simultaneous descent:
/// node-node gives 4 tests, leaf-node 2) with an explicit stack. With a `reach`, every box test is widened by
/// it, so triangles closer than the shapes' margins are candidates too.
void findCandidatePairs(const AabbTree& a, const AabbTree& b, const AffineMap& bToA,
                        std::vector<TrianglePair>& out, TraversalStats* stats = nullptr, bool parallel = true,
                        const CandidateReach& reach = CandidateReach());

}  // namespace gpucol
