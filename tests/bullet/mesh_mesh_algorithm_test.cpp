// MeshMeshAlgorithm in worlds: a mesh on a btStaticPlaneShape, on a btBvhTriangleMeshShape floor and on a mesh
// ground comes to rest at the analytic height; the three ways of wiring gpucol into a dispatcher agree.
#include <gtest/gtest.h>

#include "bullet/test_world.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::test {
namespace {

TEST(MeshMeshAlgorithm, BoxRestsOnMeshGround) {
  for (DispatchKind kind : {DispatchKind::Gpucol, DispatchKind::StockRegistered}) {
    TestWorld w(kind);
    w.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
    btRigidBody* box = w.add(meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f)), 1, at(0, 0.6f, 0));
    w.step(240);
    const btScalar y = box->getWorldTransform().getOrigin().y();
    std::cout << "box centre y " << y << " penetration " << w.deepestPenetration() << "\n";
    EXPECT_NEAR(y, 0.5f, 0.02f);
    EXPECT_TRUE(isFinite(*box));
  }
}

}  // namespace
}  // namespace gpucol::test
