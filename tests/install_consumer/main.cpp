// Uses the installed gpucol the way the README shows: a world with gpucol's dispatcher and broad phase, a mesh box
// dropped on a static mesh ground; checks that it comes to rest on it. Also runs the direct query.
#include <btBulletDynamicsCommon.h>
#include <gpucol/gpucol.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

namespace {

// A closed box mesh of half extents (hx, hy, hz), counter-clockwise seen from outside.
std::shared_ptr<const gpucol::TriangleMesh> boxMesh(float hx, float hy, float hz) {
  std::vector<float> xyz;
  for (int i = 0; i < 8; ++i) xyz.insert(xyz.end(), {i & 1 ? hx : -hx, i & 2 ? hy : -hy, i & 4 ? hz : -hz});
  const std::vector<std::uint32_t> indices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                              2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  return std::make_shared<const gpucol::TriangleMesh>(gpucol::TriangleMesh::fromArrays(xyz, indices, "box"));
}

}  // namespace

int main() {
  gpucol::Config config;
  btDefaultCollisionConfiguration collisionConfiguration;
  gpucol::CollisionDispatcher dispatcher(&collisionConfiguration, config);
  gpucol::GridBroadphase broadphase(config);
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &collisionConfiguration);
  world.setGravity(btVector3(0, -10, 0));

  gpucol::MeshShape groundShape(boxMesh(5, 0.5f, 5)), boxShape(boxMesh(0.5f, 0.5f, 0.5f));
  btRigidBody ground(0, nullptr, &groundShape);
  ground.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, -0.5f, 0)));
  btVector3 inertia;
  boxShape.calculateLocalInertia(1, inertia);
  btRigidBody box(1, nullptr, &boxShape, inertia);
  box.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 1, 0)));
  world.addRigidBody(&ground);
  world.addRigidBody(&box);
  for (int step = 0; step < 240; ++step) world.stepSimulation(1.0f / 60);
  const float y = box.getWorldTransform().getOrigin().y();

  // Saved and loaded back as MeshShape bodies (gpucol::WorldImporter links Bullet's world importer).
  btDefaultSerializer serializer;
  world.serialize(&serializer);
  std::vector<char> file(serializer.getBufferPointer(),
                         serializer.getBufferPointer() + serializer.getCurrentBufferSize());
  gpucol::WorldImporter importer(nullptr, config);
  const bool loaded = importer.loadFileFromMemory(file.data(), int(file.size()));
  const int meshes = importer.meshShapesImported(), bodies = importer.getNumRigidBodies();
  importer.deleteAllData();
  if (!loaded || meshes != 2 || bodies != 2) {
    std::cerr << "install check: the saved world should load back as 2 MeshShape bodies; got " << bodies
              << " bodies and " << meshes << " MeshShapes\n";
    return 1;
  }
  world.removeRigidBody(&box);
  world.removeRigidBody(&ground);
  if (!(std::abs(y - 0.5f) < 0.01f)) {
    std::cerr << "install check: the mesh box should rest at y = 0.5 on the mesh ground, it is at " << y << "\n";
    return 1;
  }

  const gpucol::MeshPairResult result = gpucol::collideMeshes(
      boxShape, btTransform::getIdentity(), boxShape, btTransform(btQuaternion::getIdentity(), btVector3(0.5f, 0.5f, 0.5f)));
  if (result.intersectingPairs.empty()) {
    std::cerr << "install check: overlapping boxes gave no intersecting triangle pair\n";
    return 1;
  }
  std::cout << "install check: find_package(gpucol) works; a mesh box rests at y = " << y
            << " in a world with "
            << "gpucol::CollisionDispatcher and gpucol::GridBroadphase; the direct query finds "
            << result.intersectingPairs.size()
            << " intersecting triangle pairs; a saved world loads back through "
            << "gpucol::WorldImporter\n";
  return 0;
}
