// A MeshShape collides with every concave shape Bullet has (issue 52): a heightfield, a scaled BVH, a
// multimaterial BVH, a GImpact mesh and a user's own concave shape, each a flat ground at y = 0 (some with
// local scaling). A MeshShape cube comes to rest on each where a btBoxShape of the same size rests on the same
// ground, and a MeshShape torus lying flat rests on it instead of falling through.
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btMultimaterialTriangleMeshShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "scenes/procedural_meshes.h"
#include "test_world.h"

namespace gpucol {
namespace {

/// A 20 × 20 m square at y = 0 of two triangles, as Bullet's mesh interface (float vertices, int indices).
struct GroundMesh {
  float vertices[12] = {-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10};
  int faces[6] = {0, 2, 1, 0, 3, 2};
  btTriangleIndexVertexArray array{2, faces, 3 * sizeof(int), 4, vertices, 3 * sizeof(float)};
};

/// A user's own concave shape: the same square, given by processAllTriangles alone.
class UserGround : public btConcaveShape {
 public:
  UserGround() { m_shapeType = CUSTOM_CONCAVE_SHAPE_TYPE; }
  void processAllTriangles(btTriangleCallback* callback, const btVector3&, const btVector3&) const override {
    btVector3 t0[3] = {corner(0), corner(2), corner(1)}, t1[3] = {corner(0), corner(3), corner(2)};
    callback->processTriangle(t0, 0, 0);
    callback->processTriangle(t1, 0, 1);
  }
  void getAabb(const btTransform& t, btVector3& lo, btVector3& hi) const override {
    btTransformAabb(btVector3(-10, 0, -10) * m_scale, btVector3(10, 0, 10) * m_scale, getMargin(), t, lo, hi);
  }
  void setLocalScaling(const btVector3& scaling) override { m_scale = scaling; }
  const btVector3& getLocalScaling() const override { return m_scale; }
  void calculateLocalInertia(btScalar, btVector3& inertia) const override { inertia.setZero(); }
  const char* getName() const override { return "UserGround"; }

 private:
  btVector3 corner(int i) const {
    static const btVector3 c[4] = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
    return c[i] * m_scale;
  }
  btVector3 m_scale{1, 1, 1};
};

/// A flat ground at y = 0 of one concave kind, and what it needs kept alive.
struct Ground {
  std::string name;
  std::shared_ptr<btCollisionShape> shape;
  std::shared_ptr<void> keep;  // mesh data or heights the shape points into
  // Bullet's convex–concave algorithm takes CUSTOM_CONCAVE_SHAPE_TYPE for its SDF shape (the same number in
  // 3.24) and reads a user's shape as one: a btBoxShape cannot be the reference there.
  bool boxReference = true;
};

std::vector<Ground> grounds() {
  std::vector<Ground> all;
  {
    // 21 × 21 sticks of 1 m, all at height 0 (the shape's origin is mid-way between its min and max height).
    auto heights = std::make_shared<std::vector<float>>(21 * 21, 0.0f);
    auto shape = std::make_shared<btHeightfieldTerrainShape>(21, 21, heights->data(), -1.0f, 1.0f, 1, false);
    all.push_back({"btHeightfieldTerrainShape", shape, heights});
  }
  {
    // A unit-scale square scaled by 2 in x and z.
    auto mesh = std::make_shared<GroundMesh>();
    for (float& v : mesh->vertices) v *= 0.5f;
    auto bvh = std::make_shared<btBvhTriangleMeshShape>(&mesh->array, true);
    auto shape = std::make_shared<btScaledBvhTriangleMeshShape>(bvh.get(), btVector3(2, 1, 2));
    all.push_back({"btScaledBvhTriangleMeshShape", shape, std::make_shared<std::pair<decltype(mesh), decltype(bvh)>>(mesh, bvh)});
  }
  {
    auto mesh = std::make_shared<GroundMesh>();
    all.push_back({"btMultimaterialTriangleMeshShape",
                   std::make_shared<btMultimaterialTriangleMeshShape>(&mesh->array, true), mesh});
  }
  {
    auto mesh = std::make_shared<GroundMesh>();
    auto shape = std::make_shared<btGImpactMeshShape>(&mesh->array);
    shape->updateBound();
    all.push_back({"btGImpactMeshShape", shape, mesh});
  }
  {
    // Scaled by 0.5 in x and z: still 10 × 10 m, and the cube and torus fit.
    auto shape = std::make_shared<UserGround>();
    shape->setLocalScaling(btVector3(0.5f, 1, 0.5f));
    all.push_back({"a user's btConcaveShape (CUSTOM_CONCAVE_SHAPE_TYPE)", shape, nullptr, false});
  }
  return all;
}

/// The height a body dropped from y = `from` comes to rest at on `ground` (2 s at 60 Hz), or NaN if it fell
/// below y = -1.
btScalar restHeight(const Ground& ground, std::shared_ptr<btCollisionShape> body, btScalar from,
                    const btQuaternion& turn = btQuaternion::getIdentity()) {
  test::TestWorld world(test::DispatchKind::Gpucol);
  world.add(ground.shape, 0, btTransform::getIdentity());
  btRigidBody* b = world.add(std::move(body), 1, btTransform(turn, btVector3(0.2f, from, -0.1f)));
  for (int step = 0; step < 120; ++step) {
    world.step(1);
    if (b->getWorldTransform().getOrigin().y() < -1) return btScalar(NAN);
  }
  return b->getWorldTransform().getOrigin().y();
}

TEST(ConcavePartners, MeshCubeAndTorusRestOnEveryConcaveShapeAsABoxDoes) {
  for (const Ground& ground : grounds()) {
    SCOPED_TRACE(ground.name);
    // Where Bullet's box cannot be the reference, its rest height on every other ground (centre at 0.5 m
    // plus the margins' few millimetres) stands in.
    const btScalar box = ground.boxReference
                             ? restHeight(ground, std::make_shared<btBoxShape>(btVector3(0.5f, 0.5f, 0.5f)), 0.7f)
                             : btScalar(0.5);
    ASSERT_FALSE(std::isnan(box)) << "Bullet's own box fell through";
    EXPECT_NEAR(box, 0.5f, 0.05f);
    const btScalar cube = restHeight(
        ground, std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(0.5f, 0.5f, 0.5f, 2))),
        0.7f);
    ASSERT_FALSE(std::isnan(cube)) << "the MeshShape cube fell through";
    // Both rest with their bottom face on the ground: the centres agree within the margins' few centimetres.
    EXPECT_NEAR(cube, box, 0.05f);
    // A torus of tube radius 0.15 lying flat (its axis, z, turned to y) rests on its tube.
    const btScalar torus = restHeight(
        ground, std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeTorus(0.5f, 0.15f, 24, 12))),
        0.5f, btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI));
    ASSERT_FALSE(std::isnan(torus)) << "the MeshShape torus fell through";
    EXPECT_NEAR(torus, 0.15f, 0.05f);
  }
}

}  // namespace
}  // namespace gpucol
