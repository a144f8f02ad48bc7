// principalMeshBody (issue 54): a mesh not in its principal frame (an L turned and off centre, scaled) gets
// the principal frame, centre of mass and moments that Bullet's own
// btCompoundShape::calculatePrincipalAxisTransform gives the same solid built of two boxes; its triangles
// stay where they were; and it tumbles in space as that compound does, where the tensor's diagonal
// (MeshShape::calculateLocalInertia) does not.
#include <btBulletDynamicsCommon.h>
#include <gpucol/gpucol.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>

#include "scenes/procedural_meshes.h"

namespace gpucol {
namespace {

constexpr float kSize = 0.9f, kDepth = 0.3f, kScale = 1.5f;

/// The turn and shift the L is given inside its mesh frame.
btTransform lFrame() {
  return btTransform(btQuaternion(btVector3(1, 2, 0.5f).normalized(), 0.7f), btVector3(0.3f, -0.2f, 0.5f));
}

/// The L of makeLShape(kSize, kDepth), turned and shifted by lFrame(), as a MeshShape scaled by kScale.
std::unique_ptr<MeshShape> lShape() {
  const btTransform f = lFrame();
  std::array<double, 9> rotation{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation[3 * r + c] = f.getBasis()[r][c];
  }
  const TriangleMesh moved =
      scenes::makeLShape(kSize, kDepth)
          .transformed(rotation, {f.getOrigin().x(), f.getOrigin().y(), f.getOrigin().z()});
  auto shape = std::make_unique<MeshShape>(std::make_shared<const TriangleMesh>(moved));
  shape->setLocalScaling(btVector3(kScale, kScale, kScale));
  shape->setMargin(0.004f);
  return shape;
}

/// The same solid as Bullet's compound of two boxes (makeLShape's bar along x and the upright above it), with
/// masses in proportion to their volumes.
struct LCompound {
  LCompound() {
    const float s = kSize * kScale, w = s / 3, d = kDepth * kScale;
    const btTransform f(lFrame().getBasis(), lFrame().getOrigin() * kScale);
    boxes[0] = std::make_unique<btBoxShape>(btVector3(s / 2, w / 2, d / 2));
    boxes[1] = std::make_unique<btBoxShape>(btVector3(w / 2, (s - w) / 2, d / 2));
    compound.addChildShape(f * btTransform(btQuaternion::getIdentity(), btVector3(0, w / 2 - s / 2, 0)),
                           boxes[0].get());
    compound.addChildShape(f * btTransform(btQuaternion::getIdentity(), btVector3(w / 2 - s / 2, w / 2, 0)),
                           boxes[1].get());
    masses = {s * w, w * (s - w)};
  }
  /// Bullet's principal frame and moments of the compound for a body of `mass` (the boxes' masses in
  /// proportion to their volumes).
  void principalAxes(btScalar mass, btTransform& principal, btVector3& inertia) {
    const btScalar total = masses[0] + masses[1];
    const btScalar scaled[2] = {masses[0] * mass / total, masses[1] * mass / total};
    compound.calculatePrincipalAxisTransform(scaled, principal, inertia);
  }
  std::unique_ptr<btBoxShape> boxes[2];
  btCompoundShape compound;
  std::array<btScalar, 2> masses{};
};

TEST(PrincipalMeshBody, MatchesBulletsPrincipalAxisTransformOfTheSameSolid) {
  const std::unique_ptr<MeshShape> shape = lShape();
  const btScalar mass = 3;
  const PrincipalMeshBody body = principalMeshBody(*shape, mass);

  LCompound reference;
  btTransform principal;
  btVector3 inertia;
  reference.principalAxes(mass, principal, inertia);

  // The same centre of mass and the same moments (Bullet's come in an order of its own).
  EXPECT_LT((body.principal.getOrigin() - principal.getOrigin()).length(), 1e-5f);
  std::array<btScalar, 3> ours{body.inertia.x(), body.inertia.y(), body.inertia.z()};
  std::array<btScalar, 3> bullets{inertia.x(), inertia.y(), inertia.z()};
  std::sort(ours.begin(), ours.end());
  std::sort(bullets.begin(), bullets.end());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(ours[i], bullets[i], 1e-4f * bullets[2]) << i;
  // Each of our principal axes is one of Bullet's (up to sign): the frames agree where the moments are
  // distinct.
  for (int axis = 0; axis < 3; ++axis) {
    const btVector3 a = body.principal.getBasis().getColumn(axis);
    btScalar best = 0;
    for (int other = 0; other < 3; ++other)
      best = std::max(best, btFabs(a.dot(principal.getBasis().getColumn(other))));
    EXPECT_GT(best, 0.9999f) << "axis " << axis;
  }
  EXPECT_FLOAT_EQ(body.mass, mass);
  EXPECT_FLOAT_EQ(body.shape->getMargin(), 0.004f);
  EXPECT_EQ(body.shape->getLocalScaling(), btVector3(1, 1, 1));

  // Every triangle stays where it was: the principal shape placed by bodyTransform covers the original's
  // vertices.
  const btTransform meshWorld(btQuaternion(btVector3(0, 1, 0), 0.4f), btVector3(5, 1, -2));
  const btTransform bodyWorld = body.bodyTransform(meshWorld);
  const TriangleMesh& original = shape->mesh();
  const TriangleMesh& moved = body.shape->mesh();
  ASSERT_EQ(moved.vertexCount(), original.vertexCount());
  for (std::size_t v = 0; v < original.vertexCount(); ++v) {
    const float* p = &original.positions()[3 * v];
    const float* q = &moved.positions()[3 * v];
    const btVector3 before = meshWorld(btVector3(p[0], p[1], p[2]) * shape->getLocalScaling());
    const btVector3 after = bodyWorld(btVector3(q[0], q[1], q[2]));
    EXPECT_LT((before - after).length(), 1e-5f) << "vertex " << v;
  }
  const btTransform back = body.meshTransform(bodyWorld);
  EXPECT_LT((back.getOrigin() - meshWorld.getOrigin()).length(), 1e-5f);
}

/// Orientation of the L's mesh frame after `steps` steps in a world without gravity, the body started at the
/// identity turning at `spin`; the inertia the body gets is the caller's.
btQuaternion tumble(btCollisionShape* shape, btScalar mass, const btVector3& inertia,
                    const btTransform& start, const btTransform& frameInBody, const btVector3& spin,
                    int steps) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, 0, 0));
  btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
  info.m_startWorldTransform = start;
  btRigidBody body(info);
  body.setActivationState(DISABLE_DEACTIVATION);
  // Bullet's gyroscopic term, so that a body spinning about an axis that is not principal tumbles.
  body.setFlags(body.getFlags() | BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
  body.setAngularVelocity(spin);
  world.addRigidBody(&body);
  for (int i = 0; i < steps; ++i) world.stepSimulation(btScalar(1) / 120, 0);
  const btQuaternion out = (body.getWorldTransform() * frameInBody).getRotation();
  world.removeRigidBody(&body);
  return out;
}

TEST(PrincipalMeshBody, TumblesAsBulletsCompoundOfTheSameSolidDoes) {
  const std::unique_ptr<MeshShape> shape = lShape();
  const btScalar mass = 3;
  const PrincipalMeshBody body = principalMeshBody(*shape, mass);
  LCompound reference;
  btTransform principal;
  btVector3 inertia;
  reference.principalAxes(mass, principal, inertia);
  // Bullet's recipe: the children moved into the principal frame, the body placed at principal.
  btCompoundShape centred;
  for (int i = 0; i < 2; ++i) {
    centred.addChildShape(principal.inverse() * reference.compound.getChildTransform(i),
                          reference.compound.getChildShape(i));
  }
  const btVector3 spin(2, 5, 1);
  const int steps = 240;
  const btQuaternion expected = tumble(&centred, mass, inertia, principal, principal.inverse(), spin, steps);
  const btQuaternion ours =
      tumble(body.shape.get(), mass, body.inertia, body.principal, body.principal.inverse(), spin, steps);
  EXPECT_GT(btFabs(ours.dot(expected)), 0.9995f) << "the two bodies turned apart";
  // The shape as it is, with the diagonal of its tensor in its own frame, tumbles elsewhere.
  btVector3 diagonal;
  shape->calculateLocalInertia(mass, diagonal);
  const btQuaternion approximate = tumble(shape.get(), mass, diagonal, btTransform::getIdentity(),
                                          btTransform::getIdentity(), spin, steps);
  EXPECT_LT(btFabs(approximate.dot(expected)), 0.999f) << "the diagonal alone should not match";
}

TEST(PrincipalMeshBody, RefusesAnOpenMeshAndABadMass) {
  const TriangleMesh box = scenes::makeBox(1, 1, 1, 1);
  std::vector<float> xyz = box.positions();
  std::vector<std::uint32_t> open(box.indices().begin(), box.indices().end() - 3);
  MeshShape openShape(std::make_shared<const TriangleMesh>(TriangleMesh::fromArrays(xyz, open, "open box")));
  EXPECT_THROW(principalMeshBody(openShape, 1), MeshError);
  MeshShape closed(std::make_shared<const TriangleMesh>(box));
  EXPECT_THROW(principalMeshBody(closed, 0), MeshError);
  EXPECT_THROW(principalMeshBody(closed, btScalar(NAN)), MeshError);
}

}  // namespace
}  // namespace gpucol
