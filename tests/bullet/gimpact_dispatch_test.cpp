// GImpact worlds under gpucol::CollisionDispatcher (issue 54): with the dispatcher swapped in (GImpact's
// registerAlgorithm kept, after it, or removed), GImpact mesh pairs, GImpact against MeshShape and GImpact
// against a plane go through gpucol's batch, built once per shape and again when its vertices change; a pile
// of GImpact tori and crates rests with no body through another, beside the same pile under GImpact; Config's
// switch leaves GImpact pairs to GImpact.
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "scenes/procedural_meshes.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"
#include "test_world.h"

namespace gpucol {
namespace {

/// A btGImpactMeshShape over its own copy of a mesh's arrays (which it keeps, as GImpact needs).
struct GImpactMeshBody {
  explicit GImpactMeshBody(const TriangleMesh& mesh, float margin = 0.01f)
      : xyz(mesh.positions().begin(), mesh.positions().end()),
        faces(mesh.indices().begin(), mesh.indices().end()),
        arrays(int(mesh.triangleCount()), faces.data(), 3 * sizeof(int), int(mesh.vertexCount()), xyz.data(),
               3 * sizeof(float)),
        shape(std::make_shared<btGImpactMeshShape>(&arrays)) {
    shape->setMargin(margin);
    shape->updateBound();
  }
  std::vector<float> xyz;
  std::vector<int> faces;
  btTriangleIndexVertexArray arrays;
  std::shared_ptr<btGImpactMeshShape> shape;
};

/// The deepest crossing of any two of `bodies`' mesh shapes (GImpact meshes through MeshShape::fromGImpact,
/// MeshShapes as they are; other shapes left out), from gpucol's exact triangle test at their current poses:
/// 0 when no triangles cross, else minus the depth of the deepest contact (metres). Also names the pair.
btScalar deepestCrossing(const std::vector<const btCollisionObject*>& bodies, std::string& where) {
  std::map<const btCollisionShape*, std::shared_ptr<const MeshShape>> meshes;
  for (const btCollisionObject* body : bodies) {
    const btCollisionShape* shape = body->getCollisionShape();
    if (meshes.count(shape)) continue;
    if (MeshShape::isMeshShape(shape)) {
      meshes[shape] =
          std::shared_ptr<const MeshShape>(std::shared_ptr<void>(), static_cast<const MeshShape*>(shape));
    } else if (shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE) {
      meshes[shape] = MeshShape::fromGImpact(*static_cast<const btGImpactMeshShape*>(shape));
    }
  }
  btScalar deepest = 0;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    for (std::size_t j = i + 1; j < bodies.size(); ++j) {
      if (!meshes[bodies[i]->getCollisionShape()] || !meshes[bodies[j]->getCollisionShape()]) continue;
      const MeshPairResult r =
          collideMeshes(*meshes[bodies[i]->getCollisionShape()], bodies[i]->getWorldTransform(),
                        *meshes[bodies[j]->getCollisionShape()], bodies[j]->getWorldTransform());
      for (const MeshContact& c : r.contacts) {
        if (c.depth < deepest) {
          deepest = c.depth;
          where = "bodies " + std::to_string(i) + " and " + std::to_string(j);
        }
      }
    }
  }
  return deepest;
}

std::vector<const btCollisionObject*> objectsOf(btCollisionWorld& world) {
  std::vector<const btCollisionObject*> out;
  for (int i = 0; i < world.getNumCollisionObjects(); ++i) out.push_back(world.getCollisionObjectArray()[i]);
  return out;
}

/// The kind of algorithm each overlapping pair of the world holds, by the two bodies' indices.
std::map<std::pair<int, int>, std::string> algorithmsOf(btCollisionWorld& world) {
  std::map<const btCollisionObject*, int> index;
  for (int i = 0; i < world.getNumCollisionObjects(); ++i) index[world.getCollisionObjectArray()[i]] = i;
  std::map<std::pair<int, int>, std::string> out;
  btBroadphasePairArray& pairs = world.getPairCache()->getOverlappingPairArray();
  for (int p = 0; p < pairs.size(); ++p) {
    int a = index[static_cast<btCollisionObject*>(pairs[p].m_pProxy0->m_clientObject)];
    int b = index[static_cast<btCollisionObject*>(pairs[p].m_pProxy1->m_clientObject)];
    if (a > b) std::swap(a, b);
    btCollisionAlgorithm* algorithm = pairs[p].m_algorithm;
    out[{a, b}] = algorithm == nullptr                                    ? "none"
                  : dynamic_cast<MeshMeshAlgorithm*>(algorithm)           ? "gpucol"
                  : dynamic_cast<btGImpactCollisionAlgorithm*>(algorithm) ? "gimpact"
                                                                          : "other";
  }
  return out;
}

TEST(GImpactDispatch, PileOfGImpactToriAndCratesRestsWithNoBodyThroughAnother) {
  // 16 tori and crates in a bin, all btGImpactMeshShape (1 cm margins), stepped 8 s: once as a GImpact world
  // and once with gpucol::CollisionDispatcher in its place.
  const scenes::SceneDescription pile = scenes::makeToriAndCratesScene(16);
  std::map<scenes::CollisionBackend, btScalar> crossing;
  for (const auto backend : {scenes::CollisionBackend::GImpact, scenes::CollisionBackend::GImpactOnGpucol}) {
    SCOPED_TRACE(scenes::backendName(backend));
    scenes::WorldOptions options;
    options.backend = backend;
    scenes::WorldScene world(pile, options);
    std::uint64_t gimpactPairs = 0, standIns = 0, meshPairs = 0;
    for (int step = 0; step < 480; ++step) {
      world.step(1.0f / 60);
      if (const CollisionDispatcher* d = world.gpucolDispatcher()) {
        gimpactPairs += d->lastStepStats().gimpactPairs;
        meshPairs += d->lastStepStats().meshPairs;
        standIns += d->lastStepStats().gimpactStandInsBuilt;
      }
    }
    ASSERT_TRUE(world.allFinite());
    EXPECT_EQ(world.bodiesBelowGround(), 0);
    EXPECT_LT(world.farthestBody(), 4.0f) << "a body left the bin";
    std::string where;
    crossing[backend] = deepestCrossing(objectsOf(world.world()), where);
    std::cout << scenes::backendName(backend) << ": deepest crossing " << crossing[backend] << " m (" << where
              << "), largest manifold penetration " << world.largestPenetration() << " m, moving "
              << world.movingBodyCount() << ", asleep " << world.sleepingBodyCount() << "\n";
    if (backend == scenes::CollisionBackend::GImpactOnGpucol) {
      // No two bodies' triangles cross by more than 5 mm: with 1 cm margins they rest about 2 cm apart.
      EXPECT_GT(crossing[backend], -0.005f) << where;
      EXPECT_TRUE(world.allAtRest());
      // Every GImpact pair went through the batch; a stand-in per GImpact shape (bin, torus, crate), built
      // once.
      EXPECT_GT(gimpactPairs, 480u);
      EXPECT_EQ(gimpactPairs, meshPairs);
      EXPECT_EQ(standIns, 3u);
    }
  }
}

/// A GImpact world of every kind of pair: a GImpact crate on a GImpact slab, a GImpact torus on a static
/// plane, a MeshShape torus on a GImpact crate, a GImpact crate on a MeshShape slab, a btBoxShape on the
/// GImpact slab.
struct MixedWorld {
  explicit MixedWorld(test::DispatchKind kind, const Config& config = Config()) : world(kind, config) {}

  void build() {
    world.add(std::make_shared<btStaticPlaneShape>(btVector3(0, 1, 0), 0), 0, test::at(0, 0, 0));  // 0
    world.add(slab.shape, 0, test::at(-3, 0.25f, 0));                                              // 1
    world.add(test::meshShape(scenes::makeBox(1, 0.25f, 1, 2)), 0, test::at(3, 0.25f, 0));         // 2
    crateOnSlab = world.add(crate.shape, 1, test::at(-3, 0.9f, 0));                                // 3
    torusOnPlane = world.add(torus.shape, 1, btTransform(flat, btVector3(0, 0.5f, -3)));           // 4
    lowerCrate = world.add(crate.shape, 1, test::at(0, 0.4f, 3));                                  // 5
    meshTorus = world.add(test::meshShape(scenes::makeTorus(0.4f, 0.12f, 24, 12)), 1,
                          btTransform(flat, btVector3(0, 1.2f, 3)));  // 6
    crateOnMesh = world.add(crate.shape, 1, test::at(3, 0.9f, 0));    // 7
    boxOnSlab = world.add(std::make_shared<btBoxShape>(btVector3(0.3f, 0.3f, 0.3f)), 1,
                          test::at(-3, 1.8f, 0.2f));  // 8
    for (int i = 0; i < world.world().getNumCollisionObjects(); ++i) {
      world.world().getCollisionObjectArray()[i]->setActivationState(DISABLE_DEACTIVATION);
    }
  }

  /// Where each dynamic body should rest (y of its centre), within `tolerance`; the btBoxShape on the crate
  /// too when `box`.
  void expectResting(btScalar tolerance, bool box = true) {
    EXPECT_NEAR(crateOnSlab->getWorldTransform().getOrigin().y(), 0.5f + 0.3f, tolerance);
    EXPECT_NEAR(torusOnPlane->getWorldTransform().getOrigin().y(), 0.12f, tolerance);
    EXPECT_NEAR(lowerCrate->getWorldTransform().getOrigin().y(), 0.3f, tolerance);
    EXPECT_NEAR(meshTorus->getWorldTransform().getOrigin().y(), 0.6f + 0.12f, tolerance);
    EXPECT_NEAR(crateOnMesh->getWorldTransform().getOrigin().y(), 0.5f + 0.3f, tolerance);
    if (box) {
      EXPECT_NEAR(boxOnSlab->getWorldTransform().getOrigin().y(), 1.1f + 0.3f, tolerance);
    }
  }

  const btQuaternion flat{btVector3(1, 0, 0), SIMD_HALF_PI};
  GImpactMeshBody slab{scenes::makeBox(1, 0.25f, 1, 2)};
  GImpactMeshBody crate{scenes::makeBox(0.3f, 0.3f, 0.3f, 2)};
  GImpactMeshBody torus{scenes::makeTorus(0.4f, 0.12f, 24, 12)};
  test::TestWorld world;
  btRigidBody *crateOnSlab = nullptr, *torusOnPlane = nullptr, *lowerCrate = nullptr, *meshTorus = nullptr,
              *crateOnMesh = nullptr, *boxOnSlab = nullptr;
};

TEST(GImpactDispatch, MixedWorldRestsWithOrWithoutGImpactRegistered) {
  // gpucol::CollisionDispatcher takes the GImpact pairs whether registerAlgorithm is never called, called
  // after it (overriding its create functions) or before a later registration: the same algorithms and the
  // same rest.
  for (const int registration : {0, 1}) {
    SCOPED_TRACE(registration == 0 ? "GImpact not registered" : "registerAlgorithm after the dispatcher");
    MixedWorld mixed(test::DispatchKind::Gpucol);
    if (registration == 1) btGImpactCollisionAlgorithm::registerAlgorithm(&mixed.world.dispatcher());
    mixed.build();
    mixed.world.step(150);
    mixed.expectResting(0.04f);
    std::string where;
    EXPECT_GT(deepestCrossing(objectsOf(mixed.world.world()), where), -0.005f) << where;
    const std::map<std::pair<int, int>, std::string> algorithms = algorithmsOf(mixed.world.world());
    EXPECT_EQ(algorithms.at({1, 3}), "gpucol") << "GImpact crate on GImpact slab";
    EXPECT_EQ(algorithms.at({0, 4}), "gpucol") << "GImpact torus on a plane";
    EXPECT_EQ(algorithms.at({5, 6}), "gpucol") << "MeshShape torus on a GImpact crate";
    EXPECT_EQ(algorithms.at({2, 7}), "gpucol") << "GImpact crate on a MeshShape slab";
    // A convex shape against a GImpact mesh keeps Bullet's algorithm: GImpact's where registered, else the
    // convex-concave one.
    EXPECT_EQ(algorithms.at({3, 8}), registration == 1 ? "gimpact" : "other")
        << "btBoxShape on a GImpact crate";
    const DispatchStats& stats = static_cast<CollisionDispatcher&>(mixed.world.dispatcher()).lastStepStats();
    // In the batch: crate-slab, crate-crate (5, 7 are apart), torus-crate, crate-MeshShape slab... every pair
    // of two meshes; the plane's pair is collided on its own.
    EXPECT_GE(stats.gimpactPairs, 3u);
    EXPECT_EQ(stats.gimpactStandInsBuilt, 0u) << "stand-ins are kept from step to step";
  }
}

TEST(GImpactDispatch, MeshShapesAndGImpactMeshesRestOnEachOtherUnderEitherAlgorithm) {
  // GImpact's registerAlgorithm, called last, takes every pair with a GImpact shape, a MeshShape's too: on a
  // stock dispatcher with MeshMeshAlgorithm registered first, GImpact's algorithm collides them (through the
  // MeshShape's processAllTriangles) and nothing falls through; gpucol::CollisionDispatcher takes the same
  // pairs itself.
  for (const auto kind : {test::DispatchKind::StockRegistered, test::DispatchKind::Gpucol}) {
    const bool gpucol = kind == test::DispatchKind::Gpucol;
    SCOPED_TRACE(gpucol ? "gpucol::CollisionDispatcher" : "registerWith, then GImpact's registerAlgorithm");
    test::TestWorld world(kind);
    btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
    GImpactMeshBody slab(scenes::makeBox(1, 0.25f, 1, 2)), crate(scenes::makeBox(0.3f, 0.3f, 0.3f, 2));
    world.add(slab.shape, 0, test::at(0, 0.25f, 0));                                        // 0
    world.add(test::meshShape(scenes::makeBox(1, 0.25f, 1, 2)), 0, test::at(3, 0.25f, 0));  // 1
    const btQuaternion flat(btVector3(1, 0, 0), SIMD_HALF_PI);
    btRigidBody* meshCrate =
        world.add(test::meshShape(scenes::makeBox(0.3f, 0.3f, 0.3f, 2)), 1, test::at(0.5f, 0.85f, 0));  // 2
    btRigidBody* meshTorus = world.add(test::meshShape(scenes::makeTorus(0.4f, 0.12f, 24, 12)), 1,
                                       btTransform(flat, btVector3(-0.4f, 0.7f, 0)));  // 3
    btRigidBody* gimpactCrate = world.add(crate.shape, 1, test::at(3, 0.85f, 0));      // 4
    for (btRigidBody* body : {meshCrate, meshTorus, gimpactCrate})
      body->setActivationState(DISABLE_DEACTIVATION);
    world.step(120);
    // On the slabs' tops at 0.5, 1 cm margins on the GImpact sides.
    EXPECT_NEAR(meshCrate->getWorldTransform().getOrigin().y(), 0.81f, 0.02f);
    EXPECT_NEAR(meshTorus->getWorldTransform().getOrigin().y(), 0.63f, 0.02f);
    EXPECT_NEAR(gimpactCrate->getWorldTransform().getOrigin().y(), 0.81f, 0.02f);
    const std::map<std::pair<int, int>, std::string> algorithms = algorithmsOf(world.world());
    for (const auto& pair : {std::make_pair(0, 2), std::make_pair(0, 3), std::make_pair(1, 4)}) {
      EXPECT_EQ(algorithms.at(pair), gpucol ? "gpucol" : "gimpact") << pair.first << "-" << pair.second;
    }
  }
}

TEST(GImpactDispatch, ConfigSwitchLeavesGImpactPairsToGImpact) {
  Config config;
  config.collideGImpactShapes = false;
  MixedWorld mixed(test::DispatchKind::Gpucol, config);
  btGImpactCollisionAlgorithm::registerAlgorithm(&mixed.world.dispatcher());
  mixed.build();
  mixed.world.step(150);
  const std::map<std::pair<int, int>, std::string> algorithms = algorithmsOf(mixed.world.world());
  EXPECT_EQ(algorithms.at({1, 3}), "gimpact") << "GImpact crate on GImpact slab";
  EXPECT_EQ(algorithms.at({0, 4}), "gimpact") << "GImpact torus on a plane";
  // A MeshShape against a GImpact mesh is gpucol's either way (GImpact's algorithm would let them through).
  EXPECT_EQ(algorithms.at({5, 6}), "gpucol") << "MeshShape torus on a GImpact crate";
  EXPECT_EQ(algorithms.at({2, 7}), "gpucol") << "GImpact crate on a MeshShape slab";
  const DispatchStats& stats = static_cast<CollisionDispatcher&>(mixed.world.dispatcher()).lastStepStats();
  EXPECT_EQ(stats.gimpactPairs, 0u);
  EXPECT_EQ(stats.gimpactStandInsBuilt, 0u);
  // GImpact's own algorithm rests the meshes too (with its margins' gap); the btBoxShape, left to GImpact
  // against the crate, did not stay on it (it ended at y = 0.25), so it is not checked here.
  mixed.expectResting(0.05f, false);
}

TEST(GImpactDispatch, GImpactChildOfACompoundRestsOnAGImpactSlab) {
  // A compound pair goes to Bullet's compound algorithm, whose child pairs come back to the dispatcher's
  // findAlgorithm: the GImpact crate inside the compound is collided by gpucol, pair by pair.
  test::TestWorld world(test::DispatchKind::Gpucol);
  btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
  GImpactMeshBody slab(scenes::makeBox(1, 0.25f, 1, 2)), crate(scenes::makeBox(0.3f, 0.3f, 0.3f, 2));
  world.add(slab.shape, 0, test::at(0, 0.25f, 0));
  auto compound = std::make_shared<btCompoundShape>();
  compound->addChildShape(test::at(0, 0.1f, 0), crate.shape.get());
  btRigidBody* body = world.add(compound, 1, test::at(0, 0.9f, 0));
  body->setActivationState(DISABLE_DEACTIVATION);
  std::uint64_t built = 0;
  for (int i = 0; i < 120; ++i) {
    world.step(1);
    built += static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats().gimpactStandInsBuilt;
  }
  EXPECT_EQ(built, 2u) << "the slab's and the crate's stand-ins: gpucol collided the child";
  // The crate's centre 0.3 m above the slab's top at 0.5, plus both margins (2 cm).
  EXPECT_NEAR(body->getWorldTransform().getOrigin().y() + 0.1f, 0.8f, 0.04f);
  EXPECT_EQ(static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats().gimpactPairs, 0u)
      << "a compound's child pairs are not in the batch";
}

TEST(GImpactDispatch, StandInIsBuiltAgainWhenTheVerticesChange) {
  test::TestWorld world(test::DispatchKind::Gpucol);
  btGImpactCollisionAlgorithm::registerAlgorithm(&world.dispatcher());
  GImpactMeshBody slab(scenes::makeBox(1, 0.25f, 1, 2));
  world.add(slab.shape, 0, test::at(0, 0.25f, 0));
  GImpactMeshBody crate(scenes::makeBox(0.3f, 0.3f, 0.3f, 2));
  btRigidBody* box = world.add(crate.shape, 1, test::at(0, 0.9f, 0));
  box->setActivationState(DISABLE_DEACTIVATION);
  const auto& stats = static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats();
  std::uint64_t built = 0;
  for (int i = 0; i < 90; ++i) {
    world.step(1);
    built += stats.gimpactStandInsBuilt;
  }
  EXPECT_EQ(built, 2u) << "slab and crate, once each";
  EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 0.8f, 0.03f);

  // The user raises the slab's top by 20 cm in its vertex array and tells GImpact, as GImpact asks.
  for (std::size_t v = 1; v < slab.xyz.size(); v += 3) {
    if (slab.xyz[v] > 0) slab.xyz[v] += 0.2f;
  }
  slab.shape->postUpdate();
  slab.shape->updateBound();
  world.step(1);
  EXPECT_EQ(stats.gimpactStandInsBuilt, 1u) << "the slab's stand-in, built again";
  built = 0;
  for (int i = 0; i < 90; ++i) {
    world.step(1);
    built += stats.gimpactStandInsBuilt;
  }
  EXPECT_EQ(built, 0u);
  EXPECT_NEAR(box->getWorldTransform().getOrigin().y(), 1.0f, 0.03f) << "the crate rests on the raised top";
}

TEST(GImpactDispatch, OnlyWorldsOnGpucolsDispatcherReportItsStatistics) {
  // The demo prints the dispatcher's statistics for the backends that have one; Bullet's own dispatcher (the
  // GImpact and primitives worlds) is not gpucol's and must not be read as one.
  const scenes::SceneDescription stack = scenes::makeStackScene();
  for (const auto backend : {scenes::CollisionBackend::Gpucol, scenes::CollisionBackend::GImpactOnGpucol,
                             scenes::CollisionBackend::GImpact, scenes::CollisionBackend::Primitives}) {
    SCOPED_TRACE(scenes::backendName(backend));
    scenes::WorldOptions options;
    options.backend = backend;
    scenes::WorldScene world(stack, options);
    const bool ownsGpucolDispatcher = dynamic_cast<const CollisionDispatcher*>(world.world().getDispatcher());
    EXPECT_EQ(world.gpucolDispatcher() != nullptr, ownsGpucolDispatcher);
    EXPECT_EQ(ownsGpucolDispatcher, backend == scenes::CollisionBackend::Gpucol ||
                                        backend == scenes::CollisionBackend::GImpactOnGpucol);
  }
}

}  // namespace
}  // namespace gpucol
