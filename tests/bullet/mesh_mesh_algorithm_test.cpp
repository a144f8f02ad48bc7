// MeshMeshAlgorithm against analytic answers: a mesh box resting on a mesh ground, a btStaticPlaneShape and a
// btBvhTriangleMeshShape (both pair orders) settles at the analytic height; overlapping boxes get the
// analytic normal and depth; manifolds persist across steps, split by normal direction, and a face resting on
// a face holds one; the pieces wire into a stock dispatcher; foreign concave shapes and NaN transforms
// neither crash nor reach the solver.
#include <gtest/gtest.h>

#include <BulletCollision/CollisionDispatch/btEmptyCollisionAlgorithm.h>

#include <iostream>

#include "bullet/test_world.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"
#include "support/test_paths.h"

namespace gpucol::test {
namespace {

// A resting body may sink into what holds it by Bullet's allowed penetration (the solver corrects only
// penetration beyond its slop, and gravity pulls a little in every step): 1 cm on bodies of 1 m is well
// above that and well below anything a user would see as sinking.
constexpr btScalar kRestTolerance = 0.01f;

std::shared_ptr<btStaticPlaneShape> floorPlane() {
  return std::make_shared<btStaticPlaneShape>(btVector3(0, 1, 0), 0);
}

// Two big triangles at y = 0 as Bullet's own static triangle mesh. The btTriangleMesh must outlive the shape.
struct BvhFloor {
  BvhFloor() : arrays(std::make_shared<btTriangleMesh>()) {
    arrays->addTriangle(btVector3(-10, 0, -10), btVector3(-10, 0, 10), btVector3(10, 0, 10));
    arrays->addTriangle(btVector3(-10, 0, -10), btVector3(10, 0, 10), btVector3(10, 0, -10));
    shape = std::shared_ptr<btBvhTriangleMeshShape>(new btBvhTriangleMeshShape(arrays.get(), true),
                                                   [keep = arrays](btBvhTriangleMeshShape* s) { delete s; });
  }
  std::shared_ptr<btTriangleMesh> arrays;
  std::shared_ptr<btBvhTriangleMeshShape> shape;
};

TEST(MeshMeshAlgorithm, BoxRestsOnMeshGround) {
  for (DispatchKind kind : {DispatchKind::Gpucol, DispatchKind::StockRegistered}) {
    TestWorld w(kind);
    w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
    btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0.3f, 0.7f, -0.2f));
    w.step(240);
    EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance);
    EXPECT_GT(w.deepestPenetration(), -kRestTolerance);
    EXPECT_LT(box->getLinearVelocity().length(), 1e-2f);
    EXPECT_TRUE(isFinite(*box));
  }
}

// The plane and the BVH floor are added first or last, so that they are body0 or body1 of the pair: both orders
// of the algorithm's sides get checked.
TEST(MeshMeshAlgorithm, BoxRestsOnPlaneInBothPairOrders) {
  for (bool planeFirst : {true, false}) {
    TestWorld w(DispatchKind::Gpucol);
    if (planeFirst) w.add(floorPlane(), 0, at(0, 0, 0));
    btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 1.0f, 0));
    if (!planeFirst) w.add(floorPlane(), 0, at(0, 0, 0));
    w.step(240);
    EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance) << "plane first " << planeFirst;
    EXPECT_LT(box->getLinearVelocity().length(), 1e-2f);
    // Resting flat: the box must not have tipped.
    EXPECT_GT(box->getWorldTransform().getBasis().getColumn(1).y(), 0.999f);
  }
}

TEST(MeshMeshAlgorithm, BoxRestsOnBvhTriangleMeshInBothPairOrders) {
  for (bool floorFirst : {true, false}) {
    TestWorld w(DispatchKind::Gpucol);
    BvhFloor floor;
    if (floorFirst) w.add(floor.shape, 0, at(0, 0, 0));
    btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 0.8f, 0));
    if (!floorFirst) w.add(floor.shape, 0, at(0, 0, 0));
    w.step(240);
    EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance) << "floor first " << floorFirst;
    EXPECT_LT(box->getLinearVelocity().length(), 1e-2f);
    EXPECT_GT(box->getWorldTransform().getBasis().getColumn(1).y(), 0.999f);
  }
}

// A mesh box sunk 0.05 into a mesh ground: every kept contact pushes it straight up by 0.05 (the side triangles
// of the box cross the ground's top face 0.05 above their lowest corner), on the ground's top face.
TEST(MeshMeshAlgorithm, OverlappingBoxesGetTheAnalyticNormalAndDepth) {
  TestWorld w(DispatchKind::Gpucol);
  btRigidBody* ground = w.add(meshShape(scenes::makeBox(2, 0.5f, 2)), 0, at(0, -0.5f, 0));
  btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0.2f, 0.45f, 0.1f));
  w.world().performDiscreteCollisionDetection();
  ASSERT_GT(w.contactPoints(), 0);
  for (int m = 0; m < w.dispatcher().getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = w.dispatcher().getManifoldByIndexInternal(m);
    const btScalar sign = manifold->getBody1() == ground ? 1 : -1;  // normalWorldOnB points from body1 to body0
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& point = manifold->getContactPoint(p);
      EXPECT_NEAR((sign * point.m_normalWorldOnB).y(), 1.0f, 1e-5f);
      EXPECT_NEAR(point.getDistance(), -0.05f, 1e-5f);
      const btVector3 onGround = manifold->getBody1() == ground ? point.getPositionWorldOnB() : point.getPositionWorldOnA();
      EXPECT_NEAR(onGround.y(), 0.0f, 1e-5f);
    }
  }
  (void)box;
}

// Warm starting needs the same manifold and the same points step after step (GImpact clears its manifold every
// step): a resting box keeps its manifold, its points grow old, and their impulses carry over.
TEST(MeshMeshAlgorithm, ManifoldsPersistAcrossSteps) {
  TestWorld w(DispatchKind::Gpucol);
  w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
  btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 0.5f, 0));
  box->setActivationState(DISABLE_DEACTIVATION);
  const auto manifolds = [&] {
    std::vector<const btPersistentManifold*> out;
    for (int m = 0; m < w.dispatcher().getNumManifolds(); ++m)
      out.push_back(w.dispatcher().getManifoldByIndexInternal(m));
    return out;
  };
  w.step(60);
  const std::vector<const btPersistentManifold*> first = manifolds();
  ASSERT_FALSE(first.empty());
  w.step(100);
  EXPECT_EQ(manifolds(), first);
  // Bullet holds 4 points a manifold; when the reduction keeps more, the one it trades each step is new, but
  // a box face needs 3 that stay to stand on.
  int old = 0;
  for (const btPersistentManifold* manifold : first) {
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      const btManifoldPoint& point = manifold->getContactPoint(p);
      if (point.getLifeTime() >= 100 && point.getAppliedImpulse() > 0) ++old;
    }
  }
  EXPECT_GE(old, 3);
}

// A box pushed into a corner of floor and wall touches with two normals 90° apart: each gets its own manifold,
// so that neither face's points are traded away for the other's.
TEST(MeshMeshAlgorithm, NormalsFarApartGetTheirOwnManifolds) {
  TestWorld w(DispatchKind::Gpucol);
  w.world().setGravity(btVector3(-5, -10, 0));
  // An L of arm 6 and thickness 2: moved up by 1, its floor's top is y = 0 and its wall's inner face x = -1.
  w.add(meshShape(scenes::makeLShape(6, 6)), 0, at(0, 1, 0));
  btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 0.6f, 0));
  box->setActivationState(DISABLE_DEACTIVATION);
  w.step(240);
  EXPECT_NEAR(box->getWorldTransform().getOrigin().x(), -0.5f, kRestTolerance);
  EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance);
  // Every manifold's points share one normal, the floor's or the wall's, and both are there.
  ASSERT_GE(w.dispatcher().getNumManifolds(), 2);
  int floors = 0, walls = 0;
  for (int m = 0; m < w.dispatcher().getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = w.dispatcher().getManifoldByIndexInternal(m);
    ASSERT_GT(manifold->getNumContacts(), 0);
    const btVector3 normal = manifold->getContactPoint(0).m_normalWorldOnB;
    for (int p = 1; p < manifold->getNumContacts(); ++p) {
      EXPECT_GT(manifold->getContactPoint(p).m_normalWorldOnB.dot(normal), 0.999f);
    }
    floors += std::abs(normal.y()) > 0.999f;
    walls += std::abs(normal.x()) > 0.999f;
  }
  EXPECT_GT(floors, 0);
  EXPECT_GT(walls, 0);
  EXPECT_EQ(floors + walls, w.dispatcher().getNumManifolds());
}

// A box's face resting on a mesh ground's face, or on a plane, is one flat support: one manifold of 4 points,
// as Bullet's box pair holds it, not a patch per quarter of the box (a stack of ten such faces landed
// deeper).
TEST(MeshMeshAlgorithm, AFaceRestingOnAFaceHoldsOneManifold) {
  for (bool plane : {false, true}) {
    TestWorld w(DispatchKind::Gpucol);
    if (plane) {
      w.add(floorPlane(), 0, at(0, 0, 0));
    } else {
      w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
    }
    btTransform pose = at(0.2f, 0.5f, -0.1f);
    pose.setRotation(btQuaternion(btVector3(0, 1, 0), 0.35f));
    btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, pose);
    box->setActivationState(DISABLE_DEACTIVATION);
    w.step(120);
    ASSERT_EQ(w.dispatcher().getNumManifolds(), 1) << (plane ? "plane" : "mesh ground");
    EXPECT_EQ(w.dispatcher().getManifoldByIndexInternal(0)->getNumContacts(), 4);
    EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance);
  }
}

// Meshes of the data set on each other: a torus dropped on an armadillo that stands on a mesh ground. Both come to
// rest above the ground, nothing passes through.
TEST(MeshMeshAlgorithm, RealMeshesComeToRestOnEachOther) {
  GPUCOL_REQUIRE_MESH(armadilloPath, "armadillo-5000.ply");
  GPUCOL_REQUIRE_MESH(torusPath, "torus-1152.ply");
  TestWorld w(DispatchKind::Gpucol);
  const auto load = [](const std::string& path, float size) {
    TriangleMesh mesh = loadMesh(path).inPrincipalFrame(1.0);
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (std::size_t i = 0; i < mesh.positions().size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], mesh.positions()[i]);
      hi[i % 3] = std::max(hi[i % 3], mesh.positions()[i]);
    }
    auto shape = meshShape(std::move(mesh));
    const float largest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    shape->setLocalScaling(btVector3(size / largest, size / largest, size / largest));
    return shape;
  };
  w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
  std::vector<btRigidBody*> bodies = {w.add(load(armadilloPath, 1.0f), 1, at(0, 0.8f, 0)),
                                      w.add(load(torusPath, 0.6f), 1, at(0.05f, 2.0f, 0))};
  bool touched = false;  // the torus really lands on the armadillo
  for (int i = 0; i < 600; ++i) {
    w.step(1);
    for (int m = 0; m < w.dispatcher().getNumManifolds(); ++m) {
      const btPersistentManifold* manifold = w.dispatcher().getManifoldByIndexInternal(m);
      touched |= manifold->getNumContacts() > 0 && !manifold->getBody0()->isStaticObject() &&
                 !manifold->getBody1()->isStaticObject();
    }
  }
  EXPECT_TRUE(touched);
  for (btRigidBody* body : bodies) {
    ASSERT_TRUE(isFinite(*body));
    // The lowest vertex, not the box: a turned mesh's box reaches below the mesh.
    const auto* shape = static_cast<const MeshShape*>(body->getCollisionShape());
    btScalar lowest = 1e30f;
    for (std::size_t v = 0; v < shape->mesh().vertexCount(); ++v) {
      const float* p = shape->mesh().positions().data() + 3 * v;
      lowest = std::min(lowest, (body->getWorldTransform() * (btVector3(p[0], p[1], p[2]) * shape->getLocalScaling())).y());
    }
    EXPECT_GT(lowest, -kRestTolerance) << "a mesh passed into the ground";
    EXPECT_LT(body->getLinearVelocity().length(), 0.05f);
  }
  EXPECT_GT(w.deepestPenetration(), -2 * kRestTolerance);
}

// The three ways of wiring: gpucol::CollisionDispatcher batches the same computation that a stock dispatcher with
// registerWith runs pair by pair, so the worlds stay bit-identical.
TEST(MeshMeshAlgorithm, BatchedDispatchMatchesPairByPair) {
  std::vector<btVector3> positions[2];
  int run = 0;
  for (DispatchKind kind : {DispatchKind::Gpucol, DispatchKind::StockRegistered}) {
    TestWorld w(kind);
    w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
    std::vector<btRigidBody*> bodies;
    for (int i = 0; i < 5; ++i) bodies.push_back(w.add(meshShape(scenes::makeIcosphere(0.4f, 2)), 1, at(0.3f * i, 0.5f + 0.85f * i, 0.1f * i)));
    w.step(120);
    if (kind == DispatchKind::Gpucol) {
      const DispatchStats& stats = static_cast<CollisionDispatcher&>(w.dispatcher()).lastStepStats();
      EXPECT_GT(stats.meshPairs, 0u);
      EXPECT_GT(stats.reducedContacts, 0u);
    }
    for (btRigidBody* body : bodies) positions[run].push_back(body->getWorldTransform().getOrigin());
    ++run;
  }
  for (std::size_t i = 0; i < positions[0].size(); ++i) EXPECT_EQ(positions[0][i], positions[1][i]) << "body " << i;
}

// A concave shape that is not a MeshShape goes to Bullet's default (an empty algorithm for two concave shapes),
// whether it has MeshShape's Bullet type or CUSTOM_CONCAVE_SHAPE_TYPE, while two MeshShapes get MeshMeshAlgorithm.
class ForeignConcave : public btConcaveShape {
 public:
  explicit ForeignConcave(int type) { m_shapeType = type; }
  void processAllTriangles(btTriangleCallback*, const btVector3&, const btVector3&) const override {}
  void getAabb(const btTransform& t, btVector3& lo, btVector3& hi) const override {
    lo = t.getOrigin() - btVector3(1, 1, 1);
    hi = t.getOrigin() + btVector3(1, 1, 1);
  }
  void setLocalScaling(const btVector3&) override {}
  const btVector3& getLocalScaling() const override { return m_scaling; }
  void calculateLocalInertia(btScalar, btVector3& inertia) const override { inertia.setValue(1, 1, 1); }
  const char* getName() const override { return "ForeignConcave"; }

 private:
  btVector3 m_scaling{1, 1, 1};
};

// A concave shape that is not a MeshShape, whatever type number it claims (MeshShape's own, or Bullet's custom
// concave type), is collided with a mesh through its processAllTriangles (concave_partners_test.cpp rests
// bodies on each kind).
TEST(MeshMeshAlgorithm, ForeignConcaveShapesAreCollidedThroughTheirTriangles) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  MeshMeshAlgorithm::registerWith(dispatcher);
  auto mesh = meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
  btCollisionObject meshObject, foreignObject;
  meshObject.setCollisionShape(mesh.get());
  const btCollisionObjectWrapper meshWrap(nullptr, mesh.get(), &meshObject, meshObject.getWorldTransform(), -1, -1);
  const auto release = [&](btCollisionAlgorithm* algorithm) {
    algorithm->~btCollisionAlgorithm();
    dispatcher.freeCollisionAlgorithm(algorithm);
  };
  for (int type : {MeshShape::kMeshShapeType, int(CUSTOM_CONCAVE_SHAPE_TYPE)}) {
    ForeignConcave foreign(type);
    foreignObject.setCollisionShape(&foreign);
    const btCollisionObjectWrapper foreignWrap(nullptr, &foreign, &foreignObject, foreignObject.getWorldTransform(),
                                               -1, -1);
    for (auto [w0, w1] : {std::pair{&meshWrap, &foreignWrap}, std::pair{&foreignWrap, &meshWrap}}) {
      btCollisionAlgorithm* algorithm = dispatcher.findAlgorithm(w0, w1, nullptr, BT_CONTACT_POINT_ALGORITHMS);
      ASSERT_NE(algorithm, nullptr);
      EXPECT_NE(dynamic_cast<MeshMeshAlgorithm*>(algorithm), nullptr) << "type " << type;
      release(algorithm);
    }
  }
  btCollisionAlgorithm* algorithm = dispatcher.findAlgorithm(&meshWrap, &meshWrap, nullptr, BT_CONTACT_POINT_ALGORITHMS);
  EXPECT_NE(dynamic_cast<MeshMeshAlgorithm*>(algorithm), nullptr);
  release(algorithm);
}

// A body whose transform turns NaN: its pairs are skipped (no exception through Bullet, no point left in a
// manifold), and the other bodies go on.
TEST(MeshMeshAlgorithm, NanTransformIsSkippedNotSpread) {
  TestWorld w(DispatchKind::Gpucol);
  w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
  btRigidBody* good = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(-2, 0.5f, 0));
  btRigidBody* bad = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(2, 0.5f, 0));
  w.step(30);
  btTransform nan = bad->getWorldTransform();
  nan.getOrigin().setX(std::numeric_limits<btScalar>::quiet_NaN());
  bad->setWorldTransform(nan);
  EXPECT_NO_THROW(w.step(30));
  EXPECT_TRUE(isFinite(*good));
  EXPECT_NEAR(good->getWorldTransform().getOrigin().y(), 0.5f, kRestTolerance);
}

// Bullet's contact queries outside the simulation (contactPairTest) reach the algorithm too.
TEST(MeshMeshAlgorithm, ContactPairTestReportsMeshContacts) {
  TestWorld w(DispatchKind::Gpucol);
  btRigidBody* a = w.add(meshShape(scenes::makeBox(2, 0.5f, 2)), 0, at(0, -0.5f, 0));
  btRigidBody* b = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 0.45f, 0));
  struct Count : btCollisionWorld::ContactResultCallback {
    int points = 0;
    btScalar deepest = 0;
    btScalar addSingleResult(btManifoldPoint& p, const btCollisionObjectWrapper*, int, int, const btCollisionObjectWrapper*, int,
                             int) override {
      ++points;
      deepest = std::min(deepest, p.getDistance());
      return 0;
    }
  } count;
  w.world().contactPairTest(a, b, count);
  EXPECT_GT(count.points, 0);
  EXPECT_NEAR(count.deepest, -0.05f, 1e-5f);
}

}  // namespace
}  // namespace gpucol::test
