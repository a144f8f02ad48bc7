// The mesh pair query on the CPU: middle phase (tree vs tree), near phase (Möller's test and contact
// generation, thesis §5.3.4) and contact reduction (6-D binning, §5.3.5), for one pair or a batch.
#include "gpucol/collide_meshes.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "bvh/aabb_tree.h"
#include "bvh/tree_traversal.h"
#include "gpucol/mesh_shape.h"
#include "narrowphase/contact_reduction.h"
#include "narrowphase/triangle_contact.h"
#include "narrowphase/triangle_intersection.h"

namespace gpucol {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool isFinite(const btTransform& t) {
  for (int r = 0; r < 3; ++r) {
    if (!std::isfinite(t.getOrigin()[r])) return false;
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(t.getBasis()[r][c])) return false;
    }
  }
  return true;
}

// The frame a pair is tested in: A's body frame with A's local scaling applied ("A's scaled frame"). It is
// local to the pair, so scenes far from the origin keep their precision, and A's triangles need only a
// per-axis scale. B's triangles are carried in by one affine map computed once per pair (in double, so the
// relative transform adds no rounding of its own to Bullet's float transforms).
struct PairFrame {
  Eigen::Vector3f scaleA;       // A's local scaling.
  bool flipA = false;           // A's scaling mirrors the mesh: swap two vertices to keep the winding outward.
  bool flipB = false;           // The same for B.
  Eigen::Matrix3f bLinear;      // B's mesh coordinates into A's scaled frame: R_rel * S_B ...
  Eigen::Vector3f bTranslation;  // ... + t_rel.
  AffineMap treeMap;            // B's mesh coordinates into A's unscaled mesh frame, for the traversal.
  btTransform worldFromA;       // A's rigid transform: from A's scaled frame to the world.
};

PairFrame makePairFrame(const MeshShape& a, const btTransform& transformA, const MeshShape& b,
                        const btTransform& transformB) {
  Eigen::Matrix3d rotationA, rotationB;
  Eigen::Vector3d originA, originB, scaleA, scaleB;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      rotationA(r, c) = transformA.getBasis()[r][c];
      rotationB(r, c) = transformB.getBasis()[r][c];
    }
    originA[r] = transformA.getOrigin()[r];
    originB[r] = transformB.getOrigin()[r];
    scaleA[r] = a.getLocalScaling()[r];
    scaleB[r] = b.getLocalScaling()[r];
  }
  const Eigen::Matrix3d relativeRotation = rotationA.transpose() * rotationB;
  const Eigen::Vector3d relativeTranslation = rotationA.transpose() * (originB - originA);
  const Eigen::Matrix3d bLinear = relativeRotation * scaleB.asDiagonal();

  PairFrame frame;
  frame.scaleA = scaleA.cast<float>();
  frame.flipA = scaleA.prod() < 0;
  frame.flipB = scaleB.prod() < 0;
  frame.bLinear = bLinear.cast<float>();
  frame.bTranslation = relativeTranslation.cast<float>();
  const Eigen::Vector3d inverseScaleA = scaleA.cwiseInverse();
  frame.treeMap.linear = (inverseScaleA.asDiagonal() * bLinear).cast<float>();
  frame.treeMap.translation = inverseScaleA.cwiseProduct(relativeTranslation).cast<float>();
  frame.worldFromA = transformA;
  return frame;
}

// Root boxes first: a pair whose meshes' boxes miss costs one box test (DESIGN.md, "skip what a scene
// does not need"). The carried box gets the same conservative widening as every box of the traversal.
bool rootBoxesOverlap(const AabbTree& a, const AabbTree& b, const AffineMap& bToA) {
  const Eigen::Vector3f centre = 0.5f * (b.rootMin() + b.rootMax());
  const Eigen::Vector3f extent = 0.5f * (b.rootMax() - b.rootMin());
  const Eigen::Vector3f carriedCentre = bToA.linear * centre + bToA.translation;
  const Eigen::Vector3f carriedExtent = bToA.linear.cwiseAbs() * extent + carriedBoxInflation(b, bToA);
  return ((carriedCentre - carriedExtent).array() <= a.rootMax().array()).all() &&
         ((carriedCentre + carriedExtent).array() >= a.rootMin().array()).all();
}

Eigen::Vector3f meshVertex(const TriangleMesh& mesh, std::uint32_t vertex) {
  const float* p = mesh.positions().data() + 3 * std::size_t(vertex);
  return Eigen::Vector3f(p[0], p[1], p[2]);
}

// Triangle `t` of A in A's scaled frame.
void triangleOfA(const TriangleMesh& mesh, std::uint32_t t, const PairFrame& frame, Eigen::Vector3f (&out)[3]) {
  const std::uint32_t* corner = mesh.indices().data() + 3 * std::size_t(t);
  for (int i = 0; i < 3; ++i) out[i] = frame.scaleA.cwiseProduct(meshVertex(mesh, corner[i]));
  if (frame.flipA) std::swap(out[1], out[2]);
}

// Triangle `t` of B carried into A's scaled frame.
void triangleOfB(const TriangleMesh& mesh, std::uint32_t t, const PairFrame& frame, Eigen::Vector3f (&out)[3]) {
  const std::uint32_t* corner = mesh.indices().data() + 3 * std::size_t(t);
  for (int i = 0; i < 3; ++i) out[i] = frame.bLinear * meshVertex(mesh, corner[i]) + frame.bTranslation;
  if (frame.flipB) std::swap(out[1], out[2]);
}

// What the near phase found for one candidate pair.
struct CandidateOutcome {
  bool intersects = false;
  std::optional<TriangleContact> contact;
};

// Exact test and contact generation for every candidate (thesis §5.3.4: the cheap test first, contacts only
// for intersecting pairs), in parallel; outcomes stay in candidate order, so the output is deterministic.
std::vector<CandidateOutcome> runNearPhase(const TriangleMesh& meshA, const TriangleMesh& meshB,
                                           const PairFrame& frame, const std::vector<TrianglePair>& candidates) {
  std::vector<CandidateOutcome> outcomes(candidates.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      Eigen::Vector3f a[3], b[3];
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        triangleOfA(meshA, candidates[i].triangleA, frame, a);
                        triangleOfB(meshB, candidates[i].triangleB, frame, b);
                        if (!trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2])) continue;
                        outcomes[i].intersects = true;
                        outcomes[i].contact = generateContact(a, b);
                      }
                    });
  return outcomes;
}

MeshContact toWorld(const TrianglePair& pair, const TriangleContact& contact, const btTransform& worldFromA) {
  MeshContact out;
  out.triangleA = pair.triangleA;
  out.triangleB = pair.triangleB;
  out.pointWorld = worldFromA * btVector3(contact.point.x(), contact.point.y(), contact.point.z());
  out.normalWorldOnB =
      worldFromA.getBasis() * btVector3(contact.normalOnB.x(), contact.normalOnB.y(), contact.normalOnB.z());
  out.depth = contact.depth;
  return out;
}

MeshPairResult collidePair(const MeshShape& shapeA, const btTransform& transformA, const MeshShape& shapeB,
                           const btTransform& transformB, const Config& config) {
  if (!isFinite(transformA) || !isFinite(transformB)) {
    throw std::invalid_argument("collideMeshes: the transform of shape " +
                                std::string(isFinite(transformA) ? "B" : "A") + " has a NaN or infinite component");
  }
  MeshPairResult result;
  result.stats.backendUsed = Backend::Cpu;
  const PairFrame frame = makePairFrame(shapeA, transformA, shapeB, transformB);

  auto start = Clock::now();
  result.stats.nodeTests = 1;
  if (!rootBoxesOverlap(shapeA.tree(), shapeB.tree(), frame.treeMap)) {
    result.stats.rootBoxesMissed = true;
    result.stats.middlePhaseMs = millisecondsSince(start);
    return result;
  }
  TraversalStats traversal;
  findCandidatePairs(shapeA.tree(), shapeB.tree(), frame.treeMap, result.candidatePairs, &traversal);
  result.stats.nodeTests = traversal.nodeTests;
  result.stats.middlePhaseMs = millisecondsSince(start);

  start = Clock::now();
  const std::vector<CandidateOutcome> outcomes =
      runNearPhase(shapeA.mesh(), shapeB.mesh(), frame, result.candidatePairs);
  result.stats.triangleTests = result.candidatePairs.size();
  std::vector<ReductionInput> localContacts;
  for (std::size_t i = 0; i < outcomes.size(); ++i) {
    if (!outcomes[i].intersects) continue;
    result.intersectingPairs.push_back(result.candidatePairs[i]);
    if (!outcomes[i].contact) continue;
    const TriangleContact& contact = *outcomes[i].contact;
    result.contacts.push_back(toWorld(result.candidatePairs[i], contact, frame.worldFromA));
    localContacts.push_back({contact.point, contact.normalOnB, contact.depth});
  }
  result.stats.nearPhaseMs = millisecondsSince(start);

  start = Clock::now();
  // Binning runs in A's scaled frame: positions are scaled to the contacts' own box, so the frame only has
  // to be the same for all contacts of the pair.
  for (std::uint32_t kept : reduceContacts(localContacts, config.reductionResolution)) {
    result.reducedContacts.push_back(result.contacts[kept]);
  }
  result.stats.reductionMs = millisecondsSince(start);
  return result;
}

}  // namespace

MeshPairResult collideMeshes(const MeshShape& shapeA, const btTransform& transformA, const MeshShape& shapeB,
                             const btTransform& transformB, const Config& config) {
  return collidePair(shapeA, transformA, shapeB, transformB, config);
}

std::vector<MeshPairResult> collideMeshesBatch(const std::vector<MeshPairQuery>& queries, const Config& config) {
  for (std::size_t i = 0; i < queries.size(); ++i) {
    if (queries[i].shapeA == nullptr || queries[i].shapeB == nullptr) {
      throw std::invalid_argument("collideMeshesBatch: query " + std::to_string(i) + " has a null shape");
    }
  }
  std::vector<MeshPairResult> results(queries.size());
  // Pairs run in parallel; each pair's own stages are parallel too, and oneTBB balances the nesting.
  tbb::parallel_for(std::size_t(0), queries.size(), [&](std::size_t i) {
    const MeshPairQuery& q = queries[i];
    results[i] = collidePair(*q.shapeA, q.transformA, *q.shapeB, q.transformB, config);
  });
  return results;
}

}  // namespace gpucol
