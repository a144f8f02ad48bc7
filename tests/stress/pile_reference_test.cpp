// Mesh piles held to the same piles of Bullet's convex shapes (issue 57's reference, gpucol-bench piles): the
// pile of 16 meshes and the stack of 10 boxes, with gpucol and with boxes, spheres and compounds of boxes and
// capsules of the same masses, inertia and start poses. Asserted: every body of both sleeps, the mesh pile no
// later than 1.5 times the reference (median over seeds), nothing through the bin, and both its deepest
// contact and the deepest overlap of two of its bodies (measured on their solids' convex pieces, as for the
// reference: scenes/body_overlap.h) within 1.5 times the reference's, median over seeds. The issue asks for
// no deeper; docs/limits.md says where that is not met.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "scenes/scene_run.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace gpucol::test {
namespace {

struct Settled {
  int restStep = -1;       // first step every body slept; -1 when not within the steps
  float deepest = 0;       // deepest contact over the run (m)
  float overlap = 0;       // deepest overlap of two bodies in contact over the run, on their solids (m)
  scenes::RunFailure failure = scenes::RunFailure::None;
};

Settled settle(const scenes::SceneDescription& description, scenes::CollisionBackend backend) {
  scenes::WorldOptions options;
  options.backend = backend;
  scenes::WorldScene world(description, options);
  scenes::RunOptions run;
  run.steps = 3000;
  run.stopWhenAllAsleep = true;
  Settled s;
  const scenes::RunSummary summary = scenes::runScene(
      world, run,
      [&](const scenes::StepSample& sample) {
        if (s.restStep < 0 && sample.sleepingBodies == int(world.dynamicBodies().size())) s.restStep = sample.step;
        s.overlap = std::max(s.overlap, world.deepestBodyOverlap());
      },
      1);
  s.deepest = summary.largestPenetration;
  s.failure = summary.failure;
  return s;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void expectLikeTheReference(const std::vector<scenes::SceneDescription>& scenes, const std::string& what) {
  std::vector<double> restRatios, depthRatios, overlapRatios;
  for (const scenes::SceneDescription& scene : scenes) {
    const Settled mesh = settle(scene, scenes::CollisionBackend::Gpucol);
    const Settled reference = settle(scene, scenes::CollisionBackend::Primitives);
    SCOPED_TRACE(what);
    ASSERT_EQ(mesh.failure, scenes::RunFailure::None);
    ASSERT_EQ(reference.failure, scenes::RunFailure::None);
    ASSERT_GT(reference.restStep, 0) << "the reference should come to rest";
    ASSERT_GT(mesh.restStep, 0) << "the mesh pile should come to rest (reference: step " << reference.restStep << ")";
    restRatios.push_back(double(mesh.restStep) / reference.restStep);
    depthRatios.push_back(double(mesh.deepest) / std::max(1e-3, double(reference.deepest)));
    overlapRatios.push_back(double(mesh.overlap) / std::max(1e-3, double(reference.overlap)));
    std::printf("%s: rest at step %d (reference %d), deepest %.3f m (reference %.3f m), bodies overlap %.3f m "
                "(reference %.3f m)\n",
                what.c_str(), mesh.restStep, reference.restStep, double(mesh.deepest), double(reference.deepest),
                double(mesh.overlap), double(reference.overlap));
  }
  EXPECT_LE(median(restRatios), 1.5) << what;
  EXPECT_LE(median(depthRatios), 1.5) << what;
  EXPECT_LE(median(overlapRatios), 1.5) << what;
}

TEST(PileReference, SmallPileSettlesLikeConvexShapes) {
  std::vector<scenes::SceneDescription> piles;
  for (unsigned seed : {1u, 2u, 3u}) piles.push_back(scenes::makePileScene(16, seed));
  expectLikeTheReference(piles, "pile of 16");
}

TEST(PileReference, StackOfTenSettlesLikeConvexBoxes) {
  expectLikeTheReference({scenes::makeStackScene(10, 0.01f)}, "stack of 10, 1 cm gaps");
}

}  // namespace
}  // namespace gpucol::test
