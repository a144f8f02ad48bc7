// The skips of DESIGN.md ("skip what a scene does not need") on the mesh side, each shown by its counter:
// pairs whose root boxes miss stop there (DispatchStats::rootBoxesMissed), small pairs stay on the CPU
// (DispatchStats::openClPairs) and OpenCL is never started for them (gpucol::openClStarted). The broad
// phase's skips are shown in grid_broadphase_test.cpp.
#include <gpucol/gpucol.h>
#include <gtest/gtest.h>

#include "opencl/host/opencl_started.h"
#include "scenes/procedural_meshes.h"
#include "test_world.h"

namespace gpucol {
namespace {

std::shared_ptr<MeshShape> rodShape() {
  // A 4 m × 0.2 m × 0.2 m rod: turned 45° its world box is 3 m wide, far wider than the rod.
  return std::make_shared<MeshShape>(
      std::make_shared<const TriangleMesh>(scenes::makeBox(2.0f, 0.1f, 0.1f, 1)));
}

btTransform pose(float angle, const btVector3& origin) {
  btTransform t;
  t.setIdentity();
  t.setRotation(btQuaternion(btVector3(0, 0, 1), angle));
  t.setOrigin(origin);
  return t;
}

// Two parallel rods turned 45° about z, 1 m apart sideways: their world boxes overlap (the broad phase pairs
// them), their own boxes do not, so the pair stops at the root-box test.
TEST(SkipCounters, PairWhoseRootBoxesMissStopsThere) {
  test::TestWorld world(test::DispatchKind::Gpucol);
  world.world().setGravity(btVector3(0, 0, 0));
  const float angle = 0.785398f;
  world.add(rodShape(), 1, pose(angle, btVector3(0, 0, 0)));
  world.add(rodShape(), 1, pose(angle, btVector3(0.7071f, -0.7071f, 0)));
  world.step(1);
  const auto& stats = static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats();
  EXPECT_EQ(stats.meshPairs, 1u);
  EXPECT_EQ(stats.rootBoxesMissed, 1u);
  EXPECT_EQ(stats.reducedContacts, 0u);

  // The reference: the same rods crossed (one turned the other way) do reach the traversal and touch.
  test::TestWorld crossed(test::DispatchKind::Gpucol);
  crossed.world().setGravity(btVector3(0, 0, 0));
  crossed.add(rodShape(), 1, pose(angle, btVector3(0, 0, 0)));
  crossed.add(rodShape(), 1, pose(-angle, btVector3(0, 0.1f, 0)));
  crossed.step(1);
  const auto& crossedStats = static_cast<CollisionDispatcher&>(crossed.dispatcher()).lastStepStats();
  EXPECT_EQ(crossedStats.meshPairs, 1u);
  EXPECT_EQ(crossedStats.rootBoxesMissed, 0u);
  EXPECT_GT(crossedStats.reducedContacts, 0u);
}

// Small mesh pairs under Backend::Auto run on the CPU, and OpenCL is never set up for them. ctest runs each
// test in a process of its own; run by hand after a test that started OpenCL, the lazy-start half is skipped.
TEST(SkipCounters, SmallPairsStayOnTheCpuAndOpenClIsNeverStarted) {
  const bool startedBefore = openClStarted();
  test::TestWorld world(test::DispatchKind::Gpucol);
  auto ground =
      std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(5, 0.5f, 5, 2)));
  world.add(ground, 0, pose(0, btVector3(0, -0.5f, 0)));
  auto box =
      std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  world.add(box, 1, pose(0.2f, btVector3(0, 0.6f, 0)));
  std::uint64_t pairs = 0;
  for (int step = 0; step < 30; ++step) {
    world.step(1);
    const auto& stats = static_cast<CollisionDispatcher&>(world.dispatcher()).lastStepStats();
    pairs += stats.meshPairs;
    EXPECT_EQ(stats.openClPairs, 0u) << "step " << step;
  }
  EXPECT_GT(pairs, 0u);
  if (startedBefore) GTEST_SKIP() << "OpenCL was started by an earlier test in this process";
  EXPECT_FALSE(openClStarted());
}

// Short work under Auto never asks OpenCL anything, not even the device lists (on PoCL that starts its
// threads): a broad phase of 300 moving boxes and small mesh pairs, whose CPU calls take well under
// MeasuredBackendChoice::kDeviceWorthMs.
TEST(SkipCounters, ShortWorkUnderAutoNeverAsksTheDeviceLists) {
  const std::uint32_t before = opencl::deviceListsAsked().load();
  GridBroadphase broadphase;  // Backend::Auto
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  std::vector<btBroadphaseProxy*> proxies;
  for (int i = 0; i < 300; ++i) {
    const btVector3 c(float(i % 10), float((i / 10) % 10), float(i / 100));
    proxies.push_back(broadphase.createProxy(c, c + btVector3(1.2f, 1.2f, 1.2f), BOX_SHAPE_PROXYTYPE, nullptr,
                                             btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter,
                                             &dispatcher));
  }
  for (int step = 0; step < 20; ++step) {
    for (std::size_t i = 0; i < proxies.size(); ++i) {
      const btVector3 c = proxies[i]->m_aabbMin + btVector3(0.01f, 0, 0);
      broadphase.setAabb(proxies[i], c, c + btVector3(1.2f, 1.2f, 1.2f), &dispatcher);
    }
    broadphase.calculateOverlappingPairs(&dispatcher);
  }
  EXPECT_GT(broadphase.getOverlappingPairCache()->getNumOverlappingPairs(), 300);
  const auto box =
      std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  for (int call = 0; call < 10; ++call) {
    const MeshPairResult r = collideMeshes(*box, pose(0, btVector3(0, 0, 0)), *box, pose(0.2f, btVector3(0.9f, 0, 0)));
    ASSERT_FALSE(r.reducedContacts.empty());
    EXPECT_EQ(r.stats.backendUsed, Backend::Cpu);
  }
  EXPECT_EQ(opencl::deviceListsAsked().load(), before);
}

// A large batch (two 81,920-triangle spheres) under Auto: Auto measures the device only when the chosen
// device is a GPU, and starts on the CPU path; the device lists alone decide that, so on a machine whose only
// device is a CPU one (PoCL) OpenCL is not set up at all, however many batches come.
TEST(SkipCounters, LargeBatchUnderAutoStartsOpenClOnlyForAGpu) {
  if (openClStarted()) GTEST_SKIP() << "OpenCL was started by an earlier test in this process";
  const auto sphere =
      std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeIcosphere(0.5f, 6)));
  const bool gpu = opencl::chosenDeviceIsGpu("");
  for (int call = 0; call < 4; ++call) {
    const MeshPairResult result =
        collideMeshes(*sphere, pose(0, btVector3(0, 0, 0)), *sphere, pose(0.3f, btVector3(0.9f, 0, 0)));
    ASSERT_FALSE(result.reducedContacts.empty());
    if (call == 0 || !gpu) {
      EXPECT_EQ(result.stats.backendUsed, Backend::Cpu) << "call " << call;
    }
  }
  if (!gpu) {
    EXPECT_FALSE(openClStarted());
  }
}

}  // namespace
}  // namespace gpucol
