#pragma once

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstdint>
#include <memory>

#include "gpucol/config.h"

namespace gpucol {

/// What the dispatcher did with the mesh pairs of the last step.
struct DispatchStats {
  std::uint64_t meshPairs = 0;          ///< Mesh-mesh pairs collided in the step's batch.
  std::uint64_t gimpactPairs = 0;       ///< Of those, pairs with a btGImpactMeshShape (through its stand-in).
  std::uint64_t gimpactStandInsBuilt =
      0;                                ///< GImpact meshes whose stand-in was built (first, or on a change).
  std::uint64_t rootBoxesMissed = 0;    ///< Of those, pairs whose root boxes missed (nothing else ran).
  std::uint64_t openClPairs = 0;        ///< Of those, pairs that ran on OpenCL (the rest ran on the CPU).
  std::uint64_t reducedContacts = 0;    ///< Contacts written towards the manifolds.
  double batchMilliseconds = 0;         ///< Time of collideMeshesBatch for the step.
};

class GImpactStandIns;

/// A btCollisionDispatcher with MeshMeshAlgorithm registered that gathers every mesh-mesh pair of a step into
/// one collideMeshesBatch call before Bullet dispatches the pairs; everything else is Bullet's own
/// dispatching.
///
/// It takes btGImpactMeshShape pairs too (Config::collideGImpactShapes): two GImpact meshes, a GImpact mesh
/// and a MeshShape, a GImpact mesh and a plane or other concave shape. A MeshShape with the GImpact mesh's
/// triangles, scaling and margin stands in for it, built once per shape and again when its vertices change,
/// and its pairs join the batch. A GImpact mesh against a compound goes to the configuration's compound
/// algorithm, whose child pairs come back here. It does so whether or not
/// btGImpactCollisionAlgorithm::registerAlgorithm was called on it, before or after; a GImpact mesh against a
/// convex shape stays with the algorithm registered for it.
class CollisionDispatcher : public btCollisionDispatcher {
 public:
  /// `collisionConfiguration` must outlive the dispatcher, as for btCollisionDispatcher.
  explicit CollisionDispatcher(btCollisionConfiguration* collisionConfiguration, const Config& config = Config());
  ~CollisionDispatcher() override;

  /// Batches the mesh pairs, then dispatches every pair as btCollisionDispatcher does.
  void dispatchAllCollisionPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                                 btDispatcher* dispatcher) override;

  /// MeshMeshAlgorithm (or the compound algorithm) for the GImpact pairs it takes (above), whatever create
  /// function is registered for them; btCollisionDispatcher's answer for every other pair.
  btCollisionAlgorithm* findAlgorithm(const btCollisionObjectWrapper* body0,
                                      const btCollisionObjectWrapper* body1,
                                      btPersistentManifold* sharedManifold,
                                      ebtDispatcherQueryType queryType) override;

  /// The configuration given at construction.
  const Config& config() const { return m_config; }
  /// What the last step's batch did.
  const DispatchStats& lastStepStats() const { return m_lastStepStats; }

 private:
  Config m_config;
  DispatchStats m_lastStepStats;
  std::unique_ptr<GImpactStandIns> m_standIns;
};

}  // namespace gpucol
