// Bad and extreme input: NaN or infinity in a transform (collideMeshes refuses it; in a world the pair is
// skipped with one warning and nothing else is touched), NaN or infinity in a proxy box of GridBroadphase
// (the proxy gets no pairs, with one warning; the other proxies' pairs stay exact), a zero-volume (flat) mesh
// (no mass properties, still collides), and a mesh of a million triangles (built and collided once; time and
// memory printed).
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include "bullet/test_world.h"
#include "scenes/procedural_meshes.h"
#include "stress/stress_util.h"

namespace gpucol::test {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

TEST(StressBadInput, NonFiniteTransformsAreRefusedByCollideMeshes) {
  auto a = stressShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
  auto b = stressShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
  const btTransform good(btQuaternion::getIdentity(), btVector3(0.5f, 0.5f, 0));
  for (float bad : {kNaN, kInf, -kInf}) {
    btTransform badOrigin = good, badBasis = good;
    badOrigin.getOrigin().setY(bad);
    badBasis.getBasis()[1][2] = bad;
    for (const btTransform& t : {badOrigin, badBasis}) {
      EXPECT_THROW(collideMeshes(*a, t, *b, good), std::invalid_argument);
      EXPECT_THROW(collideMeshes(*a, good, *b, t), std::invalid_argument);
      std::vector<MeshPairQuery> batch(3, MeshPairQuery{a.get(), good, b.get(), good});
      batch[1].transformB = t;
      EXPECT_THROW(collideMeshesBatch(batch), std::invalid_argument);
    }
  }
  try {
    btTransform t = good;
    t.getOrigin().setX(kNaN);
    collideMeshes(*a, t, *b, good);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << "the message must say what is wrong";
  }
}

// A world of meshes where one body's transform turns NaN. Bullet itself takes a body whose AABB overflows out
// of the simulation (btCollisionWorld::updateSingleAabb), so the pair reaches gpucol only against a body that
// is still active: here the bad box lies on a good one. The pair is skipped with one warning over many steps,
// nothing throws through Bullet, and the good box stays finite on the ground.
TEST(StressBadInput, NonFiniteTransformInAWorldIsSkippedWithOneWarning) {
  TestWorld world(DispatchKind::Gpucol);
  auto box = meshShape(scenes::makeBox(0.5f, 0.5f, 0.5f));
  world.add(meshShape(scenes::makeBox(5, 0.5f, 5)), 0, at(0, -0.5f, 0));
  btRigidBody* good = world.add(box, 1, at(0, 0.5f, 0));
  btRigidBody* bad = world.add(box, 1, at(0, 1.5f, 0));
  good->setActivationState(DISABLE_DEACTIVATION);  // keeps the pair with the bad box dispatched every step
  world.step(30);
  btTransform nan = bad->getWorldTransform();
  nan.getOrigin().setX(kNaN);
  bad->setWorldTransform(nan);
  testing::internal::CaptureStderr();
  EXPECT_NO_THROW(world.step(120));
  const std::string warnings = testing::internal::GetCapturedStderr();
  std::printf("stderr during 120 steps with a NaN body:\n%s", warnings.c_str());
  EXPECT_TRUE(isFinite(*good));
  EXPECT_NEAR(good->getWorldTransform().getOrigin().y(), 0.5f, 0.02f)
      << "the good box must still rest on the ground";
  // No manifold point is NaN.
  for (int m = 0; m < world.dispatcher().getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = world.dispatcher().getManifoldByIndexInternal(m);
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      EXPECT_TRUE(std::isfinite(manifold->getContactPoint(p).getDistance()));
      EXPECT_TRUE(std::isfinite(manifold->getContactPoint(p).m_normalWorldOnB.x()));
    }
  }
  // Said once, not every step.
  std::size_t lines = 0;
  for (std::size_t at = warnings.find("skipping"); at != std::string::npos;
       at = warnings.find("skipping", at + 1))
    ++lines;
  EXPECT_EQ(lines, 1u) << "the skipped pair must be said exactly once";
}

// Pairs of the broad phase through its cache, as keys (uid0 < uid1).
std::set<std::pair<int, int>> cachePairs(GridBroadphase& broadphase) {
  std::set<std::pair<int, int>> out;
  btBroadphasePairArray& pairs = broadphase.getOverlappingPairCache()->getOverlappingPairArray();
  for (int i = 0; i < pairs.size(); ++i) {
    const int u0 = pairs[i].m_pProxy0->m_uniqueId, u1 = pairs[i].m_pProxy1->m_uniqueId;
    out.insert({std::min(u0, u1), std::max(u0, u1)});
  }
  return out;
}

// A NaN or infinite box in the grid broad phase, given at creation or by setAabb, on the brute force and the
// grid paths: no crash, no hang, the proxy itself is in no pair, the finite proxies' pairs are exactly the
// brute force ones, and a warning is printed once. When the box becomes finite again, its pairs come back.
TEST(StressBadInput, NonFiniteProxyBoxesInTheGridBroadphase) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  std::mt19937 rng(60604);
  std::uniform_real_distribution<float> position(0, 10), size(0.2f, 1.5f);
  const btVector3 badBoxes[][2] = {
      {btVector3(kNaN, 0, 0), btVector3(1, 1, 1)},
      {btVector3(0, 0, 0), btVector3(1, kNaN, 1)},
      {btVector3(-kInf, 0, 0), btVector3(1, 1, 1)},
      {btVector3(0, 0, 0), btVector3(1, 1, kInf)},
  };
  for (int bruteForceBelow : {1000, 0}) {  // brute force path, grid path
    for (const auto& badBox : badBoxes) {
      for (bool atCreation : {true, false}) {
        SCOPED_TRACE("bruteForceBelow " + std::to_string(bruteForceBelow) +
                     (atCreation ? ", at creation" : ", by setAabb"));
        Config config;
        config.bruteForceBelow = bruteForceBelow;
        GridBroadphase broadphase(config);
        std::vector<btBroadphaseProxy*> proxies;
        std::vector<btVector3> lo, hi;
        for (int i = 0; i < 60; ++i) {
          const btVector3 p(position(rng), position(rng), position(rng));
          const btVector3 h(size(rng), size(rng), size(rng));
          lo.push_back(p - h), hi.push_back(p + h);
          proxies.push_back(broadphase.createProxy(lo.back(), hi.back(), 0, nullptr, 1, -1, &dispatcher));
        }
        btBroadphaseProxy* bad =
            atCreation ? broadphase.createProxy(badBox[0], badBox[1], 0, nullptr, 1, -1, &dispatcher)
                       : broadphase.createProxy(btVector3(4, 4, 4), btVector3(6, 6, 6), 0, nullptr, 1, -1,
                                                &dispatcher);
        if (!atCreation) {
          broadphase.calculateOverlappingPairs(&dispatcher);
          EXPECT_FALSE(
              std::none_of(cachePairs(broadphase).begin(), cachePairs(broadphase).end(),
                           [&](const std::pair<int, int>& p) { return p.second == bad->m_uniqueId; }))
              << "the box at 4-6 must overlap something first";
          broadphase.setAabb(bad, badBox[0], badBox[1], &dispatcher);
        }
        testing::internal::CaptureStderr();
        for (int step = 0; step < 3; ++step) broadphase.calculateOverlappingPairs(&dispatcher);
        const std::string warnings = testing::internal::GetCapturedStderr();
        std::set<std::pair<int, int>> expected;
        for (std::size_t i = 0; i < proxies.size(); ++i) {
          for (std::size_t j = i + 1; j < proxies.size(); ++j) {
            if (TestAabbAgainstAabb2(lo[i], hi[i], lo[j], hi[j]))
              expected.insert({proxies[i]->m_uniqueId, proxies[j]->m_uniqueId});
          }
        }
        EXPECT_EQ(cachePairs(broadphase), expected) << "the finite proxies' pairs, and none of the bad one";
        EXPECT_LE(std::count(warnings.begin(), warnings.end(), '\n'), 1) << warnings;
        btVector3 aabbMin, aabbMax;
        broadphase.getBroadphaseAabb(aabbMin, aabbMax);
        EXPECT_TRUE(
            std::isfinite(aabbMin.x() + aabbMin.y() + aabbMin.z() + aabbMax.x() + aabbMax.y() + aabbMax.z()));
        // Finite again: its pairs come back, exactly those of the brute force.
        broadphase.setAabb(bad, btVector3(4, 4, 4), btVector3(6, 6, 6), &dispatcher);
        broadphase.calculateOverlappingPairs(&dispatcher);
        for (std::size_t i = 0; i < proxies.size(); ++i) {
          if (TestAabbAgainstAabb2(lo[i], hi[i], btVector3(4, 4, 4), btVector3(6, 6, 6)))
            expected.insert({proxies[i]->m_uniqueId, bad->m_uniqueId});
        }
        EXPECT_EQ(cachePairs(broadphase), expected) << "the pairs once the bad box is finite again";
        for (btBroadphaseProxy* p : proxies) broadphase.destroyProxy(p, &dispatcher);
        broadphase.destroyProxy(bad, &dispatcher);
      }
    }
  }
}

TEST(StressBadInput, FlatMeshHasNoMassPropertiesButCollides) {
  // A 2 x 2 square of two triangles (zero volume, open) and a closed but flat one (a square and its reverse):
  // massProperties says why it has none; both collide with a box through their faces.
  const std::vector<float> xyz = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
  const TriangleMesh open = TriangleMesh::fromArrays(xyz, {0, 2, 1, 0, 3, 2}, "flat square");
  const TriangleMesh closed =
      TriangleMesh::fromArrays(xyz, {0, 2, 1, 0, 3, 2, 0, 1, 2, 0, 2, 3}, "flat both sides");
  for (const TriangleMesh* mesh : {&open, &closed}) {
    SCOPED_TRACE(mesh->name());
    try {
      mesh->massProperties();
      ADD_FAILURE() << "a flat mesh has no mass properties";
    } catch (const MeshError& e) {
      std::printf("%s: massProperties: %s\n", mesh->name().c_str(), e.what());
      EXPECT_FALSE(std::string(e.what()).empty());
    }
    auto flat = stressShape(*mesh);
    auto box = stressShape(scenes::makeBox(0.25f, 0.25f, 0.25f));
    // The box sunk 1/8 through the flat face (y = 0), facing up: depth -1/8 along +y.
    const btTransform tb(btQuaternion::getIdentity(), btVector3(0.5f, 0.125f, 0));
    const MeshPairResult r = collideMeshes(*box, tb, *flat, btTransform::getIdentity());
    ASSERT_TRUE(allFinite(r));
    ASSERT_FALSE(r.contacts.empty());
    const QueryCheck check = checkQuery(*box, tb, *flat, btTransform::getIdentity(), r, 1e-5, 1e-5);
    expectAgrees(check, 1e-5, "flat");
    EXPECT_GT(check.clearlyIntersecting, 0u);
    // Its inertia falls back to the bounding box (MeshShape's documented fallback), finite.
    btVector3 inertia;
    flat->calculateLocalInertia(1, inertia);
    EXPECT_TRUE(std::isfinite(inertia.x()) && std::isfinite(inertia.y()) && std::isfinite(inertia.z()));
  }
}

// Resident memory of this process in bytes (Linux /proc/self/statm), 0 when unknown.
double residentBytes() {
  std::ifstream statm("/proc/self/statm");
  double pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * 4096.0;
}

TEST(StressBadInput, AMillionTriangleMeshIsBuiltAndCollidedOnce) {
  // A torus of 1000 x 500 segments: 1,000,000 triangles, 500,000 vertices, against a copy turned and moved.
  using Clock = std::chrono::steady_clock;
  const double before = residentBytes();
  auto start = Clock::now();
  auto shape = std::make_shared<MeshShape>(
      std::make_shared<const TriangleMesh>(scenes::makeTorus(1.0f, 0.3f, 1000, 500)));
  const double buildSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_EQ(shape->mesh().triangleCount(), 1000000u);
  const double afterBuild = residentBytes();
  const btTransform ta = btTransform::getIdentity();
  const btTransform tb(btQuaternion(btVector3(1, 0, 0), 0.3f), btVector3(0.2f, 0.1f, 0.05f));
  start = Clock::now();
  const MeshPairResult r = collideMeshes(*shape, ta, *shape, tb);
  const double collideSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  const double afterCollide = residentBytes();
  ASSERT_TRUE(allFinite(r));
  // The copy is tilted 0.3 rad and moved 0.23: the two tubes (radius 0.3) cross along long curves.
  EXPECT_FALSE(r.intersectingPairs.empty());
  EXPECT_FALSE(r.contacts.empty());
  // Memory: the mesh is 18 MB of arrays (12 B per vertex, 12 B per triangle); the tree and the query's lists
  // are a few times that. 2 GB would mean something grows without bound.
  EXPECT_LT(afterCollide - before, 2e9);
  std::printf(
      "million-triangle torus: built (mesh + tree) in %.2f s, collided with a copy in %.2f s (%llu node "
      "tests, "
      "%zu candidates, %zu intersecting, %zu contacts, %zu reduced); resident memory +%.0f MB after the "
      "build, +%.0f MB after the query\n",
      buildSeconds, collideSeconds, static_cast<unsigned long long>(r.stats.nodeTests),
      r.candidatePairs.size(), r.intersectingPairs.size(), r.contacts.size(), r.reducedContacts.size(),
      (afterBuild - before) / 1e6, (afterCollide - before) / 1e6);
  RecordProperty("million_build_seconds", std::to_string(buildSeconds));
  RecordProperty("million_collide_seconds", std::to_string(collideSeconds));
}

}  // namespace
}  // namespace gpucol::test
