// collideMeshes against references: a double-precision brute force over all triangle pairs (real meshes,
// random poses, non-uniform scaling), analytic answers (box resting on box, two spheres), and the scaled-copy
// equivalence of local scaling.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <iostream>
#include <map>
#include <set>

#include "bullet/mesh_pair_test_util.h"
#include "mesh_pairs/pair_frame.h"
#include "narrowphase/triangle_proximity.h"
#include "scenes/gimpact_peer.h"
#include "scenes/procedural_meshes.h"
#include "support/test_paths.h"

namespace gpucol::test {
namespace {

// Relative "almost touching" band: pairs whose double-precision separation is within this fraction of their
// size may be reported either way, because the float pipeline rounds coordinates by about 2^-24 of their
// magnitude and the triangle test snaps distances under 2^-20 (narrowphase/triangle_plane.h).
constexpr double kBand = 1e-5;

std::shared_ptr<const TriangleMesh> sharedMesh(TriangleMesh mesh) {
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

TriangleMesh scaledCopy(const TriangleMesh& mesh, const btVector3& scale) {
  std::vector<float> xyz = mesh.positions();
  for (std::size_t i = 0; i < xyz.size(); ++i) xyz[i] *= scale[int(i % 3)];
  return TriangleMesh::fromArrays(std::move(xyz), mesh.indices(), "scaled copy");
}

// Checks one query against the brute force; returns the number of clearly penetrating pairs it checked.
std::size_t expectMatchesBruteForce(const MeshShape& a, const btTransform& ta, const MeshShape& b,
                                    const btTransform& tb) {
  const MeshPairResult result = collideMeshes(a, ta, b, tb);
  EXPECT_TRUE(std::is_sorted(result.candidatePairs.begin(), result.candidatePairs.end()));
  EXPECT_TRUE(std::is_sorted(result.intersectingPairs.begin(), result.intersectingPairs.end()));
  const std::set<TrianglePair> candidates(result.candidatePairs.begin(), result.candidatePairs.end());
  const std::set<TrianglePair> intersecting(result.intersectingPairs.begin(), result.intersectingPairs.end());
  EXPECT_EQ(candidates.size(), result.candidatePairs.size()) << "duplicate candidate pairs";

  std::set<TrianglePair> nearPairs;
  std::size_t clear = 0, missedCandidates = 0, missedIntersecting = 0;
  for (const BruteForcePair& p : bruteForceNearPairs(a, ta, b, tb, kBand)) {
    nearPairs.insert(p.pair);
    if (p.separation <= 0 && !candidates.count(p.pair)) ++missedCandidates;
    if (p.separation < -kBand * p.scale) {
      ++clear;
      if (!intersecting.count(p.pair)) ++missedIntersecting;
    }
  }
  std::size_t falseIntersecting = 0;
  for (const TrianglePair& p : result.intersectingPairs) {
    falseIntersecting += nearPairs.count(p) == 0;
    EXPECT_TRUE(candidates.count(p)) << "an intersecting pair that is not a candidate";
  }
  EXPECT_EQ(missedCandidates, 0u) << "touching or intersecting pairs missing from the middle phase";
  EXPECT_EQ(missedIntersecting, 0u) << "clearly intersecting pairs the pipeline did not report";
  EXPECT_EQ(falseIntersecting, 0u) << "reported pairs farther apart than the band";
  return clear;
}

TEST(CollideMeshes, MatchesBruteForceOnRealMeshesAtRandomPoses) {
  GPUCOL_REQUIRE_MESH(armadilloPath, "armadillo-2766.ply");
  GPUCOL_REQUIRE_MESH(bunnyPath, "bunny-948.ply");
  const auto armadillo = sharedMesh(scenes::centredOnVertexCentroid(loadMesh(armadilloPath)));
  const auto bunny = sharedMesh(scenes::centredOnVertexCentroid(loadMesh(bunnyPath)));
  MeshShape a(armadillo);
  MeshShape b(bunny);
  // Bring the bunny to the armadillo's size with a non-uniform scale, so scaling is exercised too.
  const float s = largestSide(*armadillo) / largestSide(*bunny);
  b.setLocalScaling(btVector3(s, 1.2f * s, 0.8f * s));

  std::mt19937 rng(20261121);
  std::size_t clear = 0;
  for (int pose = 0; pose < 4; ++pose) {
    const btTransform ta = randomPose(rng, btVector3(0, 0, 0), 0);
    const btTransform tb = randomPose(rng, btVector3(0, 0, 0), 0.25f * largestSide(*armadillo));
    clear += expectMatchesBruteForce(a, ta, b, tb);
  }
  EXPECT_GT(clear, 100u) << "the poses should make the meshes cross";
}

TEST(CollideMeshes, MatchesBruteForceOnTheThesisScene) {
  GPUCOL_REQUIRE_MESH(path, "armadillo-2766.ply");
  const auto mesh = sharedMesh(scenes::centredOnVertexCentroid(loadMesh(path)));
  MeshShape shape(mesh);
  const scenes::PairPose pose = scenes::thesisPose(*mesh);
  EXPECT_GT(expectMatchesBruteForce(shape, pose.a, shape, pose.b), 100u);
}

TEST(CollideMeshes, MatchesBruteForceFarFromTheOrigin) {
  const auto torus = sharedMesh(scenes::makeTorus(1.0f, 0.3f, 48, 16));
  const auto sphere = sharedMesh(scenes::makeIcosphere(0.5f, 3));
  MeshShape a(torus), b(sphere);
  std::mt19937 rng(7);
  const btVector3 farAway(1.0e4f, -2.0e4f, 3.0e3f);
  std::size_t clear = 0;
  for (int pose = 0; pose < 3; ++pose) {
    clear += expectMatchesBruteForce(a, randomPose(rng, farAway, 0), b, randomPose(rng, farAway, 1.0f));
  }
  EXPECT_GT(clear, 10u);
}

TEST(CollideMeshes, RootBoxesThatMissSkipEverything) {
  const auto sphere = sharedMesh(scenes::makeIcosphere(1.0f, 2));
  MeshShape shape(sphere);
  btTransform ta = btTransform::getIdentity(), tb = btTransform::getIdentity();
  tb.setOrigin(btVector3(2.5f, 0, 0));
  const MeshPairResult result = collideMeshes(shape, ta, shape, tb);
  EXPECT_TRUE(result.stats.rootBoxesMissed);
  EXPECT_TRUE(result.candidatePairs.empty());
  EXPECT_EQ(result.stats.nodeTests, 1u);
  tb.setOrigin(btVector3(1.9f, 0, 0));
  EXPECT_FALSE(collideMeshes(shape, ta, shape, tb).stats.rootBoxesMissed);
}

// A box of 4 × 4 subdivisions per face resting on a ground box of one quad per face, sunk by `depth`: every
// contact comes from a side triangle of the top box crossing the ground's top face, which the top box leaves
// by moving up by `depth` (the ground's triangles would have to move metres sideways).
TEST(CollideMeshes, BoxRestingOnBoxGivesTheFaceNormalAndTheSinkDepth) {
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 4)));
  MeshShape ground(sharedMesh(scenes::makeBox(3.0f, 3.0f, 1.0f, 1)));
  for (float sink : {0.01f, 0.002f}) {
    for (float yaw : {0.0f, 0.6f}) {
      btTransform tTop(btQuaternion(btVector3(0, 0, 1), yaw), btVector3(0.2f, -0.1f, 0.5f - sink));
      btTransform tGround(btQuaternion::getIdentity(), btVector3(0, 0, -1.0f));
      const MeshPairResult result = collideMeshes(top, tTop, ground, tGround);
      ASSERT_FALSE(result.reducedContacts.empty());
      for (const MeshContact& c : result.contacts) {
        EXPECT_NEAR(c.normalWorldOnB.z(), 1.0f, 1e-5f);
        EXPECT_NEAR(c.depth, -sink, 1e-5f);
        // On the ground's face (the middle of a crossing), or a corner of the box's side halfway out.
        EXPECT_TRUE(std::abs(c.pointWorld.z()) < 1e-5f || std::abs(c.pointWorld.z() + 0.5f * sink) < 1e-5f)
            << c.pointWorld.z();
      }
      // The reduction keeps the footprint's corners: contacts spread over the whole box side.
      btVector3 lo(1e9f, 1e9f, 0), hi(-1e9f, -1e9f, 0);
      for (const MeshContact& c : result.reducedContacts) {
        lo.setMin(c.pointWorld);
        hi.setMax(c.pointWorld);
      }
      EXPECT_GT(hi.x() - lo.x(), 0.9f);
      EXPECT_GT(hi.y() - lo.y(), 0.9f);
      EXPECT_LT(result.reducedContacts.size(), result.contacts.size());
    }
  }
}

TEST(CollideMeshes, BoxesTouchingFaceOnFaceGiveZeroDepthContacts) {
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  MeshShape ground(sharedMesh(scenes::makeBox(2.0f, 2.0f, 0.5f, 1)));
  const btTransform tTop(btQuaternion::getIdentity(), btVector3(0, 0, 0.5f));
  const btTransform tGround(btQuaternion::getIdentity(), btVector3(0, 0, -0.5f));
  const MeshPairResult result = collideMeshes(top, tTop, ground, tGround);
  ASSERT_FALSE(result.contacts.empty());
  for (const MeshContact& c : result.contacts) {
    EXPECT_NEAR(c.depth, 0.0f, 1e-6f);
    EXPECT_NEAR(c.pointWorld.z(), 0.0f, 1e-6f);
  }
}

// Two triangulated spheres of radius 1 whose centres are 2 - p apart overlap by p. Their surfaces cross on a
// known circle, and only triangles on it intersect (thesis §5.3.4 contacts come from intersecting triangle
// pairs): every contact lies on that circle, its normal is one of the two spheres' normals there, and its
// depth is at most the overlap. (A contact's depth is local to its triangle pair, so it is bounded by the
// triangles' size as well; the solver gets the body's penetration from several steps of such contacts.)
TEST(CollideMeshes, TwoSpheresAtKnownOverlap) {
  for (int levels : {3, 4}) {
    MeshShape sphere(sharedMesh(scenes::makeIcosphere(1.0f, levels)));
    const float overlap = 0.1f;
    const btVector3 axis = btVector3(1, 2, 0.5f).normalized();
    const btVector3 centreA(5, 5, 5), centreB = centreA + axis * (2.0f - overlap);
    const btTransform ta(btQuaternion(btVector3(0, 1, 1), 0.3f), centreA);
    const btTransform tb(btQuaternion(btVector3(1, 0, 1), 1.1f), centreB);
    const MeshPairResult result = collideMeshes(sphere, ta, sphere, tb);
    ASSERT_GT(result.reducedContacts.size(), 4u);
    // Icosahedron edge 1.05 (unit circumradius), halved per level; a chord's sag below the true sphere.
    const float edge = 1.06f / std::pow(2.0f, float(levels));
    const float sag = 1.0f - std::sqrt(1.0f - edge * edge / 3.0f);
    const btVector3 circleCentre = centreA + axis * (1.0f - overlap / 2);
    const float circleRadius = std::sqrt(1.0f - (1.0f - overlap / 2) * (1.0f - overlap / 2));
    btVector3 meanNormal(0, 0, 0);
    for (const MeshContact& c : result.contacts) {
      const btVector3 fromCentre = c.pointWorld - circleCentre;
      const float along = fromCentre.dot(axis);
      const float radial = (fromCentre - axis * along).length();
      EXPECT_LT(std::abs(along), edge) << "levels " << levels;
      EXPECT_LT(std::abs(radial - circleRadius), edge) << "levels " << levels;
      // The normal on B towards A is B's outward normal there or minus A's (both unit vectors at the point).
      const btVector3 normalOfB = (c.pointWorld - centreB).normalized();
      const btVector3 minusNormalOfA = -(c.pointWorld - centreA).normalized();
      const float best = std::max(c.normalWorldOnB.dot(normalOfB), c.normalWorldOnB.dot(minusNormalOfA));
      EXPECT_GT(best, std::cos(2 * edge)) << "levels " << levels;
      EXPECT_LE(c.depth, 0.0f);
      EXPECT_GE(c.depth, -(overlap + 2 * sag)) << "levels " << levels;
      meanNormal += c.normalWorldOnB;
    }
    // B is at +axis from A, so the normal on B pointing towards A is -axis on average.
    EXPECT_GT(meanNormal.normalized().dot(-axis), 0.95f) << "levels " << levels;
  }
}

TEST(CollideMeshes, LocalScalingEqualsAScaledCopyOfTheMesh) {
  const TriangleMesh torus = scenes::makeTorus(1.0f, 0.35f, 40, 16);
  const TriangleMesh sphere = scenes::makeIcosphere(0.6f, 3);
  const btVector3 scaleA(1.5f, 0.7f, 1.2f), scaleB(0.8f, 1.3f, 1.0f);
  MeshShape scaledA(sharedMesh(torus)), scaledB(sharedMesh(sphere));
  scaledA.setLocalScaling(scaleA);
  scaledB.setLocalScaling(scaleB);
  MeshShape copyA(sharedMesh(scaledCopy(torus, scaleA)));
  MeshShape copyB(sharedMesh(scaledCopy(sphere, scaleB)));
  std::mt19937 rng(99);
  for (int pose = 0; pose < 3; ++pose) {
    const btTransform ta = randomPose(rng, btVector3(0, 0, 0), 0);
    const btTransform tb = randomPose(rng, btVector3(0, 0, 0), 1.2f);
    const MeshPairResult scaled = collideMeshes(scaledA, ta, scaledB, tb);
    const MeshPairResult copied = collideMeshes(copyA, ta, copyB, tb);
    ASSERT_FALSE(copied.contacts.empty());
    // The same pairs, bar the float rounding of scaling before or during the query, which only matters for
    // pairs in the touching band: they must agree on all but a handful.
    std::vector<TrianglePair> difference;
    std::set_symmetric_difference(scaled.intersectingPairs.begin(), scaled.intersectingPairs.end(),
                                  copied.intersectingPairs.begin(), copied.intersectingPairs.end(),
                                  std::back_inserter(difference));
    EXPECT_LE(difference.size(), 2u);
    std::size_t compared = 0;
    // The deepest contact of each pair: a mirroring scale clips the triangles' corners in another order.
    const std::vector<MeshContact> scaledDeepest = deepestContactPerPair(scaled.contacts);
    const std::vector<MeshContact> copiedDeepest = deepestContactPerPair(copied.contacts);
    for (const MeshContact& c : scaledDeepest) {
      for (const MeshContact& d : copiedDeepest) {
        if (c.triangleA != d.triangleA || c.triangleB != d.triangleB) continue;
        ++compared;
        EXPECT_LT((c.pointWorld - d.pointWorld).length(), 1e-4f);
        EXPECT_GT(c.normalWorldOnB.dot(d.normalWorldOnB), 1.0f - 1e-5f);
        EXPECT_NEAR(c.depth, d.depth, 1e-4f);
      }
    }
    EXPECT_GE(compared + 2, copiedDeepest.size());
  }
}

TEST(CollideMeshes, BatchGivesTheSameResultsAsSingleQueriesInOrder) {
  const auto torus = std::make_shared<MeshShape>(sharedMesh(scenes::makeTorus(1.0f, 0.3f, 32, 12)));
  const auto sphere = std::make_shared<MeshShape>(sharedMesh(scenes::makeIcosphere(0.7f, 3)));
  const auto box = std::make_shared<MeshShape>(sharedMesh(scenes::makeBox(0.6f, 0.4f, 0.5f, 3)));
  const auto lShape = std::make_shared<MeshShape>(sharedMesh(scenes::makeLShape(1.5f, 0.5f)));
  const std::vector<std::shared_ptr<MeshShape>> shapes = {torus, sphere, box, lShape};
  std::mt19937 rng(5);
  std::vector<MeshPairQuery> queries;
  for (int i = 0; i < 7; ++i) {
    MeshPairQuery q;
    q.shapeA = shapes[i % 4].get();
    q.shapeB = shapes[(i * 3 + 1) % 4].get();
    q.transformA = randomPose(rng, btVector3(0, 0, 0), 0.2f);
    q.transformB = randomPose(rng, btVector3(0, 0, 0), 1.0f);
    queries.push_back(q);
  }
  const std::vector<MeshPairResult> batch = collideMeshesBatch(queries);
  ASSERT_EQ(batch.size(), queries.size());
  std::size_t contacts = 0;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const MeshPairResult single =
        collideMeshes(*queries[i].shapeA, queries[i].transformA, *queries[i].shapeB, queries[i].transformB);
    EXPECT_EQ(batch[i].candidatePairs, single.candidatePairs) << "query " << i;
    EXPECT_EQ(batch[i].intersectingPairs, single.intersectingPairs) << "query " << i;
    ASSERT_EQ(batch[i].reducedContacts.size(), single.reducedContacts.size()) << "query " << i;
    for (std::size_t c = 0; c < single.reducedContacts.size(); ++c) {
      EXPECT_EQ(batch[i].reducedContacts[c].pointWorld, single.reducedContacts[c].pointWorld);
      EXPECT_EQ(batch[i].reducedContacts[c].depth, single.reducedContacts[c].depth);
    }
    contacts += single.contacts.size();
  }
  EXPECT_GT(contacts, 0u);
  EXPECT_TRUE(collideMeshesBatch({}).empty());
}

TEST(CollideMeshes, OneThreadAndManyThreadsGiveIdenticalResults) {
  const auto torus = sharedMesh(scenes::makeTorus(1.0f, 0.3f, 96, 32));
  MeshShape a(torus), b(torus);
  const btTransform ta = btTransform::getIdentity();
  const btTransform tb(btQuaternion(btVector3(1, 0, 0), 1.5708f), btVector3(0.5f, 0.2f, 0));
  const MeshPairResult many = collideMeshes(a, ta, b, tb);
  MeshPairResult one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = collideMeshes(a, ta, b, tb);
  }
  ASSERT_FALSE(many.contacts.empty());
  EXPECT_EQ(one.candidatePairs, many.candidatePairs);
  EXPECT_EQ(one.intersectingPairs, many.intersectingPairs);
  ASSERT_EQ(one.contacts.size(), many.contacts.size());
  for (std::size_t i = 0; i < one.contacts.size(); ++i) {
    EXPECT_EQ(one.contacts[i].pointWorld, many.contacts[i].pointWorld);
    EXPECT_EQ(one.contacts[i].normalWorldOnB, many.contacts[i].normalWorldOnB);
  }
  ASSERT_EQ(one.reducedContacts.size(), many.reducedContacts.size());
}

TEST(CollideMeshes, BadInputGetsAClearError) {
  MeshShape shape(sharedMesh(scenes::makeIcosphere(1.0f, 1)));
  btTransform bad = btTransform::getIdentity();
  bad.setOrigin(btVector3(std::nanf(""), 0, 0));
  try {
    collideMeshes(shape, btTransform::getIdentity(), shape, bad);
    FAIL() << "a NaN transform must be rejected";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("shape B"), std::string::npos) << e.what();
  }
  MeshPairQuery nullQuery;
  nullQuery.shapeA = &shape;
  EXPECT_THROW(collideMeshesBatch({nullQuery}), std::invalid_argument);
  EXPECT_THROW(shape.setLocalScaling(btVector3(1, 0, 1)), MeshError);
  EXPECT_THROW(shape.setLocalScaling(btVector3(1, std::numeric_limits<float>::infinity(), 1)), MeshError);
  EXPECT_THROW(MeshShape(nullptr), MeshError);
  for (btScalar speculative : {btScalar(-0.1), std::numeric_limits<btScalar>::quiet_NaN(),
                               std::numeric_limits<btScalar>::infinity()}) {
    MeshPairQuery query{&shape, btTransform::getIdentity(), &shape, btTransform::getIdentity()};
    query.speculativeDistance = speculative;
    try {
      collideMeshes(query);
      FAIL() << "speculative distance " << speculative << " must be rejected";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("speculative distance"), std::string::npos) << e.what();
    }
  }
  MeshPairQuery nanMotion{&shape, btTransform::getIdentity(), &shape, btTransform::getIdentity()};
  nanMotion.speculativeMotion = btVector3(0, std::numeric_limits<btScalar>::quiet_NaN(), 0);
  EXPECT_THROW(collideMeshes(nanMotion), std::invalid_argument);
  EXPECT_THROW(collideMeshesBatch({nanMotion}), std::invalid_argument);
}

// The same box given a motion instead of a distance: moving towards the ground (or away: the search widens
// both ways along the motion) by 1.5 times the gap it gets the face's contacts at the gap; moving as far
// sideways it gets none, for the search does not widen across the motion.
TEST(CollideMeshes, SpeculativeSearchWidensAlongTheMotion) {
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  MeshShape ground(sharedMesh(scenes::makeBox(3.0f, 3.0f, 1.0f, 1)));
  const float gap = 0.05f;
  // B (the ground) moves relative to A (the box).
  const btVector3 towards(0, 0, 1.5f * gap), away(0, 0, -1.5f * gap), sideways(1.5f * gap, 0, 0);
  for (float yaw : {0.0f, 0.6f}) {
    MeshPairQuery query{
        &top, btTransform(btQuaternion(btVector3(0, 0, 1), yaw), btVector3(0.2f, -0.1f, 0.5f + gap)), &ground,
        btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -1.0f))};
    for (const btVector3& motion : {towards, away}) {
      query.speculativeMotion = motion;
      const MeshPairResult result = collideMeshes(query);
      ASSERT_FALSE(result.contacts.empty());
      int atGap = 0;
      for (const MeshContact& c : result.contacts) {
        EXPECT_GE(c.depth, gap - 1e-5f);
        atGap += std::fabs(c.depth - gap) < 1e-5f && c.normalWorldOnB.z() > 1 - 1e-5f;
      }
      EXPECT_GE(atGap, 4);
    }
    query.speculativeMotion = sideways;
    EXPECT_TRUE(collideMeshes(query).contacts.empty());
    EXPECT_TRUE(collideMeshes(query).candidatePairs.empty());
  }
}

// A box `gap` above a ground box, turned about the vertical: with a speculative distance beyond the gap, its
// bottom face's corners give contacts at exactly the gap (positive: separated), along the ground's normal,
// and no contact claims the bodies closer than that (farther features give farther contacts); with a
// speculative distance short of the gap, or none, there are no contacts. Without margins, as for every other
// check.
TEST(CollideMeshes, SpeculativeContactsComeAtTheGapAlongTheFaceNormal) {
  MeshShape top(sharedMesh(scenes::makeBox(0.5f, 0.5f, 0.5f, 2)));
  MeshShape ground(sharedMesh(scenes::makeBox(3.0f, 3.0f, 1.0f, 1)));
  for (float gap : {0.004f, 0.05f, 0.3f}) {
    for (float yaw : {0.0f, 0.6f}) {
      MeshPairQuery query{
          &top, btTransform(btQuaternion(btVector3(0, 0, 1), yaw), btVector3(0.2f, -0.1f, 0.5f + gap)),
          &ground, btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -1.0f))};
      EXPECT_TRUE(collideMeshes(query).contacts.empty()) << gap;
      query.speculativeDistance = 0.9f * gap;
      EXPECT_TRUE(collideMeshes(query).contacts.empty()) << gap;
      query.speculativeDistance = 1.5f * gap;
      const MeshPairResult result = collideMeshes(query);
      ASSERT_FALSE(result.reducedContacts.empty()) << gap;
      EXPECT_TRUE(result.intersectingPairs.empty());
      btVector3 lo(1e9f, 1e9f, 0), hi(-1e9f, -1e9f, 0);
      for (const MeshContact& c : result.contacts) {
        EXPECT_GT(c.normalWorldOnB.z(), 0.5f);
        EXPECT_GE(c.depth, gap - 1e-5f);
        EXPECT_LT(c.depth, query.speculativeDistance);
        if (c.normalWorldOnB.z() > 1 - 1e-5f) {
          EXPECT_NEAR(c.depth, gap, 1e-5f);
          EXPECT_NEAR(c.pointOnBWorld.z(), 0.0f, 1e-5f);
          lo.setMin(c.pointOnBWorld);
          hi.setMax(c.pointOnBWorld);
        }
      }
      // The face's contacts cover the bottom face (its corners, whatever the turn).
      EXPECT_GT(hi.x() - lo.x(), 0.99f);
      EXPECT_GT(hi.y() - lo.y(), 0.99f);
      // The batch and the single query agree.
      const MeshPairResult batched = collideMeshesBatch({query})[0];
      EXPECT_EQ(batched.contacts.size(), result.contacts.size());
    }
  }
}

// Triangle t's edge wings (MeshShape::edgeWings) in the world: transform * (scaling ∘ wing).
EdgeWings worldWings(const MeshShape& shape, const btTransform& transform, std::uint32_t t) {
  EdgeWings out;
  for (int k = 0; k < 3; ++k) {
    const float* w = shape.edgeWings() + 9 * std::size_t(t) + 3 * k;
    const btVector3 p = transform(btVector3(w[0], w[1], w[2]) * shape.getLocalScaling());
    out.across[k] = Eigen::Vector3f(p.x(), p.y(), p.z());
  }
  return out;
}

// The contacts of pairs that do not cross, each candidate against proximityContacts of its two triangles on
// their own (here in the world frame, from the double reference's triangles, with their edge wings): every
// clear contact of one is a contact of the other, with the same depth and normal. The pipeline finds them in
// chunks of rows, one face of A made per run of candidates sharing A's triangle.
TEST(CollideMeshes, SpeculativeContactsAreEachPairsProximityContacts) {
  MeshShape torus(sharedMesh(scenes::makeTorus(1.0f, 0.35f, 40, 16)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.6f, 3)));
  torus.setLocalScaling(btVector3(1.3f, 0.8f, 1.1f));
  std::mt19937 rng(5);
  std::size_t compared = 0;
  for (int pose = 0; pose < 4; ++pose) {
    MeshPairQuery query{&torus, randomPose(rng, btVector3(0, 0, 0), 0), &sphere,
                        randomPose(rng, btVector3(0, 0, 0), 1.3f)};
    query.speculativeDistance = 0.04f + 0.02f * float(pose);
    query.speculativeMotion = btVector3(0.02f, -0.06f, 0.03f);
    const MeshPairResult result = collideMeshes(query);
    const PairFrame frame = makePairFrame(torus, query.transformA, sphere, query.transformB,
                                          query.speculativeMotion, query.speculativeDistance);
    const std::set<TrianglePair> crossing(result.intersectingPairs.begin(), result.intersectingPairs.end());
    // (pair) -> depths and normals, of the pipeline and of the reference; clear: not within 1e-4 of the
    // reach.
    const auto clear = [&](float depth) { return depth < frame.reach - 1e-4f; };
    std::map<TrianglePair, std::vector<std::pair<float, btVector3>>> pipeline;
    for (const MeshContact& c : result.contacts) {
      const TrianglePair pair{c.triangleA, c.triangleB};
      if (!crossing.count(pair)) pipeline[pair].push_back({c.depth, c.normalWorldOnB});
    }
    std::size_t referenceContacts = 0;
    for (const TrianglePair& pair : result.candidatePairs) {
      if (crossing.count(pair)) continue;
      const TriangleD da = worldTriangle(torus, query.transformA, pair.triangleA);
      const TriangleD db = worldTriangle(sphere, query.transformB, pair.triangleB);
      Eigen::Vector3f a[3], b[3];
      for (int v = 0; v < 3; ++v) a[v] = da[v].cast<float>(), b[v] = db[v].cast<float>();
      const EdgeWings wa = worldWings(torus, query.transformA, pair.triangleA);
      const EdgeWings wb = worldWings(sphere, query.transformB, pair.triangleB);
      TriangleContact out[kMaxProximityContacts];
      const int made = proximityContacts(proximityFace(a), proximityFace(b), frame.reach, out,
                                         frame.marginReach, &wa, &wb);
      const auto& got = pipeline[pair];
      for (int k = 0; k < made; ++k) {
        if (!clear(out[k].depth)) continue;
        ++referenceContacts;
        const bool found = std::any_of(got.begin(), got.end(), [&](const auto& g) {
          const btVector3 n(out[k].normalOnB.x(), out[k].normalOnB.y(), out[k].normalOnB.z());
          return std::fabs(g.first - out[k].depth) < 1e-5f && (g.second - n).length() < 1e-4f;
        });
        EXPECT_TRUE(found) << "pair " << pair.triangleA << ", " << pair.triangleB << " depth "
                           << out[k].depth;
      }
      for (const auto& g : got) {
        if (!clear(g.first)) continue;
        const bool found = std::any_of(
            out, out + made, [&](const TriangleContact& c) { return std::fabs(g.first - c.depth) < 1e-5f; });
        EXPECT_TRUE(found) << "pair " << pair.triangleA << ", " << pair.triangleB << " depth " << g.first;
      }
    }
    compared += referenceContacts;
  }
  // Not vacuous: hundreds of contacts, over more than one chunk of candidates (512) per pose.
  EXPECT_GT(compared, 400u);
}

}  // namespace
}  // namespace gpucol::test
