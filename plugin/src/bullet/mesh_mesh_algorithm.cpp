// MeshMeshAlgorithm: a MeshShape against a MeshShape, a btStaticPlaneShape or a btBvhTriangleMeshShape, with the
// contacts in persistent manifolds (contact_manifold_set.h).
#include "gpucol/mesh_mesh_algorithm.h"

#include <BulletCollision/CollisionDispatch/btCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <cmath>
#include <list>
#include <mutex>
#include <stdexcept>
#include <string>

#include "bullet/contact_manifold_set.h"
#include "bullet/gimpact_stand_ins.h"
#include "bullet/mesh_plane_contacts.h"
#include "bullet/triangle_mesh_patch.h"
#include "bullet/warn_once.h"
#include "gpucol/mesh_shape.h"
#include "mesh_pairs/candidate_cache.h"
#include "mesh_pairs/mesh_batch.h"

namespace gpucol {

struct MeshMeshAlgorithm::Precomputed {
  MeshPairQuery query;
  MeshPairResult result;
};

namespace {

bool sameTransform(const btTransform& a, const btTransform& b) {
  return a.getOrigin() == b.getOrigin() && a.getBasis()[0] == b.getBasis()[0] &&
         a.getBasis()[1] == b.getBasis()[1] && a.getBasis()[2] == b.getBasis()[2];
}

// Every concave shape Bullet has, and a user's own (CUSTOM_CONCAVE_SHAPE_TYPE): a plane is collided as a
// plane, the others through their processAllTriangles (TriangleMeshPatch). An empty shape collides with nothing.
bool isOtherConcave(const btCollisionShape* shape) {
  return shape->isConcave() && shape->getShapeType() != EMPTY_SHAPE_PROXYTYPE && !MeshShape::isMeshShape(shape);
}

// The shape types whose pairs with a MeshShape the algorithm is registered for.
const int kPartnerTypes[] = {MeshShape::kMeshShapeType,
                             TRIANGLE_MESH_SHAPE_PROXYTYPE,
                             SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE,
                             TERRAIN_SHAPE_PROXYTYPE,
                             GIMPACT_SHAPE_PROXYTYPE,
                             MULTIMATERIAL_TRIANGLE_MESH_PROXYTYPE,
                             STATIC_PLANE_PROXYTYPE,
                             CUSTOM_CONCAVE_SHAPE_TYPE};

// The pairs the algorithm takes: two meshes, or a mesh and one of the concave shapes it knows.
bool handles(const btCollisionShape* s0, const btCollisionShape* s1) {
  const bool mesh0 = MeshShape::isMeshShape(s0), mesh1 = MeshShape::isMeshShape(s1);
  return (mesh0 && mesh1) || (mesh0 && isOtherConcave(s1)) || (mesh1 && isOtherConcave(s0));
}

// Reduced mesh contacts as manifold contacts: the point moves onto B's margin surface and the distance counts
// both margins, so that bodies with margins rest that far apart (as Bullet's convex shapes do). Each side's
// triangle is named by its part and its index within the part, as Bullet's mesh shapes name theirs.
std::vector<PairContact> toPairContacts(const std::vector<MeshContact>& reduced, const MeshShape& a,
                                        const MeshShape& b) {
  const btScalar marginA = a.getMargin(), marginB = b.getMargin();
  std::vector<PairContact> out;
  out.reserve(reduced.size());
  for (const MeshContact& c : reduced) {
    PairContact p{c.pointOnBWorld + c.normalWorldOnB * marginB, c.normalWorldOnB, c.depth - marginA - marginB};
    const PartTriangle t0 = a.mesh().partTriangle(c.triangleA), t1 = b.mesh().partTriangle(c.triangleB);
    p.partId0 = t0.part;
    p.index0 = t0.index;
    p.partId1 = t1.part;
    p.index1 = t1.index;
    p.flatSize = btMin(a.flatFaceSize(c.triangleA), b.flatFaceSize(c.triangleB));
    out.push_back(p);
  }
  return out;
}

// The farthest any point of the body's shape is from the body's origin.
btScalar reachFromOrigin(const btCollisionShape& shape) {
  btVector3 center;
  btScalar radius;
  shape.getBoundingSphere(center, radius);
  return center.length() + radius;
}

// How far any point of the body's shape moves in `timeStep` by the body's turn: its spin times the farthest
// the shape's box (in the shape's frame) reaches from the turn's axis through the centre of mass. A rod
// spinning about its own length moves its points by its thickness, not its length, as reachFromOrigin would
// have it.
btScalar turnReach(const btCollisionObjectWrapper& body, const btRigidBody* rigid, btScalar timeStep) {
  if (rigid == nullptr) return 0;
  const btVector3 spin = rigid->getAngularVelocity();
  const btScalar rate = spin.length();
  if (rate == 0) return 0;
  // A NaN or infinite spin makes the pair's reach non-finite, and setSpeculativeReach gives it none.
  if (!std::isfinite(rate)) return rate;
  const btCollisionShape& shape = *body.getCollisionShape();
  const btVector3 axis = spin / rate;
  btVector3 lo, hi;
  shape.getAabb(btTransform::getIdentity(), lo, hi);
  if (!(lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z()) || !std::isfinite((hi - lo).length2())) {
    return timeStep * rate * reachFromOrigin(shape);
  }
  const btTransform& pose = body.getWorldTransform();
  const btVector3 offset = pose.getOrigin() - rigid->getCenterOfMassPosition();
  btScalar farthest2 = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const btVector3 local((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                          (corner & 4) ? hi.z() : lo.z());
    farthest2 = btMax(farthest2, axis.cross(pose.getBasis() * local + offset).length2());
  }
  return timeStep * rate * btSqrt(farthest2);
}

// The pair's speculative reach in a step of `timeStep` at the bodies' velocities: body1's motion relative to
// body0 and how far any point moves by their turns (turnReach of each). When
// the two together are more than Bullet's contact breaking threshold for the pair (what its convex shapes'
// speculative reach is), triangles that far apart get speculative contacts (thesis §7.1: small triangles
// otherwise pass through each other between steps), capped at the smaller body's diameter. Slower pairs get
// none: resting bodies touch, and the closest features of touching triangles have no direction to push along.
void setSpeculativeReach(const btCollisionObjectWrapper* body0, const btCollisionObjectWrapper* body1,
                         btScalar timeStep, MeshPairQuery& query) {
  if (!(timeStep > 0) || !std::isfinite(timeStep)) return;
  const btRigidBody* rigid0 = btRigidBody::upcast(body0->getCollisionObject());
  const btRigidBody* rigid1 = btRigidBody::upcast(body1->getCollisionObject());
  const btVector3 zero(0, 0, 0);
  const btVector3 linear0 = rigid0 ? rigid0->getLinearVelocity() : zero;
  const btVector3 linear1 = rigid1 ? rigid1->getLinearVelocity() : zero;
  const btCollisionShape& shape0 = *body0->getCollisionShape();
  const btCollisionShape& shape1 = *body1->getCollisionShape();
  const btScalar reach0 = reachFromOrigin(shape0), reach1 = reachFromOrigin(shape1);
  btVector3 motion = (linear1 - linear0) * timeStep;
  btScalar turns = turnReach(*body0, rigid0, timeStep) + turnReach(*body1, rigid1, timeStep);
  const btScalar total = motion.length() + turns;
  const btScalar breaking = btMin(shape0.getContactBreakingThreshold(gContactBreakingThreshold),
                                  shape1.getContactBreakingThreshold(gContactBreakingThreshold));
  if (!std::isfinite(total) || !(total > breaking)) return;
  const btScalar cap = 2 * btMin(reach0, reach1);
  if (total > cap) {
    motion *= cap / total;
    turns *= cap / total;
  }
  query.speculativeMotion = motion;
  query.speculativeDistance = turns;
}

std::string pairName(const btCollisionShape* s0, const btCollisionShape* s1) {
  const auto name = [](const btCollisionShape* s) {
    return MeshShape::isMeshShape(s) ? "mesh '" + static_cast<const MeshShape*>(s)->mesh().name() + "'"
                                     : std::string(s->getName());
  };
  return name(s0) + " against " + name(s1);
}

// The create function registered on a dispatcher: the algorithm for the pairs it handles, else what the
// dispatcher's collision configuration gave for that pair of shape types before.
class MeshMeshCreateFunc : public btCollisionAlgorithmCreateFunc {
 public:
  MeshMeshCreateFunc(const Config& config, btCollisionAlgorithmCreateFunc* fallback, bool speculativeContacts)
      : m_config(config), m_fallback(fallback), m_speculativeContacts(speculativeContacts) {}

  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& info,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override {
    if (!handles(body0->getCollisionShape(), body1->getCollisionShape())) {
      return m_fallback ? m_fallback->CreateCollisionAlgorithm(info, body0, body1) : nullptr;
    }
    void* memory = info.m_dispatcher1->allocateCollisionAlgorithm(sizeof(MeshMeshAlgorithm));
    return new (memory) MeshMeshAlgorithm(info, body0, body1, m_config, nullptr, m_speculativeContacts);
  }

 private:
  Config m_config;
  btCollisionAlgorithmCreateFunc* m_fallback;
  bool m_speculativeContacts;
};

}  // namespace

MeshMeshAlgorithm::MeshMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& info,
                                     const btCollisionObjectWrapper* body0,
                                     const btCollisionObjectWrapper* body1, const Config& config,
                                     GImpactStandIns* standIns, bool speculativeContacts)
    : btActivatingCollisionAlgorithm(info, body0, body1),
      m_config(config),
      m_standIns(standIns),
      m_speculativeContacts(speculativeContacts),
      m_manifolds(std::make_unique<ContactManifoldSet>(info.m_dispatcher1)),
      m_patch(std::make_unique<TriangleMeshPatch>()),
      m_candidates(std::make_unique<CandidateCache>()) {}

MeshMeshAlgorithm::~MeshMeshAlgorithm() = default;

const MeshShape* MeshMeshAlgorithm::asMesh(const btCollisionShape* shape) const {
  if (MeshShape::isMeshShape(shape)) return static_cast<const MeshShape*>(shape);
  if (m_standIns != nullptr && GImpactStandIns::isGImpactMesh(shape)) {
    return m_standIns->get(*static_cast<const btGImpactMeshShape*>(shape));
  }
  return nullptr;
}

std::optional<MeshPairQuery> MeshMeshAlgorithm::meshPairQuery(const btCollisionObjectWrapper* body0,
                                                              const btCollisionObjectWrapper* body1,
                                                              btScalar timeStep) const {
  const MeshShape* a = asMesh(body0->getCollisionShape());
  const MeshShape* b = a ? asMesh(body1->getCollisionShape()) : nullptr;
  if (b == nullptr) return std::nullopt;
  MeshPairQuery query;
  query.shapeA = a;
  query.transformA = body0->getWorldTransform();
  query.shapeB = b;
  query.transformB = body1->getWorldTransform();
  if (m_speculativeContacts) setSpeculativeReach(body0, body1, timeStep, query);
  return query;
}

CandidateCache* MeshMeshAlgorithm::candidateCache(const btCollisionShape* shape0,
                                                  const btCollisionShape* shape1) {
  // A closest-points algorithm lives for one query (contactTest makes it and throws it away): a cache would
  // only widen its one traversal.
  return m_speculativeContacts && MeshShape::isMeshShape(shape0) && MeshShape::isMeshShape(shape1)
             ? m_candidates.get()
             : nullptr;
}

void MeshMeshAlgorithm::setPrecomputedResult(const MeshPairQuery& query, MeshPairResult result) {
  m_precomputed = std::make_unique<Precomputed>(Precomputed{query, std::move(result)});
}

void MeshMeshAlgorithm::processCollision(const btCollisionObjectWrapper* body0,
                                         const btCollisionObjectWrapper* body1,
                                         const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
  const btCollisionShape* s0 = body0->getCollisionShape();
  const btCollisionShape* s1 = body1->getCollisionShape();
  std::unique_ptr<Precomputed> precomputed = std::move(m_precomputed);
  std::vector<PairContact> contacts;
  btScalar speculative = 0;
  try {
    const MeshShape* mesh0 = asMesh(s0);
    const MeshShape* mesh1 = asMesh(s1);
    if (mesh0 == nullptr && mesh1 == nullptr) {
      // Only a GImpact mesh's pair comes here without a mesh: its triangles could not be read this step.
      throw std::runtime_error("the GImpact mesh's triangles cannot be read");
    }
    if (const std::optional<MeshPairQuery> query = meshPairQuery(body0, body1, dispatchInfo.m_timeStep)) {
      // The batch's result is used only for the very shapes and transforms it was computed with: a compound's
      // child or a user calling processCollision again gets its own query.
      const bool batched = precomputed && precomputed->query.shapeA == query->shapeA &&
                           precomputed->query.shapeB == query->shapeB &&
                           sameTransform(precomputed->query.transformA, query->transformA) &&
                           sameTransform(precomputed->query.transformB, query->transformB) &&
                           precomputed->query.speculativeMotion == query->speculativeMotion &&
                           precomputed->query.speculativeDistance == query->speculativeDistance;
      const MeshPairResult result =
          batched ? std::move(precomputed->result) : collideMeshes(*query, m_config, candidateCache(s0, s1));
      speculative = query->speculativeMotion.length() + query->speculativeDistance;
      contacts = toPairContacts(result.reducedContacts, *query->shapeA, *query->shapeB);
    } else {
      // A mesh against a plane or another concave shape: computed with the mesh as body0, then turned round if
      // the mesh is body1.
      const bool meshFirst = mesh0 != nullptr;
      const btCollisionObjectWrapper* meshBody = meshFirst ? body0 : body1;
      const btCollisionObjectWrapper* otherBody = meshFirst ? body1 : body0;
      const MeshShape& mesh = meshFirst ? *mesh0 : *mesh1;
      const btCollisionShape* other = otherBody->getCollisionShape();
      if (other->getShapeType() == STATIC_PLANE_PROXYTYPE) {
        contacts = meshPlaneContacts(mesh, meshBody->getWorldTransform(), *static_cast<const btStaticPlaneShape*>(other),
                                     otherBody->getWorldTransform(), m_config.reductionResolution);
      } else if (isOtherConcave(other)) {
        MeshPairQuery query;
        query.shapeA = &mesh;
        query.transformA = meshBody->getWorldTransform();
        query.transformB = otherBody->getWorldTransform();
        if (m_speculativeContacts) setSpeculativeReach(meshBody, otherBody, dispatchInfo.m_timeStep, query);
        speculative = query.speculativeMotion.length() + query.speculativeDistance;
        if (const MeshShape* patch = m_patch->update(*static_cast<const btConcaveShape*>(other),
                                                     query.transformB, mesh, query.transformA, speculative)) {
          query.shapeB = patch;
          const MeshPairResult result = collideMeshes(query, m_config);
          contacts = toPairContacts(result.reducedContacts, mesh, *patch);
          // The patch's triangles are the other shape's: their part and index as its processAllTriangles
          // gave.
          for (PairContact& c : contacts)
            m_patch->sourceTriangle(std::uint32_t(c.index1), c.partId1, c.index1);
        }
      }
      if (!meshFirst) contacts = swapSides(std::move(contacts));
    }
  } catch (const std::exception& e) {
    // Never through Bullet: the pair is skipped this step, its manifolds emptied so that no stale or NaN point
    // reaches the solver, and the reason said once.
    warnOnce("pair " + pairName(s0, s1), "skipping the collision of " + pairName(s0, s1) + ": " + e.what());
    m_manifolds = std::make_unique<ContactManifoldSet>(m_dispatcher);
    return;
  }
  m_manifolds->write(contacts, body0, body1, resultOut, speculative);
}

btScalar MeshMeshAlgorithm::calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                                  btManifoldResult*) {
  return 1;
}

void MeshMeshAlgorithm::getAllContactManifolds(btManifoldArray& manifolds) { m_manifolds->appendTo(manifolds); }

void MeshMeshAlgorithm::registerWith(btCollisionDispatcher& dispatcher, const Config& config) {
  // Create functions must outlive the dispatcher's use of them; like GImpact's static one, they live until the
  // process ends.
  static std::mutex mutex;
  static std::list<MeshMeshCreateFunc> functions;
  const std::lock_guard<std::mutex> lock(mutex);
  btCollisionConfiguration* configuration = dispatcher.getCollisionConfiguration();
  for (int a : kPartnerTypes) {
    for (int b : kPartnerTypes) {
      if (a != MeshShape::kMeshShapeType && b != MeshShape::kMeshShapeType) continue;
      functions.emplace_back(config, configuration->getCollisionAlgorithmCreateFunc(a, b), true);
      dispatcher.registerCollisionCreateFunc(a, b, &functions.back());
      functions.emplace_back(config, configuration->getClosestPointsAlgorithmCreateFunc(a, b), false);
      dispatcher.registerClosestPointsCreateFunc(a, b, &functions.back());
    }
  }
}

}  // namespace gpucol
