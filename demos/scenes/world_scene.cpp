#include "scenes/world_scene.h"

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletDynamics/ConstraintSolver/btSequentialImpulseConstraintSolver.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <gpucol/collision_dispatcher.h>
#include <gpucol/grid_broadphase.h>
#include <gpucol/mesh_shape.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "scenes/body_overlap.h"
#include "scenes/convex_piece_shape.h"
#include "scenes/gimpact_peer.h"

namespace gpucol::scenes {

const char* backendName(CollisionBackend backend) {
  switch (backend) {
    case CollisionBackend::Gpucol:
      return "gpucol";
    case CollisionBackend::GImpact:
      return "gimpact";
    case CollisionBackend::Primitives:
      return "primitives";
    case CollisionBackend::GImpactOnGpucol:
      return "gimpact-gpucol";
  }
  return "?";
}

// One collision shape per mesh of the description, of the backend's kind.
struct WorldScene::Shapes {
  std::vector<std::unique_ptr<MeshShape>> gpucol;
  std::vector<std::unique_ptr<GImpactMesh>> gimpact;
  std::vector<std::unique_ptr<btCollisionShape>> pieces;  // the primitives' children, destroyed last
  std::vector<std::unique_ptr<btCollisionShape>> primitives;

  btCollisionShape* shape(std::size_t mesh) {
    if (!gpucol.empty()) return gpucol[mesh].get();
    if (!gimpact.empty()) return gimpact[mesh]->shape();
    return primitives[mesh].get();
  }
};

namespace {

// Diagonal inertia of a solid of uniform density bounded by `mesh` (in its principal frame), scaled to
// `mass`. The GImpact backend uses it because btGImpactMeshShape's own inertia lumps the mass at the
// vertices; with the same numbers as MeshShape::calculateLocalInertia, both backends simulate the same
// bodies.
btVector3 solidInertia(const TriangleMesh& mesh, float mass) {
  const MassProperties properties = mesh.massProperties(1.0);
  const double scale = double(mass) / properties.mass;
  return btVector3(btScalar(properties.inertia[0] * scale), btScalar(properties.inertia[4] * scale),
                   btScalar(properties.inertia[8] * scale));
}

}  // namespace

WorldScene::WorldScene(const SceneDescription& scene, const WorldOptions& options)
    : m_scene(scene), m_options(options), m_shapes(std::make_unique<Shapes>()) {
  for (const SceneBody& body : m_scene.bodies) {
    if (body.mesh >= m_scene.meshes.size()) {
      throw std::invalid_argument("scene '" + m_scene.name + "': a body names mesh " +
                                  std::to_string(body.mesh) + " of " + std::to_string(m_scene.meshes.size()));
    }
  }

  m_collisionConfiguration = std::make_unique<btDefaultCollisionConfiguration>();
  if (options.backend == CollisionBackend::Gpucol) {
    m_dispatcher = std::make_unique<CollisionDispatcher>(m_collisionConfiguration.get(), options.config);
    m_broadphase = std::make_unique<GridBroadphase>(options.config);
    for (const auto& mesh : m_scene.meshes) {
      m_shapes->gpucol.push_back(std::make_unique<MeshShape>(mesh, options.config));
      m_shapes->gpucol.back()->setMargin(options.meshMargin);
    }
  } else if (options.backend == CollisionBackend::Primitives) {
    m_dispatcher = std::make_unique<btCollisionDispatcher>(m_collisionConfiguration.get());
    m_broadphase = std::make_unique<btDbvtBroadphase>();
    for (std::size_t mesh = 0; mesh < m_scene.meshes.size(); ++mesh) {
      if (mesh >= m_scene.convexPieces.size() || m_scene.convexPieces[mesh].empty()) {
        throw std::invalid_argument("scene '" + m_scene.name + "': mesh " + std::to_string(mesh) +
                                    " has no convex pieces for the primitives backend");
      }
      const std::vector<ConvexPiece>& pieces = m_scene.convexPieces[mesh];
      if (pieces.size() == 1 && pieces[0].pose == btTransform::getIdentity()) {
        m_shapes->primitives.push_back(makePieceShape(pieces[0]));
        continue;
      }
      auto compound = std::make_unique<btCompoundShape>();
      for (const ConvexPiece& piece : pieces) {
        m_shapes->pieces.push_back(makePieceShape(piece));
        compound->addChildShape(piece.pose, m_shapes->pieces.back().get());
      }
      m_shapes->primitives.push_back(std::move(compound));
    }
  } else {
    // The one line a GImpact world changes to move over to gpucol.
    if (options.backend == CollisionBackend::GImpactOnGpucol) {
      m_dispatcher = std::make_unique<CollisionDispatcher>(m_collisionConfiguration.get(), options.config);
    } else {
      m_dispatcher = std::make_unique<btCollisionDispatcher>(m_collisionConfiguration.get());
    }
    btGImpactCollisionAlgorithm::registerAlgorithm(m_dispatcher.get());
    m_broadphase = std::make_unique<btDbvtBroadphase>();
    for (const auto& mesh : m_scene.meshes) {
      auto peer = std::make_unique<GImpactMesh>(*mesh);
      peer->shape()->setMargin(options.gimpactMargin);
      peer->shape()->updateBound();
      m_shapes->gimpact.push_back(std::move(peer));
    }
  }
  m_solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  m_world = std::make_unique<btDiscreteDynamicsWorld>(m_dispatcher.get(), m_broadphase.get(), m_solver.get(),
                                                      m_collisionConfiguration.get());
  m_world->setGravity(m_scene.gravity);
  m_world->getSolverInfo().m_numIterations = options.solverIterations;

  for (const SceneBody& body : m_scene.bodies) {
    btCollisionShape* shape = m_shapes->shape(body.mesh);
    btVector3 inertia(0, 0, 0);
    if (body.mass > 0) {
      if (options.backend == CollisionBackend::Gpucol) {
        shape->calculateLocalInertia(body.mass, inertia);
      } else {
        inertia = solidInertia(*m_scene.meshes[body.mesh], body.mass);
      }
    }
    btRigidBody::btRigidBodyConstructionInfo info(body.mass, nullptr, shape, inertia);
    info.m_startWorldTransform = body.start;
    auto rigidBody = std::make_unique<btRigidBody>(info);
    if (body.mass > 0) {
      if (!options.allowSleeping) rigidBody->setActivationState(DISABLE_DEACTIVATION);
      m_dynamicBodies.push_back(rigidBody.get());
    }
    m_world->addRigidBody(rigidBody.get());
    m_bodyIndex[rigidBody.get()] = m_bodies.size();
    m_bodies.push_back(std::move(rigidBody));
  }
}

WorldScene::~WorldScene() {
  // Removing a body destroys its broad phase proxy, which frees its pairs' algorithms through the dispatcher:
  // every body leaves the world while the broad phase and the dispatcher still exist.
  for (auto it = m_bodies.rbegin(); it != m_bodies.rend(); ++it) m_world->removeRigidBody(it->get());
  m_bodies.clear();
  m_world.reset();
  m_solver.reset();
  m_broadphase.reset();
  m_dispatcher.reset();
  m_collisionConfiguration.reset();
  m_shapes.reset();
}

void WorldScene::step(float dt) {
  // maxSubSteps = 0: one step of exactly dt, no fixed-step accumulator and no interpolated motion states.
  m_world->stepSimulation(dt, 0);
}

const CollisionDispatcher* WorldScene::gpucolDispatcher() const {
  // Only these two backends build gpucol's dispatcher; the others hold Bullet's own.
  const bool gpucol =
      m_options.backend == CollisionBackend::Gpucol || m_options.backend == CollisionBackend::GImpactOnGpucol;
  return gpucol ? static_cast<const CollisionDispatcher*>(m_dispatcher.get()) : nullptr;
}

double WorldScene::kineticEnergy() const {
  double energy = 0;
  for (const btRigidBody* body : m_dynamicBodies) {
    const btVector3& v = body->getLinearVelocity();
    energy += 0.5 / double(body->getInvMass()) *
              (double(v.x()) * v.x() + double(v.y()) * v.y() + double(v.z()) * v.z());
    // Rotational energy in the body frame, where the inertia is diagonal.
    const btVector3 w = body->getWorldTransform().getBasis().transpose() * body->getAngularVelocity();
    const btVector3& inverseInertia = body->getInvInertiaDiagLocal();
    for (int axis = 0; axis < 3; ++axis) {
      if (inverseInertia[axis] > 0) energy += 0.5 / double(inverseInertia[axis]) * double(w[axis]) * w[axis];
    }
  }
  return energy;
}

double WorldScene::potentialEnergy() const {
  double energy = 0;
  const double g = -double(m_scene.gravity.y());
  for (const btRigidBody* body : m_dynamicBodies) {
    const double height = double(body->getCenterOfMassPosition().y()) - m_scene.groundTop;
    energy += g * height / double(body->getInvMass());
  }
  return energy;
}

float WorldScene::largestPenetration() const {
  float deepest = 0;
  const int manifolds = m_dispatcher->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = m_dispatcher->getManifoldByIndexInternal(i);
    for (int j = 0; j < manifold->getNumContacts(); ++j) {
      deepest = std::max(deepest, -manifold->getContactPoint(j).getDistance());
    }
  }
  return deepest;
}

float WorldScene::deepestBodyOverlap() const {
  if (!m_overlap) m_overlap = std::make_unique<BodyOverlap>(m_scene);
  if (!m_overlap->complete()) return -1;
  float deepest = 0;
  const int manifolds = m_dispatcher->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = m_dispatcher->getManifoldByIndexInternal(i);
    if (manifold->getNumContacts() == 0) continue;
    const auto a = m_bodyIndex.find(manifold->getBody0()), b = m_bodyIndex.find(manifold->getBody1());
    if (a == m_bodyIndex.end() || b == m_bodyIndex.end()) continue;
    deepest = std::max(deepest, m_overlap->deepest(m_scene.bodies[a->second].mesh,
                                                   manifold->getBody0()->getWorldTransform(),
                                                   m_scene.bodies[b->second].mesh,
                                                   manifold->getBody1()->getWorldTransform()));
  }
  return deepest;
}

int WorldScene::contactCount() const {
  int contacts = 0;
  const int manifolds = m_dispatcher->getNumManifolds();
  for (int i = 0; i < manifolds; ++i)
    contacts += m_dispatcher->getManifoldByIndexInternal(i)->getNumContacts();
  return contacts;
}

int WorldScene::movingBodyCount(float linearSpeed, float angularSpeed) const {
  int moving = 0;
  for (const btRigidBody* body : m_dynamicBodies) {
    if (body->getActivationState() == ISLAND_SLEEPING) continue;
    moving += !(body->getLinearVelocity().length() < linearSpeed &&
                body->getAngularVelocity().length() < angularSpeed);
  }
  return moving;
}

bool WorldScene::allAtRest(float linearSpeed, float angularSpeed) const {
  return movingBodyCount(linearSpeed, angularSpeed) == 0;
}

int WorldScene::sleepingBodyCount() const {
  return int(std::count_if(m_dynamicBodies.begin(), m_dynamicBodies.end(), [](const btRigidBody* body) {
    return body->getActivationState() == ISLAND_SLEEPING;
  }));
}

std::vector<btVector3> WorldScene::positions() const {
  std::vector<btVector3> out;
  out.reserve(m_dynamicBodies.size());
  for (const btRigidBody* body : m_dynamicBodies) out.push_back(body->getCenterOfMassPosition());
  return out;
}

bool WorldScene::allFinite() const {
  auto finite = [](const btVector3& v) {
    return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
  };
  for (const btRigidBody* body : m_dynamicBodies) {
    const btQuaternion q = body->getOrientation();
    if (!finite(body->getCenterOfMassPosition()) || !finite(body->getLinearVelocity()) ||
        !finite(body->getAngularVelocity()) || !std::isfinite(q.x()) || !std::isfinite(q.y()) ||
        !std::isfinite(q.z()) || !std::isfinite(q.w())) {
      return false;
    }
  }
  return true;
}

int WorldScene::bodiesBelowGround() const {
  // A body resting on the ground has its centre of mass above the ground's top face (the centre of mass lies
  // in the body's convex hull, which rests on the face), so a centre below it means the body went through.
  return int(std::count_if(m_dynamicBodies.begin(), m_dynamicBodies.end(), [this](const btRigidBody* body) {
    return body->getCenterOfMassPosition().y() < m_scene.groundTop - m_scene.fallTolerance;
  }));
}

float WorldScene::farthestBody() const {
  float farthest = 0;
  for (const btRigidBody* body : m_dynamicBodies)
    farthest = std::max(farthest, body->getCenterOfMassPosition().length());
  return farthest;
}

}  // namespace gpucol::scenes
