#pragma once

#include <LinearMath/btTransform.h>
#include <LinearMath/btVector3.h>

#include <cstdint>
#include <vector>

#include "gpucol/config.h"

namespace gpucol {

class MeshShape;

/// A triangle of mesh A and a triangle of mesh B (indices into each mesh's triangle list).
struct TrianglePair {
  std::uint32_t triangleA = 0;  ///< Triangle index in mesh A.
  std::uint32_t triangleB = 0;  ///< Triangle index in mesh B.
  /// Pairs compare by (triangleA, triangleB): the order in which results are reported.
  friend bool operator==(const TrianglePair& l, const TrianglePair& r) {
    return l.triangleA == r.triangleA && l.triangleB == r.triangleB;
  }
  friend bool operator<(const TrianglePair& l, const TrianglePair& r) {
    return l.triangleA != r.triangleA ? l.triangleA < r.triangleA : l.triangleB < r.triangleB;
  }
};

/// One contact between two meshes, in Bullet's conventions.
struct MeshContact {
  std::uint32_t triangleA = 0;  ///< Triangle of mesh A that generated the contact.
  std::uint32_t triangleB = 0;  ///< Triangle of mesh B that generated the contact.
  /// In world space: a point shared by both triangles (the middle of their common segment) for a pair's
  /// deepest contact; for a contact at another corner of their overlap (a pair gives one per corner that dips
  /// in, after its deepest), that corner moved halfway out.
  btVector3 pointWorld;
  /// Bullet's point on B. The triangle pushed out of the other's face contributes a corner of the part of it
  /// that lies over the other triangle: when it is B's, that corner is this point; when it is A's, this point
  /// is that corner moved out along the normal by the depth (onto B's face plane). Bullet's point on A is
  /// pointOnBWorld + normalWorldOnB * depth.
  btVector3 pointOnBWorld;
  btVector3 normalWorldOnB;     ///< Unit normal on B pointing towards A, in world space.
  btScalar depth = 0;           ///< Signed distance along the normal: negative when penetrating.
};

/// Counters and timings of one mesh pair query.
struct MeshPairStats {
  std::uint64_t nodeTests = 0;      ///< Box-box tests of the middle phase.
  std::uint64_t triangleTests = 0;  ///< Exact triangle-triangle tests of the near phase.
  double middlePhaseMs = 0;         ///< Time of the tree-vs-tree traversal.
  double nearPhaseMs = 0;           ///< Time of the exact tests and contact generation.
  double reductionMs = 0;           ///< Time of the contact reduction.
  Backend backendUsed = Backend::Cpu;  ///< Where the pair ran.
  bool rootBoxesMissed = false;     ///< True when the root boxes missed and nothing else ran.
};

/// Everything one mesh pair query finds, each list sorted for determinism.
struct MeshPairResult {
  std::vector<TrianglePair> candidatePairs;     ///< Middle phase output: triangle boxes overlap.
  std::vector<TrianglePair> intersectingPairs;  ///< Candidates whose triangles really intersect.
  /// One contact per kept intersecting pair (thesis §5.3.4). Pairs of triangles facing the same way give
  /// contacts only when no pair facing each other does: flush faces side by side push sideways for nothing.
  std::vector<MeshContact> contacts;
  std::vector<MeshContact> reducedContacts;     ///< What the 6-D binning kept (thesis §5.3.5).
  MeshPairStats stats;                          ///< Counters and timings.
};

/// One pair of a batch query.
struct MeshPairQuery {
  const MeshShape* shapeA = nullptr;  ///< First shape (its triangles are "A" in the result).
  btTransform transformA = btTransform::getIdentity();  ///< World transform of shape A.
  const MeshShape* shapeB = nullptr;  ///< Second shape.
  btTransform transformB = btTransform::getIdentity();  ///< World transform of shape B.
  /// Speculative contacts: triangles up to `|speculativeMotion| + speculativeDistance` farther apart than the
  /// shapes' margins also give contacts, at their positive distance, which Bullet's solver lets the bodies
  /// close in one step and no more. `speculativeMotion` is how far B moves relative to A in the step (world
  /// frame): the search for such triangles widens along it only (in both directions). `speculativeDistance`
  /// widens it every way: how far any point moves by the bodies' turns. MeshMeshAlgorithm sets both from the
  /// bodies' velocities for pairs that close fast; 0: none.
  btVector3 speculativeMotion = btVector3(0, 0, 0);
  btScalar speculativeDistance = 0;
};

/// Collides two mesh shapes at the given world transforms, without a world.
MeshPairResult collideMeshes(const MeshShape& shapeA, const btTransform& transformA, const MeshShape& shapeB,
                             const btTransform& transformB, const Config& config = Config());

/// Collides one query's pair, without a world.
MeshPairResult collideMeshes(const MeshPairQuery& query, const Config& config = Config());

/// Collides every pair of the batch, in parallel; results come back in the order of the queries.
std::vector<MeshPairResult> collideMeshesBatch(const std::vector<MeshPairQuery>& queries,
                                               const Config& config = Config());

}  // namespace gpucol
