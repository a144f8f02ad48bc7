#pragma once
// A resting mesh pair's candidate triangle pairs, kept from step to step while neither body moves far
// relative to the other.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "bvh/aabb_tree.h"
#include "bvh/tree_traversal.h"
#include "mesh_pairs/pair_frame.h"

namespace gpucol {

class MeshShape;

/// The candidates of one pair (MeshMeshAlgorithm keeps one per pair), found by a traversal whose box tests
/// are widened by a slack, and reused while the pair's relative pose has moved every box by less than half
/// that slack since. The kept candidates are then a superset of what a traversal at the present pose would
/// give, and the near phase's exact tests reject the extra ones (their boxes miss, or they lie beyond the
/// reach), so the contacts are the same as without the cache. A pair at rest jitters far less than the slack,
/// so its trees are traversed again only when it moves; the idea is the fattened boxes of Bullet's dynamic
/// tree, applied to the pair's relative pose.
class CandidateCache {
 public:
  /// The candidates of the pair at `frame`: the kept ones when they cover it (covers()), else those of a new
  /// traversal with widened boxes, kept for the next steps. `nodeTests` gets the traversal's node tests (none
  /// when the kept candidates serve).
  const std::vector<TrianglePair>& candidates(const MeshShape& a, const MeshShape& b, const PairFrame& frame,
                                              std::uint64_t& nodeTests);

  /// True when the kept candidates include every candidate of the pair at `frame`.
  bool covers(const MeshShape& a, const MeshShape& b, const PairFrame& frame) const;

  /// Share of the smaller mesh's size the kept traversal widens its boxes by (in the world).
  static constexpr double kSlackShare = 0.02;

 private:
  // What the kept candidates were found for: the trees (null: nothing kept; their sizes, against a shape
  // replaced at the same address), the maps of the other tree's boxes into A's and B's frames, and per axis
  // of each frame the most that the boxes' movement, rounding and reach may take (withinLimit).
  const AabbTree* m_treeA = nullptr;
  const AabbTree* m_treeB = nullptr;
  std::size_t m_nodesA = 0, m_nodesB = 0;
  AffineMap m_intoA, m_intoB;
  Eigen::Vector3d m_limitA = Eigen::Vector3d::Zero(), m_limitB = Eigen::Vector3d::Zero();
  std::vector<TrianglePair> m_candidates;
};

}  // namespace gpucol
