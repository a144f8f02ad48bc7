#include "gpucol/collision_dispatcher.h"

#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <BulletCollision/CollisionDispatch/btCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <chrono>
#include <exception>
#include <vector>

#include "bullet/gimpact_stand_ins.h"
#include "bullet/warn_once.h"
#include "gpucol/collide_meshes.h"
#include "gpucol/mesh_mesh_algorithm.h"
#include "gpucol/mesh_shape.h"
#include "mesh_pairs/mesh_batch.h"

namespace gpucol {
namespace {

// Finds the step's mesh-mesh pairs (a GImpact mesh counting as a mesh when gpucol collides it) as Bullet's
// default near callback would see them: the same filter (needsCollision: masks, both asleep) and the same
// algorithm, created here if the pair is new.
class MeshPairCollector : public btOverlapCallback {
 public:
  MeshPairCollector(btCollisionDispatcher& dispatcher, bool gimpactMeshes, btScalar timeStep)
      : m_dispatcher(dispatcher), m_gimpactMeshes(gimpactMeshes), m_timeStep(timeStep) {}

  bool processOverlap(btBroadphasePair& pair) override {
    auto* object0 = static_cast<btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    auto* object1 = static_cast<btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    const bool gimpact0 = m_gimpactMeshes && GImpactStandIns::isGImpactMesh(object0->getCollisionShape());
    const bool gimpact1 = m_gimpactMeshes && GImpactStandIns::isGImpactMesh(object1->getCollisionShape());
    if ((!gimpact0 && !MeshShape::isMeshShape(object0->getCollisionShape())) ||
        (!gimpact1 && !MeshShape::isMeshShape(object1->getCollisionShape())) ||
        !m_dispatcher.needsCollision(object0, object1)) {
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
    if (std::optional<MeshPairQuery> query = algorithm->meshPairQuery(&wrapper0, &wrapper1, m_timeStep)) {
      algorithms.push_back(algorithm);
      queries.push_back(*query);
      caches.push_back(algorithm->candidateCache(object0->getCollisionShape(), object1->getCollisionShape()));
      gimpactPairs += gimpact0 || gimpact1;
    }
    return false;  // keep the pair
  }

  std::vector<MeshMeshAlgorithm*> algorithms;
  std::vector<MeshPairQuery> queries;
  std::vector<CandidateCache*> caches;
  std::uint64_t gimpactPairs = 0;

 private:
  btCollisionDispatcher& m_dispatcher;
  bool m_gimpactMeshes;
  btScalar m_timeStep;
};

// A concave shape gpucol collides a mesh with (a plane, a BVH, a heightfield, a GImpact mesh, a user's own).
bool isConcavePartner(const btCollisionShape* shape) {
  return shape->isConcave() && shape->getShapeType() != EMPTY_SHAPE_PROXYTYPE;
}

}  // namespace

CollisionDispatcher::CollisionDispatcher(btCollisionConfiguration* collisionConfiguration,
                                         const Config& config)
    : btCollisionDispatcher(collisionConfiguration),
      m_config(config),
      m_standIns(std::make_unique<GImpactStandIns>(config)) {
  MeshMeshAlgorithm::registerWith(*this, m_config);
}

CollisionDispatcher::~CollisionDispatcher() = default;

btCollisionAlgorithm* CollisionDispatcher::findAlgorithm(const btCollisionObjectWrapper* body0,
                                                         const btCollisionObjectWrapper* body1,
                                                         btPersistentManifold* sharedManifold,
                                                         ebtDispatcherQueryType queryType) {
  const btCollisionShape* s0 = body0->getCollisionShape();
  const btCollisionShape* s1 = body1->getCollisionShape();
  const bool gimpact0 = GImpactStandIns::isGImpactMesh(s0), gimpact1 = GImpactStandIns::isGImpactMesh(s1);
  if (gimpact0 || gimpact1) {
    // Checked here, not left to registered create functions: registerAlgorithm, called after this dispatcher
    // was made, registers GImpact's algorithm for every pair with a GImpact shape, a MeshShape's included.
    const btCollisionShape* other = gimpact0 ? s1 : s0;
    const auto readable = [&](const btCollisionShape* s) {
      return m_standIns->get(*static_cast<const btGImpactMeshShape*>(s)) != nullptr;
    };
    GImpactStandIns* standIns = nullptr;
    bool take = MeshShape::isMeshShape(other);
    if (m_config.collideGImpactShapes && isConcavePartner(other) &&
        ((gimpact0 && readable(s0)) || (gimpact1 && readable(s1)))) {
      take = true;
      standIns = m_standIns.get();
    }
    btCollisionAlgorithmConstructionInfo info;
    info.m_dispatcher1 = this;
    info.m_manifold = sharedManifold;
    if (take) {
      void* memory = allocateCollisionAlgorithm(sizeof(MeshMeshAlgorithm));
      return new (memory)
          MeshMeshAlgorithm(info, body0, body1, m_config, standIns, queryType == BT_CONTACT_POINT_ALGORITHMS);
    }
    if (m_config.collideGImpactShapes && other->isCompound()) {
      // The configuration's compound algorithm (GImpact's would collide the children itself): its child pairs
      // come back here.
      btCollisionAlgorithmCreateFunc* create =
          queryType == BT_CONTACT_POINT_ALGORITHMS
              ? m_collisionConfiguration->getCollisionAlgorithmCreateFunc(s0->getShapeType(),
                                                                          s1->getShapeType())
              : m_collisionConfiguration->getClosestPointsAlgorithmCreateFunc(s0->getShapeType(),
                                                                              s1->getShapeType());
      return create->CreateCollisionAlgorithm(info, body0, body1);
    }
  }
  return btCollisionDispatcher::findAlgorithm(body0, body1, sharedManifold, queryType);
}

void CollisionDispatcher::dispatchAllCollisionPairs(btOverlappingPairCache* pairCache,
                                                    const btDispatcherInfo& dispatchInfo, btDispatcher* dispatcher) {
  m_lastStepStats = DispatchStats();
  m_standIns->beginStep();
  m_standIns->resetBuilt();
  if (dispatchInfo.m_dispatchFunc == btDispatcherInfo::DISPATCH_DISCRETE) {
    MeshPairCollector collector(*this, m_config.collideGImpactShapes, dispatchInfo.m_timeStep);
    pairCache->processAllOverlappingPairs(&collector, this, dispatchInfo);
    if (!collector.queries.empty()) {
      const auto start = std::chrono::steady_clock::now();
      try {
        std::vector<MeshPairResult> results =
            collideMeshesBatch(collector.queries, m_config, collector.caches);
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
      m_lastStepStats.gimpactPairs = collector.gimpactPairs;
      m_lastStepStats.batchMilliseconds =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
  }
  btCollisionDispatcher::dispatchAllCollisionPairs(pairCache, dispatchInfo, dispatcher);
  m_lastStepStats.gimpactStandInsBuilt = m_standIns->built();
}

}  // namespace gpucol
