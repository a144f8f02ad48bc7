#pragma once

#include <BulletCollision/CollisionDispatch/btActivatingCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionCreateFunc.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <memory>
#include <optional>

#include "gpucol/collide_meshes.h"
#include "gpucol/config.h"

namespace gpucol {

class CandidateCache;
class ContactManifoldSet;
class GImpactStandIns;
class TriangleMeshPatch;

/// Bullet's collision algorithm for a MeshShape against another MeshShape or any other concave shape (a
/// plane, a BVH mesh, a heightfield, a GImpact mesh...), either order; under gpucol::CollisionDispatcher also
/// for a btGImpactMeshShape, which a MeshShape stands in for. Contacts go into persistent manifolds that live
/// as long as the pair (refreshed every step, so the solver warm starts), one manifold per direction of
/// contact normal, and name their triangles by part and index.
class MeshMeshAlgorithm : public btActivatingCollisionAlgorithm {
 public:
  /// Made by the create function registered through registerWith(), or by gpucol::CollisionDispatcher with
  /// `standIns`, through which btGImpactMeshShapes are collided as MeshShapes (not owned; null: GImpact
  /// meshes are only ever the other concave shape of a MeshShape's pair). `speculativeContacts` is false for
  /// the closest-points queries (contactTest, contactPairTest): they ask what touches now.
  MeshMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& info, const btCollisionObjectWrapper* body0,
                    const btCollisionObjectWrapper* body1, const Config& config,
                    GImpactStandIns* standIns = nullptr, bool speculativeContacts = true);
  ~MeshMeshAlgorithm() override;

  /// Collides the pair and writes the reduced contacts into the pair's manifolds, with speculative contacts
  /// when two meshes close fast (meshPairQuery). Never throws: a pair that cannot be collided (NaN transform)
  /// is skipped with a warning printed once.
  void processCollision(const btCollisionObjectWrapper* body0, const btCollisionObjectWrapper* body1,
                        const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;
  /// No time of impact for meshes: returns 1, as GImpact does. Pairs that close fast get speculative contacts
  /// from processCollision instead (docs/contacts.md).
  btScalar calculateTimeOfImpact(btCollisionObject* body0, btCollisionObject* body1,
                                 const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;
  /// Appends this pair's manifolds.
  void getAllContactManifolds(btManifoldArray& manifolds) override;

  /// Registers the create function for every shape pair this algorithm handles on `dispatcher`. Pairs it does
  /// not handle (another shape of MeshShape's Bullet type) go to the create function the dispatcher's collision
  /// configuration gives, as before the call.
  static void registerWith(btCollisionDispatcher& dispatcher, const Config& config = Config());

  /// For gpucol::CollisionDispatcher: the result of this pair for this step, computed in a batch with the
  /// other mesh pairs. processCollision uses it when the shapes and transforms are the ones given here.
  void setPrecomputedResult(const MeshPairQuery& query, MeshPairResult result);

  /// For gpucol::CollisionDispatcher: where this pair keeps its candidate triangle pairs from step to step
  /// between two MeshShapes (null for any other pair, a GImpact mesh's stand-in being rebuilt as its mesh
  /// changes, and for a closest-points algorithm, which serves one query).
  CandidateCache* candidateCache(const btCollisionShape* shape0, const btCollisionShape* shape1);

  /// The query this pair would run between two mesh shapes (a GImpact mesh through its stand-in) in a step of
  /// `timeStep` seconds, its speculative reach from the bodies' velocities (none for a closest-points
  /// algorithm); std::nullopt when it is not a mesh-mesh pair.
  std::optional<MeshPairQuery> meshPairQuery(const btCollisionObjectWrapper* body0,
                                             const btCollisionObjectWrapper* body1, btScalar timeStep) const;

 private:
  struct Precomputed;
  /// `shape` as a MeshShape: itself, a GImpact mesh's stand-in, or null.
  const MeshShape* asMesh(const btCollisionShape* shape) const;

  Config m_config;
  GImpactStandIns* m_standIns;
  bool m_speculativeContacts;
  std::unique_ptr<ContactManifoldSet> m_manifolds;
  std::unique_ptr<Precomputed> m_precomputed;
  std::unique_ptr<TriangleMeshPatch> m_patch;  // triangles of a btBvhTriangleMeshShape near the mesh, kept
  std::unique_ptr<CandidateCache> m_candidates;  // a resting mesh pair's candidates, kept
};

}  // namespace gpucol
