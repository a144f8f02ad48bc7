#pragma once

// A small Bullet world for the integration tests: owns the configuration, dispatcher, broad phase, solver,
// shapes and bodies, and destroys them in Bullet's order.

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <memory>
#include <vector>

#include <gpucol/gpucol.h>

namespace gpucol::test {

/// How the world dispatches collisions.
enum class DispatchKind {
  Gpucol,          ///< gpucol::CollisionDispatcher (batched mesh pairs).
  StockRegistered, ///< btCollisionDispatcher with MeshMeshAlgorithm::registerWith.
  Stock,           ///< btCollisionDispatcher untouched (convex-vs-mesh through Bullet's own algorithm).
};

/// A world with btDbvtBroadphase and the sequential impulse solver; gravity -10 along y.
class TestWorld {
 public:
  explicit TestWorld(DispatchKind kind, const Config& config = Config()) {
    if (kind == DispatchKind::Gpucol) {
      m_dispatcher = std::make_unique<CollisionDispatcher>(&m_configuration, config);
    } else {
      m_dispatcher = std::make_unique<btCollisionDispatcher>(&m_configuration);
      if (kind == DispatchKind::StockRegistered) MeshMeshAlgorithm::registerWith(*m_dispatcher, config);
    }
    m_world = std::make_unique<btDiscreteDynamicsWorld>(m_dispatcher.get(), &m_broadphase, &m_solver, &m_configuration);
    m_world->setGravity(btVector3(0, -10, 0));
  }

  ~TestWorld() {
    for (int i = m_world->getNumCollisionObjects() - 1; i >= 0; --i) {
      btCollisionObject* object = m_world->getCollisionObjectArray()[i];
      m_world->removeCollisionObject(object);
      btRigidBody* body = btRigidBody::upcast(object);
      if (body) delete body->getMotionState();
      delete object;
    }
  }

  /// Adds a body (static when mass is 0); the world keeps `shape` alive.
  btRigidBody* add(std::shared_ptr<btCollisionShape> shape, btScalar mass, const btTransform& transform) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(mass, new btDefaultMotionState(transform), shape.get(), inertia);
    auto* body = new btRigidBody(info);
    m_world->addRigidBody(body);
    m_shapes.push_back(std::move(shape));
    return body;
  }

  /// Steps the world `steps` times at 60 Hz.
  void step(int steps) {
    for (int i = 0; i < steps; ++i) m_world->stepSimulation(btScalar(1) / 60, 1, btScalar(1) / 60);
  }

  btDiscreteDynamicsWorld& world() { return *m_world; }
  btCollisionDispatcher& dispatcher() { return *m_dispatcher; }

  /// Deepest contact distance over all manifolds (0 when none penetrates).
  btScalar deepestPenetration() {
    btScalar deepest = 0;
    for (int m = 0; m < m_dispatcher->getNumManifolds(); ++m) {
      const btPersistentManifold* manifold = m_dispatcher->getManifoldByIndexInternal(m);
      for (int p = 0; p < manifold->getNumContacts(); ++p) deepest = std::min(deepest, manifold->getContactPoint(p).getDistance());
    }
    return deepest;
  }

  /// Number of contact points over all manifolds.
  int contactPoints() {
    int points = 0;
    for (int m = 0; m < m_dispatcher->getNumManifolds(); ++m) points += m_dispatcher->getManifoldByIndexInternal(m)->getNumContacts();
    return points;
  }

 private:
  btDefaultCollisionConfiguration m_configuration;
  std::unique_ptr<btCollisionDispatcher> m_dispatcher;
  btDbvtBroadphase m_broadphase;
  btSequentialImpulseConstraintSolver m_solver;
  std::unique_ptr<btDiscreteDynamicsWorld> m_world;
  std::vector<std::shared_ptr<btCollisionShape>> m_shapes;
};

/// A MeshShape over a mesh built in place.
inline std::shared_ptr<MeshShape> meshShape(TriangleMesh mesh) {
  return std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(std::move(mesh)));
}

/// A transform that only translates.
inline btTransform at(btScalar x, btScalar y, btScalar z) {
  return btTransform(btQuaternion::getIdentity(), btVector3(x, y, z));
}

/// True when every component of the body's position and velocities is finite.
inline bool isFinite(const btRigidBody& body) {
  const btVector3 p = body.getWorldTransform().getOrigin(), v = body.getLinearVelocity(), w = body.getAngularVelocity();
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(p[i]) || !std::isfinite(v[i]) || !std::isfinite(w[i])) return false;
  }
  return true;
}

}  // namespace gpucol::test
