#include "gpucol/collision_dispatcher.h"

#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>

#include <chrono>
#include <exception>
#include <vector>

#include "bullet/warn_once.h"
#include "gpucol/collide_meshes.h"
#include "gpucol/mesh_mesh_algorithm.h"
#include "gpucol/mesh_shape.h"

namespace gpucol {
namespace {

// Finds the step's mesh-mesh pairs as Bullet's default near callback would see them: the same filter
// (needsCollision: masks, both asleep) and the same algorithm, created here if the pair is new.
class MeshPairCollector : public btOverlapCallback {
 public:
  explicit MeshPairCollector(btCollisionDispatcher& dispatcher) : m_dispatcher(dispatcher) {}

  bool processOverlap(btBroadphasePair& pair) override {
    auto* object0 = static_cast<btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    auto* object1 = static_cast<btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    if (!MeshShape::isMeshShape(object0->getCollisionShape()) ||
        !MeshShape::isMeshShape(object1->getCollisionShape()) || !m_dispatcher.needsCollision(object0, object1)) {
      return false;
    }
    const btCollisionObjectWrapper wrapper0(nullptr, object0->getCollisionShape(), object0,
                                            object0->getWorldTransform(), -1, -1);
    const btCollisionObjectWrapper wrapper1(nullptr, object1->getCollisionShape(), object1,
                                            object1->getWorldTransform(), -1, -1);
    if (pair.m_algorithm == nullptr) {
      pair.m_algorithm = m_dispatcher.findAlgorithm(&wrapper0, &wrapper1, nullptr, BT_CONTACT_POINT_ALGORITHMS);
    }
    auto* algorithm = dynamic_cast<MeshMeshAlgorithm*>(pair.m_algorithm);
    if (algorithm == nullptr) return false;  // a user replaced the create function for meshes
    if (std::optional<MeshPairQuery> query = algorithm->meshPairQuery(&wrapper0, &wrapper1)) {
      algorithms.push_back(algorithm);
      queries.push_back(*query);
    }
    return false;  // keep the pair
  }

  std::vector<MeshMeshAlgorithm*> algorithms;
  std::vector<MeshPairQuery> queries;

 private:
  btCollisionDispatcher& m_dispatcher;
};

}  // namespace

CollisionDispatcher::CollisionDispatcher(btCollisionConfiguration* collisionConfiguration, const Config& config)
    : btCollisionDispatcher(collisionConfiguration), m_config(config) {
  MeshMeshAlgorithm::registerWith(*this, m_config);
}

CollisionDispatcher::~CollisionDispatcher() = default;

void CollisionDispatcher::dispatchAllCollisionPairs(btOverlappingPairCache* pairCache,
                                                    const btDispatcherInfo& dispatchInfo, btDispatcher* dispatcher) {
  m_lastStepStats = DispatchStats();
  if (dispatchInfo.m_dispatchFunc == btDispatcherInfo::DISPATCH_DISCRETE) {
    MeshPairCollector collector(*this);
    pairCache->processAllOverlappingPairs(&collector, this, dispatchInfo);
    if (!collector.queries.empty()) {
      const auto start = std::chrono::steady_clock::now();
      try {
        std::vector<MeshPairResult> results = collideMeshesBatch(collector.queries, m_config);
        for (std::size_t i = 0; i < results.size(); ++i) {
          m_lastStepStats.rootBoxesMissed += results[i].stats.rootBoxesMissed;
          m_lastStepStats.openClPairs += results[i].stats.backendUsed == Backend::OpenCL;
          m_lastStepStats.reducedContacts += results[i].reducedContacts.size();
          collector.algorithms[i]->setPrecomputedResult(collector.queries[i], std::move(results[i]));
        }
      } catch (const std::exception& e) {
        // One bad pair (a NaN transform) spoils the batch: every pair then runs alone in processCollision,
        // which skips the bad one with its own warning.
        warnOnce("batch", std::string("a mesh pair batch failed, colliding its pairs one by one: ") + e.what());
      }
      m_lastStepStats.meshPairs = collector.queries.size();
      m_lastStepStats.batchMilliseconds =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
  }
  btCollisionDispatcher::dispatchAllCollisionPairs(pairCache, dispatchInfo, dispatcher);
}

}  // namespace gpucol
