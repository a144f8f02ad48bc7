// Worlds with meshes save and load (issue 54): world->serialize writes each MeshShape in a form Debian's
// stock btBulletWorldImporter brings back with its triangles, scaling, margin, mass and transform (compound
// children too); gpucol::WorldImporter brings them back as MeshShapes with the saved inertia, and the loaded
// world steps as the saved one; a file of GImpact bodies written by stock Bullet loads through
// gpucol::WorldImporter as MeshShape bodies.
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletWorldImporter/btBulletWorldImporter.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "scenes/procedural_meshes.h"
#include "test_world.h"

namespace gpucol {
namespace {

using Triangles = std::map<std::pair<int, int>, std::vector<btScalar>>;

/// Every triangle `shape` gives (in its scaled frame), by (part, index).
Triangles trianglesOf(const btConcaveShape& shape) {
  struct Collector : btTriangleCallback {
    void processTriangle(btVector3* triangle, int part, int index) override {
      std::vector<btScalar>& corners = out[{part, index}];
      for (int k = 0; k < 3; ++k) {
        for (int axis = 0; axis < 3; ++axis) corners.push_back(triangle[k][axis]);
      }
    }
    Triangles out;
  } collector;
  const btVector3 big(1e6f, 1e6f, 1e6f);
  shape.processAllTriangles(&collector, -big, big);
  return collector.out;
}

/// True when both give the same triangles under the same ids, corners within `tolerance`.
::testing::AssertionResult sameTriangles(const Triangles& a, const Triangles& b, btScalar tolerance) {
  if (a.size() != b.size())
    return ::testing::AssertionFailure() << a.size() << " triangles against " << b.size();
  for (const auto& [id, corners] : a) {
    const auto other = b.find(id);
    if (other == b.end())
      return ::testing::AssertionFailure() << "no triangle " << id.first << "/" << id.second;
    for (std::size_t i = 0; i < corners.size(); ++i) {
      if (btFabs(corners[i] - other->second[i]) > tolerance) {
        return ::testing::AssertionFailure() << "triangle " << id.first << "/" << id.second << " coordinate "
                                             << i << ": " << corners[i] << " against " << other->second[i];
      }
    }
  }
  return ::testing::AssertionSuccess();
}

/// The world as a .bullet file in memory.
std::vector<char> save(btDynamicsWorld& world,
                       const std::function<void(btDefaultSerializer&)>& names = nullptr) {
  btDefaultSerializer serializer;
  if (names) names(serializer);
  world.serialize(&serializer);
  const char* bytes = reinterpret_cast<const char*>(serializer.getBufferPointer());
  return std::vector<char>(bytes, bytes + serializer.getCurrentBufferSize());
}

/// A mesh of two parts (a box and a torus beside it), each part with its own vertices.
TriangleMesh twoPartMesh() {
  const TriangleMesh a = scenes::makeBox(0.3f, 0.2f, 0.25f, 2), b = scenes::makeTorus(0.3f, 0.1f, 16, 8);
  std::vector<float> xyz = a.positions();
  for (std::size_t i = 0; i < b.positions().size(); ++i)
    xyz.push_back(b.positions()[i] + (i % 3 == 0 ? 0.8f : 0.0f));
  std::vector<std::uint32_t> indices = a.indices();
  for (std::uint32_t i : b.indices()) indices.push_back(i + std::uint32_t(a.vertexCount()));
  return TriangleMesh::fromParts(std::move(xyz), std::move(indices),
                                 {{0, std::uint32_t(a.triangleCount()), 0, std::uint32_t(a.vertexCount())},
                                  {std::uint32_t(a.triangleCount()), std::uint32_t(b.triangleCount()),
                                   std::uint32_t(a.vertexCount()), std::uint32_t(b.vertexCount())}},
                                 "two parts");
}

/// A world of MeshShape bodies of every kind: a static scaled slab with a margin, a scaled dynamic torus with
/// a margin (named "torus"), a mesh of two parts, one shape shared by two bodies, a compound holding a
/// MeshShape and a box whose inertia the user chose, and that MeshShape as a body of its own.
struct MeshWorld {
  MeshWorld() : world(test::DispatchKind::Gpucol) {
    slab = test::meshShape(scenes::makeBox(2, 0.25f, 2, 2));
    slab->setLocalScaling(btVector3(2, 1, 2));
    slab->setMargin(0.01f);
    world.add(slab, 0, test::at(0, -0.25f, 0));
    torus = test::meshShape(scenes::makeTorus(0.4f, 0.12f, 24, 12));
    torus->setLocalScaling(btVector3(1, 1.5f, 1));
    torus->setMargin(0.02f);
    world.add(torus, 2,
              btTransform(btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI), btVector3(-1.5f, 0.4f, 0.5f)));
    parts = test::meshShape(twoPartMesh());
    world.add(parts, 1.5f, btTransform(btQuaternion(btVector3(0, 1, 0), 0.3f), btVector3(1, 0.6f, -1)));
    shared = test::meshShape(scenes::makeBox(0.25f, 0.25f, 0.25f, 1));
    world.add(shared, 0.5f, test::at(0, 0.3f, 1.5f));
    world.add(shared, 0.5f, test::at(0.2f, 0.9f, 1.5f));
    compoundMesh = test::meshShape(scenes::makeIcosphere(0.3f, 2));
    box = std::make_shared<btBoxShape>(btVector3(0.1f, 0.4f, 0.1f));
    compound = std::make_shared<btCompoundShape>();
    compound->addChildShape(test::at(0, 0.1f, 0), compoundMesh.get());
    compound->addChildShape(test::at(0.35f, 0, 0), box.get());
    btRigidBody* body = world.add(compound, 3, test::at(1.5f, 0.6f, 1.5f));
    body->setMassProps(3, btVector3(0.5f, 0.6f, 0.7f));
    body->updateInertiaTensor();
    // The compound's MeshShape, scaled, is a body's shape too: its record is read twice by the importers (a
    // scaled BVH mesh read twice by the stock importer comes back unscaled the second time).
    compoundMesh->setLocalScaling(btVector3(1.2f, 0.8f, 1.2f));
    world.add(compoundMesh, 1, test::at(-1.5f, 0.6f, -1.5f));
  }
  test::TestWorld world;
  std::shared_ptr<MeshShape> slab, torus, parts, shared, compoundMesh;
  std::shared_ptr<btBoxShape> box;
  std::shared_ptr<btCompoundShape> compound;
};

/// A fresh world to load into, and what it needs; bodies and shapes belong to the importer.
struct LoadWorld {
  explicit LoadWorld(bool gpucol) {
    if (gpucol) {
      dispatcher = std::make_unique<CollisionDispatcher>(&configuration);
    } else {
      dispatcher = std::make_unique<btCollisionDispatcher>(&configuration);
    }
    world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), &broadphase, &solver, &configuration);
  }
  ~LoadWorld() {
    for (int i = world->getNumCollisionObjects() - 1; i >= 0; --i) {
      world->removeCollisionObject(world->getCollisionObjectArray()[i]);
    }
  }
  btDefaultCollisionConfiguration configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
};

btRigidBody* bodyOf(btDynamicsWorld& world, int i) {
  return btRigidBody::upcast(world.getCollisionObjectArray()[i]);
}

void expectSameBody(const btRigidBody& saved, const btRigidBody& loaded) {
  EXPECT_EQ(saved.getWorldTransform().getOrigin(), loaded.getWorldTransform().getOrigin());
  EXPECT_EQ(saved.getWorldTransform().getRotation(), loaded.getWorldTransform().getRotation());
  EXPECT_FLOAT_EQ(saved.getInvMass(), loaded.getInvMass());
  EXPECT_EQ(saved.isStaticObject(), loaded.isStaticObject());
}

TEST(WorldSerialization, StockImporterBringsBackEveryMeshBody) {
  MeshWorld saved;
  std::vector<char> file = save(saved.world.world());
  LoadWorld load(false);
  btBulletWorldImporter importer(load.world.get());
  ASSERT_TRUE(importer.loadFileFromMemory(file.data(), int(file.size())));
  btDiscreteDynamicsWorld& original = saved.world.world();
  ASSERT_EQ(load.world->getNumCollisionObjects(), original.getNumCollisionObjects());
  for (int i = 0; i < original.getNumCollisionObjects(); ++i) {
    SCOPED_TRACE("body " + std::to_string(i));
    const btRigidBody& before = *bodyOf(original, i);
    const btRigidBody& after = *bodyOf(*load.world, i);
    expectSameBody(before, after);
    // Each MeshShape comes back as a compound holding one BVH mesh at the identity, with its triangles (the
    // same parts and indices), its scaling (the BVH mesh's) and its margin.
    const auto check = [](const btCollisionShape& mesh, const btCollisionShape& loaded) {
      ASSERT_EQ(loaded.getShapeType(), COMPOUND_SHAPE_PROXYTYPE);
      const auto& compound = static_cast<const btCompoundShape&>(loaded);
      ASSERT_EQ(compound.getNumChildShapes(), 1);
      EXPECT_EQ(compound.getChildTransform(0).getOrigin(), btVector3(0, 0, 0));
      ASSERT_EQ(compound.getChildShape(0)->getShapeType(), TRIANGLE_MESH_SHAPE_PROXYTYPE);
      const auto& bvh = *static_cast<const btBvhTriangleMeshShape*>(compound.getChildShape(0));
      EXPECT_EQ(bvh.getLocalScaling(), mesh.getLocalScaling());
      EXPECT_FLOAT_EQ(bvh.getMargin(), mesh.getMargin());
      EXPECT_TRUE(
          sameTriangles(trianglesOf(static_cast<const btConcaveShape&>(mesh)), trianglesOf(bvh), 1e-6f));
    };
    if (MeshShape::isMeshShape(before.getCollisionShape())) {
      check(*before.getCollisionShape(), *after.getCollisionShape());
    } else {
      // The user's compound: the MeshShape child as above, the box as it was.
      ASSERT_EQ(after.getCollisionShape()->getShapeType(), COMPOUND_SHAPE_PROXYTYPE);
      const auto& compound = *static_cast<const btCompoundShape*>(after.getCollisionShape());
      ASSERT_EQ(compound.getNumChildShapes(), 2) << "the MeshShape child is kept";
      EXPECT_EQ(compound.getChildTransform(0).getOrigin(), btVector3(0, 0.1f, 0));
      check(*saved.compoundMesh, *compound.getChildShape(0));
      EXPECT_EQ(compound.getChildShape(1)->getShapeType(), BOX_SHAPE_PROXYTYPE);
    }
  }
  importer.deleteAllData();
}

TEST(WorldSerialization, GpucolImporterBringsBackMeshShapesThatStepAsTheSavedOnes) {
  MeshWorld saved;
  std::vector<char> file = save(saved.world.world(), [&](btDefaultSerializer& s) {
    s.registerNameForPointer(saved.torus.get(), "torus");
  });
  LoadWorld load(true);
  WorldImporter importer(load.world.get());
  ASSERT_TRUE(importer.loadFileFromMemory(file.data(), int(file.size())));
  EXPECT_EQ(importer.meshShapesImported(), 5);
  EXPECT_EQ(
      static_cast<const btCompoundShape*>(bodyOf(*load.world, 5)->getCollisionShape())->getChildShape(0),
      bodyOf(*load.world, 6)->getCollisionShape())
      << "the compound's child and the body's shape are one MeshShape";
  btDiscreteDynamicsWorld& original = saved.world.world();
  ASSERT_EQ(load.world->getNumCollisionObjects(), original.getNumCollisionObjects());
  for (int i = 0; i < original.getNumCollisionObjects(); ++i) {
    SCOPED_TRACE("body " + std::to_string(i));
    const btRigidBody& before = *bodyOf(original, i);
    const btRigidBody& after = *bodyOf(*load.world, i);
    expectSameBody(before, after);
    // The saved inertia, the user's own on the compound included.
    EXPECT_EQ(before.getInvInertiaDiagLocal(), after.getInvInertiaDiagLocal());
    const auto check = [](const btCollisionShape& saved, const btCollisionShape* loaded) {
      ASSERT_TRUE(MeshShape::isMeshShape(loaded));
      const MeshShape& a = static_cast<const MeshShape&>(saved);
      const MeshShape& b = *static_cast<const MeshShape*>(loaded);
      EXPECT_EQ(a.mesh().positions(), b.mesh().positions());
      EXPECT_EQ(a.mesh().indices(), b.mesh().indices());
      ASSERT_EQ(a.mesh().parts().size(), b.mesh().parts().size());
      EXPECT_EQ(a.getLocalScaling(), b.getLocalScaling());
      EXPECT_FLOAT_EQ(a.getMargin(), b.getMargin());
    };
    if (MeshShape::isMeshShape(before.getCollisionShape())) {
      check(*before.getCollisionShape(), after.getCollisionShape());
    } else {
      ASSERT_EQ(after.getCollisionShape()->getShapeType(), COMPOUND_SHAPE_PROXYTYPE);
      const auto& compound = *static_cast<const btCompoundShape*>(after.getCollisionShape());
      ASSERT_EQ(compound.getNumChildShapes(), 2);
      check(*saved.compoundMesh, compound.getChildShape(0));
      EXPECT_EQ(compound.getChildShape(1)->getShapeType(), BOX_SHAPE_PROXYTYPE);
    }
  }
  // One shape shared by two bodies comes back shared; the name given to the torus's shape names its
  // MeshShape.
  EXPECT_EQ(bodyOf(*load.world, 3)->getCollisionShape(), bodyOf(*load.world, 4)->getCollisionShape());
  EXPECT_EQ(importer.getCollisionShapeByName("torus"), bodyOf(*load.world, 1)->getCollisionShape());

  // The loaded world steps as the saved one.
  load.world->setGravity(saved.world.world().getGravity());
  for (int step = 0; step < 90; ++step) {
    saved.world.step(1);
    load.world->stepSimulation(btScalar(1) / 60, 1, btScalar(1) / 60);
  }
  for (int i = 0; i < original.getNumCollisionObjects(); ++i) {
    EXPECT_LT((bodyOf(original, i)->getWorldTransform().getOrigin() -
               bodyOf(*load.world, i)->getWorldTransform().getOrigin())
                  .length(),
              1e-4f)
        << "body " << i;
  }
  importer.deleteAllData();
}

/// A GImpact world as stock Bullet users build it: a static GImpact slab, a scaled GImpact torus with a
/// margin, a GImpact mesh of two parts, under btCollisionDispatcher with GImpact registered.
TEST(WorldSerialization, GImpactFileLoadsAsMeshShapeBodies) {
  const TriangleMesh slabMesh = scenes::makeBox(2, 0.25f, 2, 2),
                     torusMesh = scenes::makeTorus(0.4f, 0.12f, 24, 12);
  const TriangleMesh partsMesh = twoPartMesh();
  struct Arrays {
    explicit Arrays(const TriangleMesh& mesh) {
      for (const MeshPart& part : mesh.parts()) {
        xyz.emplace_back(mesh.positions().begin() + 3 * part.firstVertex,
                         mesh.positions().begin() + 3 * (part.firstVertex + part.vertexCount));
        faces.emplace_back();
        for (std::size_t i = 3 * part.firstTriangle; i < 3 * (part.firstTriangle + part.triangleCount); ++i) {
          faces.back().push_back(int(mesh.indices()[i] - part.firstVertex));
        }
      }
      for (std::size_t p = 0; p < xyz.size(); ++p) {
        btIndexedMesh m;
        m.m_numTriangles = int(faces[p].size() / 3);
        m.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(faces[p].data());
        m.m_triangleIndexStride = 3 * sizeof(int);
        m.m_numVertices = int(xyz[p].size() / 3);
        m.m_vertexBase = reinterpret_cast<const unsigned char*>(xyz[p].data());
        m.m_vertexStride = 3 * sizeof(float);
        arrays.addIndexedMesh(m, PHY_INTEGER);
      }
    }
    std::vector<std::vector<float>> xyz;
    std::vector<std::vector<int>> faces;
    btTriangleIndexVertexArray arrays;
  };
  Arrays slabArrays(slabMesh), torusArrays(torusMesh), partsArrays(partsMesh);

  test::TestWorld world(test::DispatchKind::Stock);
  btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
  std::vector<std::shared_ptr<btGImpactMeshShape>> shapes;
  for (Arrays* arrays : {&slabArrays, &torusArrays, &partsArrays}) {
    shapes.push_back(std::make_shared<btGImpactMeshShape>(&arrays->arrays));
  }
  shapes[0]->setMargin(0.01f);
  shapes[1]->setLocalScaling(btVector3(1, 1.5f, 1));
  shapes[1]->setMargin(0.02f);
  shapes[2]->setMargin(0.015f);
  for (auto& shape : shapes) shape->updateBound();
  world.add(shapes[0], 0, test::at(0, -0.25f, 0));
  world.add(shapes[1], 2, btTransform(btQuaternion(btVector3(1, 0, 0), 1.0f), btVector3(-1, 0.5f, 0)));
  world.add(shapes[2], 1, test::at(1, 0.6f, 0.5f));
  world.add(std::make_shared<btBoxShape>(btVector3(0.2f, 0.2f, 0.2f)), 1, test::at(0, 0.5f, -1));
  std::vector<char> file = save(world.world());

  // Debian's importer is built without GImpact: it brings back the box alone.
  {
    LoadWorld load(false);
    btBulletWorldImporter stock(load.world.get());
    std::vector<char> copy = file;
    ASSERT_TRUE(stock.loadFileFromMemory(copy.data(), int(copy.size())));
    std::cout << "btBulletWorldImporter brought back " << load.world->getNumCollisionObjects()
              << " of 4 bodies\n";
    stock.deleteAllData();
  }

  LoadWorld load(true);
  WorldImporter importer(load.world.get());
  ASSERT_TRUE(importer.loadFileFromMemory(file.data(), int(file.size())));
  EXPECT_EQ(importer.meshShapesImported(), 3);
  ASSERT_EQ(load.world->getNumCollisionObjects(), 4);
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE("body " + std::to_string(i));
    const btRigidBody& before = *bodyOf(world.world(), i);
    const btRigidBody& after = *bodyOf(*load.world, i);
    expectSameBody(before, after);
    EXPECT_EQ(before.getInvInertiaDiagLocal(), after.getInvInertiaDiagLocal())
        << "GImpact's inertia, as saved";
    if (i == 3) {
      EXPECT_EQ(after.getCollisionShape()->getShapeType(), BOX_SHAPE_PROXYTYPE);
      continue;
    }
    ASSERT_TRUE(MeshShape::isMeshShape(after.getCollisionShape()));
    const MeshShape& mesh = *static_cast<const MeshShape*>(after.getCollisionShape());
    const auto& gimpact = *shapes[std::size_t(i)];
    EXPECT_EQ(mesh.getLocalScaling(), gimpact.getLocalScaling());
    EXPECT_FLOAT_EQ(mesh.getMargin(), gimpact.getMargin());
    EXPECT_EQ(mesh.mesh().parts().size(), std::size_t(gimpact.getMeshPartCount()));
    EXPECT_TRUE(sameTriangles(trianglesOf(mesh), trianglesOf(gimpact), 1e-6f));
  }
  // The loaded bodies rest on the slab under gpucol.
  load.world->setGravity(btVector3(0, -10, 0));
  for (int step = 0; step < 120; ++step) load.world->stepSimulation(btScalar(1) / 60, 1, btScalar(1) / 60);
  for (int i = 1; i < 4; ++i)
    EXPECT_GT(bodyOf(*load.world, i)->getWorldTransform().getOrigin().y(), 0.05f) << i;
  importer.deleteAllData();
}

}  // namespace
}  // namespace gpucol
