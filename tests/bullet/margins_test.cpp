// Collision margins of MeshShape: a margin only makes bodies rest that much further apart. Boxes and tori of
// meshes rest at the gap their margins ask for, at several margins, beside the same shapes as
// btGImpactMeshShape (Bullet's own triangle-mesh shape with margins), and on foreign concave shapes whose
// margin counts too.
#include <gtest/gtest.h>

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <cmath>
#include <functional>

#include "bullet/test_world.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::test {
namespace {

// The margins tried: none, a few millimetres, GImpact's default and beyond it, on bodies of about 1 m.
const btScalar kMargins[] = {0.0f, 0.002f, 0.005f, 0.01f, 0.02f, 0.04f};

// A resting body sits within Bullet's allowed penetration (its slop) of where its contacts put it; gravity
// presses a little in every step. A millimetre is far below what any margin here changes.
constexpr btScalar kRestTolerance = 0.001f;

// GImpact's resting bodies sink a few millimetres into their margins (its contacts from clipped triangles
// are fewer and less deep than the gap), so it is held to a looser bound: the same rest, not the same bits.
constexpr btScalar kGImpactTolerance = 0.005f;

// A transform turning the torus's z axis onto the world's y axis (lying flat), at (0, y, 0).
btTransform lyingFlatAt(btScalar y) {
  return btTransform(btQuaternion(btVector3(1, 0, 0), -SIMD_HALF_PI), btVector3(0, y, 0));
}

// Where a body comes to rest: the world is stepped 300 steps at 60 Hz; the body must be still and upright.
struct Rest {
  btScalar height = 0;
  btScalar speed = 0;
  btScalar upright = 0;  // the cosine between the body's start and end orientation of its y (or torus axis)
};

Rest restOf(TestWorld& w, btRigidBody* body, const btVector3& axis) {
  const btVector3 before = body->getWorldTransform().getBasis() * axis;
  w.step(300);
  Rest r;
  r.height = body->getWorldTransform().getOrigin().y();
  r.speed = body->getLinearVelocity().length() + body->getAngularVelocity().length();
  r.upright = before.dot(body->getWorldTransform().getBasis() * axis);
  EXPECT_TRUE(isFinite(*body));
  return r;
}

// A box (half size 0.5) on a slab whose top is at y = 0, both with `margin`; the same pair of shapes as
// MeshShape bodies through gpucol's dispatcher and as GImpact bodies through Bullet's.
Rest meshBoxOnSlab(btScalar margin) {
  TestWorld w(DispatchKind::Gpucol);
  auto slab = meshShape(scenes::makeBox(5, 0.5f, 5));
  auto box = meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
  slab->setMargin(margin);
  box->setMargin(margin);
  w.add(slab, 0, at(0, -0.5f, 0));
  return restOf(w, w.add(box, 1, at(0.1f, 0.5f + 3 * margin + 0.01f, -0.05f)), btVector3(0, 1, 0));
}

// GImpact bodies in a world of their own: btCollisionDispatcher with GImpact's algorithm registered.
struct GImpactWorld {
  GImpactWorld() : world(DispatchKind::Stock) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
  }
  btRigidBody* add(const TriangleMesh& mesh, btScalar margin, btScalar mass, const btTransform& transform) {
    auto peer = std::make_shared<scenes::GImpactMesh>(mesh);
    peer->shape()->setMargin(margin);
    peer->shape()->updateBound();
    peers.push_back(peer);
    // The world keeps the shape alive through a pointer that shares the peer's ownership.
    return world.add(std::shared_ptr<btCollisionShape>(peer, peer->shape()), mass, transform);
  }
  TestWorld world;
  std::vector<std::shared_ptr<scenes::GImpactMesh>> peers;
};

Rest gimpactBoxOnSlab(btScalar margin) {
  GImpactWorld g;
  g.add(scenes::makeBox(5, 0.5f, 5), margin, 0, at(0, -0.5f, 0));
  btRigidBody* box =
      g.add(scenes::makeBox(0.5f, 0.5f, 0.5f), margin, 1, at(0.1f, 0.5f + 3 * margin + 0.01f, -0.05f));
  return restOf(g.world, box, btVector3(0, 1, 0));
}

TEST(Margins, MeshBoxRestsTwoMarginsAboveMeshSlabAsGImpactDoes) {
  for (btScalar margin : kMargins) {
    SCOPED_TRACE("margin " + std::to_string(margin));
    const Rest mesh = meshBoxOnSlab(margin);
    const Rest gimpact = gimpactBoxOnSlab(margin);
    EXPECT_NEAR(mesh.height, 0.5f + 2 * margin, kRestTolerance);
    EXPECT_LT(mesh.speed, 1e-2f);
    EXPECT_GT(mesh.upright, 0.9999f);
    // GImpact's triangles with margins rest about the same distance apart.
    EXPECT_NEAR(gimpact.height, mesh.height, kGImpactTolerance);
    EXPECT_LT(gimpact.speed, 1e-2f);
  }
}

// Two tori lying flat on each other, axes on one line: the upper one rests on the lower one's top ring, its
// centre 2 * minor + 2 * margin above the lower one's (the tube's top and bottom rings are vertices of the
// mesh: 16 tube segments). Before margins gave contacts, tori with margins of 2 mm or more fell through each
// other.
constexpr float kMajor = 0.5f, kMinor = 0.15f;

Rest meshTorusOnTorus(btScalar margin) {
  TestWorld w(DispatchKind::Gpucol);
  auto lower = meshShape(scenes::makeTorus(kMajor, kMinor, 48, 16));
  auto upper = meshShape(scenes::makeTorus(kMajor, kMinor, 48, 16));
  lower->setMargin(margin);
  upper->setMargin(margin);
  w.add(lower, 0, lyingFlatAt(0));
  btRigidBody* body = w.add(upper, 1, lyingFlatAt(2 * kMinor + 3 * margin + 0.01f));
  return restOf(w, body, btVector3(0, 0, 1));
}

Rest gimpactTorusOnTorus(btScalar margin) {
  GImpactWorld g;
  g.add(scenes::makeTorus(kMajor, kMinor, 48, 16), margin, 0, lyingFlatAt(0));
  btRigidBody* body =
      g.add(scenes::makeTorus(kMajor, kMinor, 48, 16), margin, 1, lyingFlatAt(2 * kMinor + 3 * margin + 0.01f));
  return restOf(g.world, body, btVector3(0, 0, 1));
}

TEST(Margins, MeshTorusRestsOnMeshTorusTwoMarginsApartAsGImpactDoes) {
  for (btScalar margin : kMargins) {
    SCOPED_TRACE("margin " + std::to_string(margin));
    const Rest mesh = meshTorusOnTorus(margin);
    const Rest gimpact = gimpactTorusOnTorus(margin);
    EXPECT_NEAR(mesh.height, 2 * kMinor + 2 * margin, kRestTolerance);
    EXPECT_LT(mesh.speed, 1e-2f);
    EXPECT_GT(mesh.upright, 0.9999f);
    EXPECT_NEAR(gimpact.height, mesh.height, kGImpactTolerance);
  }
}

// A foreign concave shape's margin counts as a MeshShape's: a mesh box on Bullet's own BVH triangle mesh rests
// the sum of both margins above it, in both pair orders.
TEST(Margins, ForeignConcaveShapesMarginCounts) {
  for (bool floorFirst : {true, false}) {
    for (btScalar margin : {0.0f, 0.01f, 0.03f}) {
      SCOPED_TRACE("margin " + std::to_string(margin) + (floorFirst ? ", floor first" : ", floor last"));
      TestWorld w(DispatchKind::Gpucol);
      auto arrays = std::make_shared<btTriangleMesh>();
      arrays->addTriangle(btVector3(-10, 0, -10), btVector3(-10, 0, 10), btVector3(10, 0, 10));
      arrays->addTriangle(btVector3(-10, 0, -10), btVector3(10, 0, 10), btVector3(10, 0, -10));
      std::shared_ptr<btBvhTriangleMeshShape> floor(new btBvhTriangleMeshShape(arrays.get(), true),
                                                    [keep = arrays](btBvhTriangleMeshShape* s) { delete s; });
      floor->setMargin(margin);
      auto box = meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
      box->setMargin(margin / 2);
      if (floorFirst) w.add(floor, 0, at(0, 0, 0));
      btRigidBody* body = w.add(box, 1, at(0, 0.5f + 2 * margin + 0.01f, 0));
      if (!floorFirst) w.add(floor, 0, at(0, 0, 0));
      const Rest r = restOf(w, body, btVector3(0, 1, 0));
      EXPECT_NEAR(r.height, 0.5f + 1.5f * margin, kRestTolerance);
      EXPECT_LT(r.speed, 1e-2f);
    }
  }
}

}  // namespace
}  // namespace gpucol::test
