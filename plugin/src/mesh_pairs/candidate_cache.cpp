#include "mesh_pairs/candidate_cache.h"

#include <algorithm>
#include <cmath>

#include "gpucol/mesh_shape.h"

namespace gpucol {
namespace {

// The largest coordinate magnitude of a tree's root box: every node's |centre| + extent on each axis is at
// most this.
double rootRadius(const AabbTree& tree) {
  return double(tree.rootMin().cwiseAbs().cwiseMax(tree.rootMax().cwiseAbs()).maxCoeff());
}

// The largest side of a shape's tree box in the world (its local scaling applied).
double worldSize(const MeshShape& shape) {
  const AabbTree& tree = shape.tree();
  const btVector3& s = shape.getLocalScaling();
  const Eigen::Vector3f side = tree.rootMax() - tree.rootMin();
  return std::max({double(side.x()) * std::fabs(s.x()), double(side.y()) * std::fabs(s.y()),
                   double(side.z()) * std::fabs(s.z())});
}

// True when, on every axis, what the other tree's boxes can have moved from `kept` to `now` (|dM| R + |dt|),
// twice the rounding widening of the carry at `now` and the reach at `now` stay within `limit`.
bool withinLimit(const BoxMap& now, const AffineMap& kept, double otherRadius,
                 const Eigen::Vector3f& reachNow, const Eigen::Vector3d& limit) {
  if (!now.inflation.allFinite()) return false;
  for (int i = 0; i < 3; ++i) {
    double moved = std::fabs(double(now.map.translation[i]) - double(kept.translation[i]));
    for (int j = 0; j < 3; ++j) {
      moved += std::fabs(double(now.map.linear(i, j)) - double(kept.linear(i, j))) * otherRadius;
    }
    if (!(moved + 2.0 * double(now.inflation[i]) + double(reachNow[i]) <= limit[i])) return false;
  }
  return true;
}

}  // namespace

bool CandidateCache::covers(const MeshShape& a, const MeshShape& b, const PairFrame& frame) const {
  const AabbTree& treeA = a.tree();
  const AabbTree& treeB = b.tree();
  if (&treeA != m_treeA || &treeB != m_treeB || treeA.nodeCount() != m_nodesA ||
      treeB.nodeCount() != m_nodesB) {
    return false;
  }
  return withinLimit(boxMapIntoA(treeB, frame.treeMap), m_intoA, rootRadius(treeB), frame.candidateReach.inA,
                     m_limitA) &&
         withinLimit(boxMapIntoB(treeA, frame.treeMap), m_intoB, rootRadius(treeA), frame.candidateReach.inB,
                     m_limitB);
}

const std::vector<TrianglePair>& CandidateCache::candidates(const MeshShape& a, const MeshShape& b,
                                                            const PairFrame& frame,
                                                            std::uint64_t& nodeTests) {
  if (covers(a, b, frame)) return m_candidates;
  m_treeA = nullptr;  // nothing kept until the new candidates are in
  const double slack = kSlackShare * std::min(worldSize(a), worldSize(b));
  const btVector3& scaleB = b.getLocalScaling();
  CandidateReach widened = frame.candidateReach;
  for (int i = 0; i < 3; ++i) {
    const double alongA = slack / std::fabs(double(frame.scaleA[i]));
    const double alongB = slack / std::fabs(double(scaleB[i]));
    widened.inA[i] += float(alongA);
    widened.inB[i] += float(alongB);
    // Half the slack is the room left for the pose to move: the rest covers the roundings of the two
    // traversals' box tests many times over.
    m_limitA[i] = double(frame.candidateReach.inA[i]) + 0.5 * alongA;
    m_limitB[i] = double(frame.candidateReach.inB[i]) + 0.5 * alongB;
  }
  TraversalStats stats;
  findCandidatePairs(a.tree(), b.tree(), frame.treeMap, m_candidates, &stats, true, widened);
  nodeTests += stats.nodeTests;
  const BoxMap intoB = boxMapIntoB(a.tree(), frame.treeMap);
  if (widened.inA.allFinite() && widened.inB.allFinite() && intoB.inflation.allFinite()) {
    m_treeA = &a.tree();
    m_treeB = &b.tree();
    m_nodesA = a.tree().nodeCount();
    m_nodesB = b.tree().nodeCount();
    m_intoA = frame.treeMap;
    m_intoB = intoB.map;
  }
  return m_candidates;
}

}  // namespace gpucol
