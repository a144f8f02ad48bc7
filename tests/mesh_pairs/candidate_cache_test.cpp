// CandidateCache against the plain pipeline: a pair whose pose jitters as a resting pair's does gets, step
// after step, exactly the contacts it gets without the cache, while its trees are traversed again only when
// the pose has moved farther than the cache's slack allows.
#include "mesh_pairs/candidate_cache.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "bullet/mesh_pair_test_util.h"
#include "mesh_pairs/mesh_batch.h"
#include "mesh_pairs/pair_frame.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::test {
namespace {

std::shared_ptr<const TriangleMesh> sharedMesh(TriangleMesh mesh) {
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

bool sameBits(const btVector3& a, const btVector3& b) {
  return a.x() == b.x() && a.y() == b.y() && a.z() == b.z();
}

// The two results' contacts, reduced contacts and intersecting pairs are the same, value for value.
void expectSameContacts(const MeshPairResult& cached, const MeshPairResult& plain, int step) {
  ASSERT_EQ(cached.intersectingPairs, plain.intersectingPairs) << "step " << step;
  for (const auto* lists : {&cached.contacts, &cached.reducedContacts}) {
    const std::vector<MeshContact>& mine = *lists;
    const std::vector<MeshContact>& theirs =
        lists == &cached.contacts ? plain.contacts : plain.reducedContacts;
    ASSERT_EQ(mine.size(), theirs.size()) << "step " << step;
    for (std::size_t i = 0; i < mine.size(); ++i) {
      EXPECT_EQ(mine[i].triangleA, theirs[i].triangleA) << "step " << step;
      EXPECT_EQ(mine[i].triangleB, theirs[i].triangleB) << "step " << step;
      EXPECT_TRUE(sameBits(mine[i].pointWorld, theirs[i].pointWorld)) << "step " << step;
      EXPECT_TRUE(sameBits(mine[i].pointOnBWorld, theirs[i].pointOnBWorld)) << "step " << step;
      EXPECT_TRUE(sameBits(mine[i].normalWorldOnB, theirs[i].normalWorldOnB)) << "step " << step;
      EXPECT_EQ(mine[i].depth, theirs[i].depth) << "step " << step;
    }
  }
}

// B's pose moved by a small turn about a random axis and a small shift.
btTransform jittered(const btTransform& pose, std::mt19937& rng, float shift, float turn) {
  std::normal_distribution<float> gauss;
  btVector3 axis(gauss(rng), gauss(rng), gauss(rng));
  axis.normalize();
  const btQuaternion q(axis, turn * gauss(rng));
  return btTransform(q * pose.getRotation(),
                     pose.getOrigin() + shift * btVector3(gauss(rng), gauss(rng), gauss(rng)));
}

// Pairs of meshes touching and overlapping a little, with and without margins (margins add proximity
// contacts, whose reach the cache's test must cover), scaled non-uniformly, walked through small jitters and
// now and then a jump: every step's contacts are the plain pipeline's, the cached candidates include the
// plain ones, most steps reuse the kept candidates and every jump traverses again.
TEST(CandidateCache, AJitteringPairGetsThePlainPipelinesContacts) {
  MeshShape torus(sharedMesh(scenes::makeTorus(0.3f, 0.12f, 24, 12)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.4f, 2)));
  MeshShape box(sharedMesh(scenes::makeBox(0.35f, 0.35f, 0.35f, 3)));
  box.setLocalScaling(btVector3(1.2f, 0.7f, 1.0f));
  const std::pair<MeshShape*, MeshShape*> pairs[] = {
      {&torus, &sphere}, {&box, &torus}, {&sphere, &box}, {&torus, &torus}};
  std::mt19937 rng(20261129);
  int reused = 0, steps = 0, jumps = 0, jumpsTraversed = 0;
  std::size_t contacts = 0;
  for (float margin : {0.0f, 0.01f}) {
    for (const auto& [a, b] : pairs) {
      a->setMargin(margin);
      b->setMargin(margin);
      CandidateCache cache;
      MeshPairQuery query{a, randomPose(rng, btVector3(0, 0, 0), 0.05f), b,
                          randomPose(rng, btVector3(0.55f, 0, 0), 0.05f)};
      for (int step = 0; step < 40; ++step) {
        const bool jump = step % 13 == 12;
        query.transformB = jittered(query.transformB, rng, jump ? 0.05f : 2e-4f, jump ? 0.3f : 5e-4f);
        const MeshPairResult plain = collideMeshes(query, Config(), nullptr);
        const MeshPairResult cached = collideMeshes(query, Config(), &cache);
        expectSameContacts(cached, plain, step);
        const std::set<TrianglePair> kept(cached.candidatePairs.begin(), cached.candidatePairs.end());
        for (const TrianglePair& p : plain.candidatePairs) ASSERT_TRUE(kept.count(p)) << "step " << step;
        const bool traversed = cached.stats.nodeTests > 1;
        ++steps;
        reused += !traversed && !cached.stats.rootBoxesMissed;
        jumps += jump;
        jumpsTraversed += jump && (traversed || cached.stats.rootBoxesMissed);
        contacts += plain.contacts.size();
      }
      a->setMargin(0);
      b->setMargin(0);
    }
  }
  EXPECT_GT(contacts, 1000u) << "the pairs must touch for the comparison to mean anything";
  EXPECT_EQ(jumpsTraversed, jumps);
  EXPECT_GT(reused, steps / 2);
}

// The kept candidates cover the pose they were found at and poses within a small part of the slack, not a
// pose moved by the slack itself, another pair of shapes, or a speculative reach wider than the one they were
// found with.
TEST(CandidateCache, CoversOnlyPosesWithinItsSlack) {
  MeshShape torus(sharedMesh(scenes::makeTorus(0.3f, 0.12f, 24, 12)));
  MeshShape sphere(sharedMesh(scenes::makeIcosphere(0.4f, 2)));
  const btTransform poseA(btQuaternion(btVector3(1, 1, 0).normalized(), 0.4f), btVector3(0, 0, 0));
  const btTransform poseB(btQuaternion(btVector3(0, 1, 0), 0.3f), btVector3(0.6f, 0.1f, 0));
  CandidateCache cache;
  std::uint64_t tests = 0;
  cache.candidates(torus, sphere, makePairFrame(torus, poseA, sphere, poseB), tests);
  EXPECT_GT(tests, 1u);
  EXPECT_TRUE(cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, poseB)));
  // The slack in the world: a share of the smaller mesh's largest side.
  const float slack =
      float(CandidateCache::kSlackShare) * std::min(largestSide(torus.mesh()), largestSide(sphere.mesh()));
  for (const btVector3& along : {btVector3(1, 0, 0), btVector3(0, 1, 0), btVector3(0, 0, 1)}) {
    btTransform near = poseB, far = poseB;
    near.setOrigin(poseB.getOrigin() + 0.1f * slack * along);
    far.setOrigin(poseB.getOrigin() + slack * along);
    EXPECT_TRUE(cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, near)));
    EXPECT_FALSE(cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, far)));
  }
  // A turn of the sphere about its centre moves its points by up to its radius times the angle.
  const btTransform turned(btQuaternion(btVector3(0, 0, 1), 2 * slack / 0.4f) * poseB.getRotation(),
                           poseB.getOrigin());
  EXPECT_FALSE(cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, turned)));
  EXPECT_FALSE(cache.covers(sphere, torus, makePairFrame(sphere, poseA, torus, poseB)));
  EXPECT_FALSE(
      cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, poseB, btVector3(0, 0, 0), 2 * slack)));
  // Found again after a miss, it covers the new pose.
  btTransform moved = poseB;
  moved.setOrigin(poseB.getOrigin() + btVector3(0, 0, 2 * slack));
  tests = 0;
  cache.candidates(torus, sphere, makePairFrame(torus, poseA, sphere, moved), tests);
  EXPECT_GT(tests, 1u);
  EXPECT_TRUE(cache.covers(torus, sphere, makePairFrame(torus, poseA, sphere, moved)));
}

}  // namespace
}  // namespace gpucol::test
