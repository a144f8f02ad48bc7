#pragma once

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstdint>

#include "gpucol/config.h"

namespace gpucol {

/// What the dispatcher did with the mesh pairs of the last step.
struct DispatchStats {
  std::uint64_t meshPairs = 0;          ///< Mesh-mesh pairs collided in the step's batch.
  std::uint64_t rootBoxesMissed = 0;    ///< Of those, pairs whose root boxes missed (nothing else ran).
  std::uint64_t openClPairs = 0;        ///< Of those, pairs that ran on OpenCL (the rest ran on the CPU).
  std::uint64_t reducedContacts = 0;    ///< Contacts written towards the manifolds.
  double batchMilliseconds = 0;         ///< Time of collideMeshesBatch for the step.
};

/// A btCollisionDispatcher with MeshMeshAlgorithm registered that gathers every mesh-mesh pair of a step into one
/// collideMeshesBatch call before Bullet dispatches the pairs; everything else is Bullet's own dispatching.
class CollisionDispatcher : public btCollisionDispatcher {
 public:
  /// `collisionConfiguration` must outlive the dispatcher, as for btCollisionDispatcher.
  explicit CollisionDispatcher(btCollisionConfiguration* collisionConfiguration, const Config& config = Config());
  ~CollisionDispatcher() override;

  /// Batches the mesh pairs, then dispatches every pair as btCollisionDispatcher does.
  void dispatchAllCollisionPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                                 btDispatcher* dispatcher) override;

  /// The configuration given at construction.
  const Config& config() const { return m_config; }
  /// What the last step's batch did.
  const DispatchStats& lastStepStats() const { return m_lastStepStats; }

 private:
  Config m_config;
  DispatchStats m_lastStepStats;
};

}  // namespace gpucol
