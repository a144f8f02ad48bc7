// The OpenCL mesh pipeline (opencl/host/mesh_pipeline.cpp, reached through collideMeshesBatch with
// Backend::OpenCL) against the CPU path, the reference: on the scenes of the foundation issue's tests
// (tests/bullet/collide_meshes_test.cpp), batches of 1, 7 and 100 mixed pairs, a pair with no candidates,
// launches larger than a work-group, leaves of several triangles, scaled and mirrored shapes, every start
// depth, with and without the early-out test, device or host sort. Candidate and intersecting pairs must be
// identical and in the same order; contacts equal within float tolerance (and counted bit for bit).
#include "opencl/host/mesh_pipeline.h"

#include <gpucol/gpucol.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "mesh_pairs/mesh_device_backend.h"
#include "opencl/opencl_test_device.h"
#include "opencl/shared/mesh_pipeline_types.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"
#include "support/auto_on_cpu_device.h"
#include "support/test_paths.h"

namespace gpucol::test {
namespace {

std::shared_ptr<const TriangleMesh> sharedMesh(TriangleMesh mesh) {
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

btTransform randomPose(std::mt19937& rng, const btVector3& centre, float halfExtent) {
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> uniform(-halfExtent, halfExtent);
  btQuaternion q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
  q.normalize();
  return btTransform(q, centre + btVector3(uniform(rng), uniform(rng), uniform(rng)));
}

/// Restores the default device options when a test ends.
struct DeviceOptionsGuard {
  MeshBatchDeviceOptions saved = detail::meshDeviceOptions();
  ~DeviceOptionsGuard() { detail::setMeshDeviceOptions(saved); }
};

/// What one comparison saw, for the tests' own "not vacuous" checks.
struct Compared {
  std::size_t candidates = 0, intersecting = 0, contacts = 0, bitIdentical = 0, onDevice = 0;
};

void expectContactNear(const MeshContact& cpu, const MeshContact& cl, float scale, const std::string& where) {
  EXPECT_EQ(cpu.triangleA, cl.triangleA) << where;
  EXPECT_EQ(cpu.triangleB, cl.triangleB) << where;
  // Float tolerance: a few float ulps of the scene's size (the device computes in the same frame).
  const float tolerance = 1e-5f * scale;
  EXPECT_LE((cpu.pointWorld - cl.pointWorld).length(), tolerance) << where;
  EXPECT_LE((cpu.pointOnBWorld - cl.pointOnBWorld).length(), tolerance) << where;
  EXPECT_GE(cpu.normalWorldOnB.dot(cl.normalWorldOnB), 1.0f - 1e-6f) << where;
  EXPECT_NEAR(cpu.depth, cl.depth, tolerance) << where;
}

/// Runs `queries` on the CPU and on OpenCL and compares everything; `scale` is the scene's size.
Compared expectSameAsCpu(const std::vector<MeshPairQuery>& queries, float scale) {
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  Config cl;
  cl.meshBackend = Backend::OpenCL;
  const std::vector<MeshPairResult> expected = collideMeshesBatch(queries, cpu);
  const std::vector<MeshPairResult> got = collideMeshesBatch(queries, cl);
  Compared seen;
  EXPECT_EQ(expected.size(), got.size());
  for (std::size_t i = 0; i < std::min(expected.size(), got.size()); ++i) {
    const MeshPairResult& e = expected[i];
    const MeshPairResult& g = got[i];
    const std::string where = "query " + std::to_string(i);
    EXPECT_EQ(e.stats.rootBoxesMissed, g.stats.rootBoxesMissed) << where;
    // Root-box misses never reach the device; every other pair does.
    EXPECT_EQ(g.stats.backendUsed, e.stats.rootBoxesMissed ? Backend::Cpu : Backend::OpenCL) << where;
    seen.onDevice += g.stats.backendUsed == Backend::OpenCL;
    EXPECT_EQ(e.candidatePairs, g.candidatePairs) << where;
    EXPECT_EQ(e.intersectingPairs, g.intersectingPairs) << where;
    EXPECT_EQ(e.stats.triangleTests, g.stats.triangleTests) << where;
    seen.candidates += e.candidatePairs.size();
    seen.intersecting += e.intersectingPairs.size();
    EXPECT_EQ(e.contacts.size(), g.contacts.size()) << where;
    if (e.contacts.size() == g.contacts.size()) {
      for (std::size_t c = 0; c < e.contacts.size(); ++c) {
        expectContactNear(e.contacts[c], g.contacts[c], scale, where + " contact " + std::to_string(c));
        seen.bitIdentical += e.contacts[c].pointWorld == g.contacts[c].pointWorld &&
                             e.contacts[c].normalWorldOnB == g.contacts[c].normalWorldOnB &&
                             e.contacts[c].depth == g.contacts[c].depth;
      }
      seen.contacts += e.contacts.size();
    }
    EXPECT_EQ(e.reducedContacts.size(), g.reducedContacts.size()) << where;
    if (e.reducedContacts.size() == g.reducedContacts.size()) {
      for (std::size_t c = 0; c < e.reducedContacts.size(); ++c) {
        expectContactNear(e.reducedContacts[c], g.reducedContacts[c], scale,
                          where + " reduced " + std::to_string(c));
      }
    }
  }
  return seen;
}

MeshPairQuery query(const MeshShape& a, const btTransform& ta, const MeshShape& b, const btTransform& tb) {
  return MeshPairQuery{&a, ta, &b, tb};
}

/// The thesis scene on a real mesh (the benchmark's): the mesh centred on its vertex centroid, one shape, and
/// the two poses of scenes::thesisPose.
struct ThesisScene {
  explicit ThesisScene(const std::string& path)
      : mesh(sharedMesh(scenes::centredOnVertexCentroid(loadMesh(path)))),
        shape(mesh),
        pose(scenes::thesisPose(*mesh)) {}
  std::shared_ptr<const TriangleMesh> mesh;
  MeshShape shape;
  scenes::PairPose pose;
  /// The scene's pair as one query of a batch.
  MeshPairQuery pair() const { return query(shape, pose.a, shape, pose.b); }
};

TEST(MeshPipeline, RealMeshesAtRandomPoses) {
  GPUCOL_REQUIRE_OPENCL(context);
  GPUCOL_REQUIRE_MESH(armadilloPath, "armadillo-2766.ply");
  GPUCOL_REQUIRE_MESH(bunnyPath, "bunny-948.ply");
  const auto armadillo = sharedMesh(scenes::centredOnVertexCentroid(loadMesh(armadilloPath)));
  const auto bunny = sharedMesh(scenes::centredOnVertexCentroid(loadMesh(bunnyPath)));
  MeshShape a(armadillo), b(bunny);
  b.setLocalScaling(btVector3(90.0f, 1.2f * 90.0f, 0.8f * 90.0f));
  std::mt19937 rng(20261121);
  std::vector<MeshPairQuery> queries;
  for (int pose = 0; pose < 4; ++pose) {
    const btTransform ta = randomPose(rng, btVector3(0, 0, 0), 0);
    queries.push_back(query(a, ta, b, randomPose(rng, btVector3(0, 0, 0), 25.0f)));
  }
  const Compared seen = expectSameAsCpu(queries, 100.0f);
  EXPECT_GT(seen.intersecting, 100u) << "the poses should make the meshes cross";
  std::cout << "[          ] " << seen.bitIdentical << " of " << seen.contacts << " contacts bit-identical\n";
}

TEST(MeshPipeline, ThesisSceneBothWalksAtEveryStartDepthWithAndWithoutEarlyOut) {
  GPUCOL_REQUIRE_OPENCL(context);
  GPUCOL_REQUIRE_MESH(path, "armadillo-27674.ply");
  const ThesisScene scene(path);
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  const std::uint64_t cpuNodeTests =
      collideMeshes(scene.shape, scene.pose.a, scene.shape, scene.pose.b, cpu).stats.nodeTests;
  DeviceOptionsGuard guard;
  for (MeshTraversal traversal : {MeshTraversal::DepthFirst, MeshTraversal::BreadthFirst}) {
    for (int depth : {0, 1, 3, 6}) {
      for (bool prefilter : {true, false}) {
        for (CandidateSort sort : {CandidateSort::Device, CandidateSort::Host}) {
          MeshBatchDeviceOptions options;
          options.traversal = traversal;
          // Depth-first: the start front at the same depths (0 = one work-item walks the whole tree pair).
          options.startDepth = depth;
          options.depthFirstStartDepth = depth;
          options.nearPrefilter = prefilter;
          options.candidateSort = sort;
          detail::setMeshDeviceOptions(options);
          SCOPED_TRACE(std::string(traversal == MeshTraversal::DepthFirst ? "depth-first" : "breadth-first") +
                       ", start depth " + std::to_string(depth) +
                       (prefilter ? ", early-out" : ", no early-out") +
                       (sort == CandidateSort::Device ? ", device sort" : ", host sort"));
          const Compared seen = expectSameAsCpu({scene.pair()}, 100.0f);
          EXPECT_GT(seen.intersecting, 100u);
          // Larger than one work-group of this device: the launches span several groups.
          EXPECT_GT(seen.candidates, context.device().getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>());
          // Both walks make the same box tests (the CPU's count, root test included) whatever the start
          // depth.
          if (traversal == MeshTraversal::DepthFirst || depth == 0) {
            EXPECT_EQ(detail::lastMeshDeviceStats().nodeTests, cpuNodeTests);
          }
        }
      }
    }
  }
}

// The default path reads counters, keys and hits behind the kernels in one wait, as many as the last batch
// had plus an eighth, and the rest after: a large batch after a small one reads most of its lists late, a
// small one after a large one reads more than it needs. Both, and the timed path with a wait after the
// traversal, must give the CPU's lists.
TEST(MeshPipeline, OneWaitReadsWhatItsGuessMissed) {
  GPUCOL_REQUIRE_OPENCL(context);
  GPUCOL_REQUIRE_MESH(path, "armadillo-2766.ply");
  const ThesisScene armadillo(path);
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(1.0f, 2)));
  const btTransform ta(btQuaternion(btVector3(0, 1, 1), 0.3f), btVector3(0, 0, 0));
  const btTransform tb(btQuaternion(btVector3(1, 0, 1), 1.1f), btVector3(1.9f, 0, 0));
  DeviceOptionsGuard guard;
  for (bool splitTimes : {false, true}) {
    MeshBatchDeviceOptions options;
    options.splitTimes = splitTimes;
    detail::setMeshDeviceOptions(options);
    SCOPED_TRACE(splitTimes ? "wait after the traversal" : "one wait");
    for (bool large : {true, false, true, true, false}) {
      const Compared seen = large ? expectSameAsCpu({armadillo.pair()}, 100.0f)
                                  : expectSameAsCpu({query(sphere, ta, sphere, tb)}, 3.0f);
      EXPECT_GT(seen.intersecting, large ? 100u : 0u);
    }
  }
}

TEST(MeshPipeline, FarFromTheOrigin) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape a(sharedMesh(scenes::makeTorus(1.0f, 0.3f, 48, 16))),
      b(sharedMesh(scenes::makeIcosphere(0.5f, 3)));
  std::mt19937 rng(7);
  const btVector3 farAway(1.0e4f, -2.0e4f, 3.0e3f);
  std::vector<MeshPairQuery> queries;
  for (int pose = 0; pose < 3; ++pose) {
    const btTransform ta = randomPose(rng, farAway, 0);
    queries.push_back(query(a, ta, b, randomPose(rng, farAway, 1.0f)));
  }
  // World points are ~2e4 from the origin: float tolerance is relative to that.
  EXPECT_GT(expectSameAsCpu(queries, 2.0e4f).intersecting, 10u);
}

TEST(MeshPipeline, RootBoxMissesNeverReachTheDeviceAndZeroCandidatePairsWork) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(1.0f, 2)));
  MeshShape small(sharedMesh(scenes::makeIcosphere(0.25f, 2)));
  MeshShape torus(sharedMesh(scenes::makeTorus(1.0f, 0.3f, 32, 12)));
  btTransform apart = btTransform::getIdentity();
  apart.setOrigin(btVector3(2.5f, 0, 0));
  // A small sphere in the torus's hole: the root boxes overlap, no triangle boxes do.
  const btTransform identity = btTransform::getIdentity();
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  const MeshPairResult hole = collideMeshes(torus, identity, small, identity, cpu);
  ASSERT_FALSE(hole.stats.rootBoxesMissed);
  ASSERT_TRUE(hole.candidatePairs.empty());
  const Compared seen = expectSameAsCpu({query(sphere, identity, sphere, apart)}, 1.0f);
  EXPECT_EQ(seen.onDevice, 0u);
  EXPECT_EQ(expectSameAsCpu({query(torus, identity, small, identity)}, 1.0f).onDevice, 1u);
  // Mixed in one batch: the miss stays on the CPU, the empty pair and a crossing pair on the device.
  btTransform crossing = identity;
  crossing.setOrigin(btVector3(1.2f, 0, 0));
  const Compared mixed =
      expectSameAsCpu({query(sphere, identity, sphere, apart), query(torus, identity, small, identity),
                       query(torus, identity, sphere, crossing)},
                      2.0f);
  EXPECT_EQ(mixed.onDevice, 2u);
  EXPECT_GT(mixed.intersecting, 0u);
}

TEST(MeshPipeline, BoxesRestingAndTouchingFaceOnFace) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 4)));
  MeshShape ground(sharedMesh(scenes::makeBox(3.0f, 3.0f, 1.0f, 1)));
  MeshShape top2(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  MeshShape ground2(sharedMesh(scenes::makeBox(2.0f, 2.0f, 0.5f, 1)));
  std::vector<MeshPairQuery> queries;
  std::vector<btTransform> poses;
  for (float sink : {0.01f, 0.002f}) {
    for (float yaw : {0.0f, 0.6f}) {
      poses.emplace_back(btQuaternion(btVector3(0, 0, 1), yaw), btVector3(0.2f, -0.1f, 0.5f - sink));
    }
  }
  const btTransform tGround(btQuaternion::getIdentity(), btVector3(0, 0, -1.0f));
  for (const btTransform& t : poses) queries.push_back(query(top, t, ground, tGround));
  // Face on face: the coplanar branch of the near phase.
  const btTransform tTop2(btQuaternion::getIdentity(), btVector3(0, 0, 0.5f));
  const btTransform tGround2(btQuaternion::getIdentity(), btVector3(0, 0, -0.5f));
  queries.push_back(query(top2, tTop2, ground2, tGround2));
  const Compared seen = expectSameAsCpu(queries, 3.0f);
  EXPECT_GT(seen.contacts, 20u);
}

// tests/stress/special_contacts_test.cpp's NeedleInTheOtherPlaneGivesAFiniteContact as two one-triangle
// meshes: a needle 1e-44 wide in the other triangle's plane, where the coplanar overlap once divided 0 by 0
// (CPU fixed in 4429c70, the kernel's copy since). The device must give the CPU's finite contact.
TEST(MeshPipeline, NeedleInTheOtherPlaneGivesTheCpusFiniteContact) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape needle(sharedMesh(TriangleMesh::fromArrays(
      {4.20389539e-45f, 1.12103877e-44f, 0, 0, 0, 1, 0, 0, 0}, {0, 1, 2}, "needle")));
  MeshShape other(sharedMesh(TriangleMesh::fromArrays(
      {1, 0, 0.5f, 0.5f, 0, 2.3509887e-38f, -6.52687105e-24f, 1.0354888e-38f, 0}, {0, 1, 2}, "other")));
  const btTransform identity = btTransform::getIdentity();
  DeviceOptionsGuard guard;
  for (bool prefilter : {true, false}) {
    MeshBatchDeviceOptions options;
    options.nearPrefilter = prefilter;
    detail::setMeshDeviceOptions(options);
    SCOPED_TRACE(prefilter ? "early-out" : "no early-out");
    const Compared seen = expectSameAsCpu({query(needle, identity, other, identity)}, 1.0f);
    EXPECT_EQ(seen.onDevice, 1u);
    EXPECT_EQ(seen.intersecting, 1u);
    EXPECT_EQ(seen.contacts, 1u);
    Config cl;
    cl.meshBackend = Backend::OpenCL;
    for (const MeshContact& c : collideMeshes(needle, identity, other, identity, cl).contacts) {
      EXPECT_TRUE(std::isfinite(c.pointWorld.x()) && std::isfinite(c.pointWorld.y()) &&
                  std::isfinite(c.pointWorld.z()));
      EXPECT_TRUE(std::isfinite(c.depth));
    }
  }
}

TEST(MeshPipeline, TwoSpheresAtKnownOverlap) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape sphere3(sharedMesh(scenes::makeIcosphere(1.0f, 3))),
      sphere4(sharedMesh(scenes::makeIcosphere(1.0f, 4)));
  const btVector3 axis = btVector3(1, 2, 0.5f).normalized();
  const btVector3 centreA(5, 5, 5), centreB = centreA + axis * 1.9f;
  const btTransform ta(btQuaternion(btVector3(0, 1, 1), 0.3f), centreA);
  const btTransform tb(btQuaternion(btVector3(1, 0, 1), 1.1f), centreB);
  EXPECT_GT(
      expectSameAsCpu({query(sphere3, ta, sphere3, tb), query(sphere4, ta, sphere4, tb)}, 7.0f).contacts,
      20u);
}

TEST(MeshPipeline, ScaledAndMirroredShapes) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape torus(sharedMesh(scenes::makeTorus(1.0f, 0.35f, 40, 16)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.6f, 3)));
  MeshShape mirrored(sharedMesh(scenes::makeLShape(1.2f, 0.5f)));
  torus.setLocalScaling(btVector3(1.5f, 0.7f, 1.2f));
  sphere.setLocalScaling(btVector3(0.8f, 1.3f, 1.0f));
  mirrored.setLocalScaling(btVector3(-1.0f, 1.1f, 0.9f));  // a mirror: the pipeline swaps two vertices
  std::mt19937 rng(99);
  std::vector<MeshPairQuery> queries;
  for (int pose = 0; pose < 3; ++pose) {
    const btTransform ta = randomPose(rng, btVector3(0, 0, 0), 0);
    queries.push_back(query(torus, ta, sphere, randomPose(rng, btVector3(0, 0, 0), 1.2f)));
    queries.push_back(query(mirrored, ta, torus, randomPose(rng, btVector3(0, 0, 0), 0.8f)));
  }
  EXPECT_GT(expectSameAsCpu(queries, 3.0f).contacts, 20u);
}

// Shapes with margins: the device's middle phase is widened by them and the contacts of triangles closer than
// the margins join the crossing ones, as on the CPU. Boxes hovering within their margins of a ground (no
// triangle crosses), scaled tori and spheres near each other.
TEST(MeshPipeline, ShapesWithMarginsGiveTheCpusProximityContacts) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  MeshShape ground(sharedMesh(scenes::makeBox(3.0f, 3.0f, 1.0f, 1)));
  MeshShape torus(sharedMesh(scenes::makeTorus(1.0f, 0.35f, 40, 16)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.6f, 3)));
  top.setMargin(0.01f);
  ground.setMargin(0.02f);
  torus.setMargin(0.03f);
  sphere.setMargin(0.01f);
  torus.setLocalScaling(btVector3(1.5f, 0.7f, 1.2f));
  const btTransform tGround(btQuaternion::getIdentity(), btVector3(0, 0, -1.0f));
  std::vector<MeshPairQuery> queries;
  for (float gap : {0.0f, 0.01f, 0.025f}) {
    for (float yaw : {0.0f, 0.6f}) {
      queries.push_back(query(top, btTransform(btQuaternion(btVector3(0, 0, 1), yaw), btVector3(0.2f, -0.1f, 0.5f + gap)),
                              ground, tGround));
    }
  }
  std::mt19937 rng(7);
  for (int pose = 0; pose < 4; ++pose) {
    queries.push_back(query(torus, randomPose(rng, btVector3(0, 0, 0), 0), sphere,
                            randomPose(rng, btVector3(0, 0, 0), 1.4f)));
  }
  const Compared seen = expectSameAsCpu(queries, 3.0f);
  EXPECT_GT(seen.contacts, 20u);
  // Not vacuous: the hovering boxes touch only through their margins.
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  const MeshPairResult hovering = collideMeshes(top, queries[2].transformA, ground, tGround, cpu);
  EXPECT_TRUE(hovering.intersectingPairs.empty());
  EXPECT_FALSE(hovering.contacts.empty());
}

// Speculative reaches (a distance every way and a motion) over pairs of many candidates: on the CPU the
// proximity contacts come from the near phase's own chunks of rows, on the device's path from a pass of their
// own after the device's near phase; both give the same contacts, chunk after chunk, crossing pairs left out.
TEST(MeshPipeline, SpeculativeReachGivesTheCpusContactsOverManyChunks) {
  GPUCOL_REQUIRE_OPENCL(context);
  MeshShape torus(sharedMesh(scenes::makeTorus(1.0f, 0.35f, 40, 16)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.6f, 3)));
  std::mt19937 rng(11);
  std::vector<MeshPairQuery> queries;
  for (int pose = 0; pose < 6; ++pose) {
    MeshPairQuery q = query(torus, randomPose(rng, btVector3(0, 0, 0), 0), sphere,
                            randomPose(rng, btVector3(0, 0, 0), 1.2f + 0.1f * float(pose % 3)));
    q.speculativeDistance = 0.05f + 0.02f * float(pose);
    q.speculativeMotion = btVector3(0.03f, -0.08f, 0.02f);
    queries.push_back(q);
  }
  const Compared seen = expectSameAsCpu(queries, 3.0f);
  // Not vacuous: several chunks of candidates (512 each), pairs that cross and pairs that only come near.
  EXPECT_GT(seen.candidates, 6u * 1024u);
  EXPECT_GT(seen.intersecting, 0u);
  EXPECT_GT(seen.contacts, seen.intersecting + 100u);
}

TEST(MeshPipeline, LeavesOfSeveralTriangles) {
  GPUCOL_REQUIRE_OPENCL(context);
  Config four;
  four.trianglesPerLeaf = 4;
  Config three;
  three.trianglesPerLeaf = 3;
  const auto torusMesh = sharedMesh(scenes::makeTorus(1.0f, 0.3f, 48, 16));
  const auto sphereMesh = sharedMesh(scenes::makeIcosphere(0.6f, 3));
  MeshShape torus4(torusMesh, four), sphere3(sphereMesh, three), torus1(torusMesh);
  std::mt19937 rng(11);
  std::vector<MeshPairQuery> queries;
  for (int pose = 0; pose < 3; ++pose) {
    const btTransform ta = randomPose(rng, btVector3(0, 0, 0), 0);
    queries.push_back(query(torus4, ta, sphere3, randomPose(rng, btVector3(0, 0, 0), 1.0f)));
    queries.push_back(query(torus1, ta, torus4, randomPose(rng, btVector3(0, 0, 0), 0.5f)));
  }
  EXPECT_GT(expectSameAsCpu(queries, 2.0f).intersecting, 50u);
}

// Batches of 1, 7 and 100 pairs of mixed meshes in one traversal front.
TEST(MeshPipeline, MixedBatchesOfOneSevenAndAHundredPairs) {
  GPUCOL_REQUIRE_OPENCL(context);
  const std::vector<std::shared_ptr<MeshShape>> shapes = {
      std::make_shared<MeshShape>(sharedMesh(scenes::makeTorus(1.0f, 0.3f, 32, 12))),
      std::make_shared<MeshShape>(sharedMesh(scenes::makeIcosphere(0.7f, 3))),
      std::make_shared<MeshShape>(sharedMesh(scenes::makeBox(0.6f, 0.4f, 0.5f, 3))),
      std::make_shared<MeshShape>(sharedMesh(scenes::makeLShape(1.5f, 0.5f)))};
  std::mt19937 rng(5);
  for (int size : {1, 7, 100}) {
    std::vector<MeshPairQuery> queries;
    for (int i = 0; i < size; ++i) {
      queries.push_back(query(*shapes[i % 4], randomPose(rng, btVector3(0, 0, 0), 0.2f),
                              *shapes[(i * 3 + 1) % 4], randomPose(rng, btVector3(0, 0, 0), 1.0f)));
    }
    SCOPED_TRACE("batch of " + std::to_string(size));
    const Compared seen = expectSameAsCpu(queries, 3.0f);
    if (size == 100) {
      EXPECT_GT(seen.contacts, 100u);
      EXPECT_GT(seen.onDevice, 50u);
    }
  }
}

TEST(MeshPipeline, MeshesStayResidentUntilTheirLastOwnerIsGone) {
  GPUCOL_REQUIRE_OPENCL(context);
  Config config;
  config.meshBackend = Backend::OpenCL;
  MeshBatchDevice* device = sharedMeshBatchDevice(config);
  ASSERT_NE(device, nullptr);
  MeshShape keep(sharedMesh(scenes::makeIcosphere(1.0f, 2)));
  const btTransform identity = btTransform::getIdentity();
  btTransform near = identity;
  near.setOrigin(btVector3(1.5f, 0, 0));
  collideMeshes(keep, identity, keep, near, config);
  const std::size_t before = device->residentMeshes();
  {
    MeshShape temporary(sharedMesh(scenes::makeTorus(1.0f, 0.3f, 24, 8)));
    const MeshPairResult r = collideMeshes(keep, identity, temporary, near, config);
    EXPECT_EQ(r.stats.backendUsed, Backend::OpenCL);
    EXPECT_EQ(device->residentMeshes(), before + 1);
  }
  // The torus died with its shape: the next batch drops it, and results stay right after the arenas shrink.
  EXPECT_EQ(expectSameAsCpu({query(keep, identity, keep, near)}, 2.0f).onDevice, 1u);
  EXPECT_EQ(device->residentMeshes(), before);
  // A second batch of the same pair uploads nothing but its description.
  collideMeshes(keep, identity, keep, near, config);
  EXPECT_EQ(detail::lastMeshDeviceStats().uploadedBytes, sizeof(GpucolMeshPair));
}

TEST(MeshPipeline, AutoKeepsSmallBatchesAndCpuDevicesOnTheCpu) {
  GPUCOL_REQUIRE_OPENCL(context);
  GPUCOL_REQUIRE_MESH(path, "armadillo-27674.ply");
  const ThesisScene scene(path);
  // Auto starts every size on the CPU path, and on a CPU device stays there.
  for (int call = 0; call < 10; ++call) {
    const MeshPairResult r =
        collideMeshes(scene.shape, scene.pose.a, scene.shape, scene.pose.b);  // Backend::Auto
    if (call < 2 || !context.isGpu()) {
      EXPECT_EQ(r.stats.backendUsed, Backend::Cpu) << "call " << call;
    }
  }
  MeshShape small(sharedMesh(scenes::makeIcosphere(1.0f, 2)));
  btTransform near = btTransform::getIdentity();
  near.setOrigin(btVector3(1.5f, 0, 0));
  for (int call = 0; call < 10; ++call) {
    EXPECT_EQ(collideMeshes(small, btTransform::getIdentity(), small, near).stats.backendUsed, Backend::Cpu);
  }
}

/// Auto on PoCL's CPU device (AutoOnCpuDevice) with a fresh measured choice for mesh batches, for one test.
struct FreshMeshAutoOnCpuDevice {
  FreshMeshAutoOnCpuDevice() { detail::meshAutoChoice().reset(); }
  ~FreshMeshAutoOnCpuDevice() { detail::meshAutoChoice().reset(); }
  AutoOnCpuDevice autoOnCpu;
};

TEST(MeshPipeline, AutoMeasuresBothPathsThenKeepsOne) {
  GPUCOL_REQUIRE_OPENCL(context);
  GPUCOL_REQUIRE_MESH(path, "armadillo-27674.ply");
  const ThesisScene scene(path);
  // Eight pairs in one batch: several milliseconds on the CPU path, far above kDeviceWorthMs.
  std::vector<MeshPairQuery> queries;
  for (int i = 0; i < 8; ++i) queries.push_back(scene.pair());
  Config cpu;
  cpu.meshBackend = Backend::Cpu;
  const std::vector<MeshPairResult> expected = collideMeshesBatch(queries, cpu);
  ASSERT_FALSE(expected[0].intersectingPairs.empty());
  const std::uint64_t size = 8 * 2 * std::uint64_t(scene.mesh->triangleCount());

  const FreshMeshAutoOnCpuDevice autoOnCpu;
  // The measured sequence (MeasuredBackendChoice): two CPU calls, then the two paths in turn until each has
  // its uncounted call and three counted ones; then one path for good.
  const Backend measuring[] = {Backend::Cpu,    Backend::Cpu, Backend::OpenCL, Backend::OpenCL,
                               Backend::OpenCL, Backend::Cpu, Backend::OpenCL, Backend::Cpu};
  std::vector<Backend> used;
  for (int call = 0; call < 12; ++call) {
    EXPECT_EQ(detail::meshAutoChoice().decided(size).has_value(), call >= 8) << "call " << call;
    const std::vector<MeshPairResult> got = collideMeshesBatch(queries, Config{});  // Backend::Auto
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].stats.backendUsed, got[0].stats.backendUsed);
      EXPECT_EQ(got[i].candidatePairs, expected[i].candidatePairs) << "call " << call << " pair " << i;
      EXPECT_EQ(got[i].intersectingPairs, expected[i].intersectingPairs) << "call " << call << " pair " << i;
      EXPECT_EQ(got[i].contacts.size(), expected[i].contacts.size()) << "call " << call << " pair " << i;
    }
    used.push_back(got[0].stats.backendUsed);
    if (call < 8) {
      EXPECT_EQ(used.back(), measuring[call]) << "call " << call;
    }
  }
  const Backend kept = *detail::meshAutoChoice().decided(size) == MeasuredBackendChoice::Path::Device
                           ? Backend::OpenCL
                           : Backend::Cpu;
  for (int call = 8; call < 12; ++call) EXPECT_EQ(used[std::size_t(call)], kept) << "call " << call;
}

}  // namespace
}  // namespace gpucol::test
