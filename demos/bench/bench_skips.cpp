// gpucol-bench skips: each of DESIGN.md's skips ("skip what a scene does not need") on a scene made to show it:
// its counter, the time with the skip, the time of the same work without it (or of the work it avoids), and
// what it saves.
#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gpucol/gpucol.h>

#include "bench_commands.h"
#include "bench_stats.h"
#include "scenes/procedural_meshes.h"

namespace gpucol::bench {
namespace {

struct SkipLine {
  std::string skip;
  std::string scene;
  std::string counter;
  double withMs = 0;
  double withoutMs = 0;
  std::string without;  // what the "without" time measures
};

void print(const SkipLine& l) {
  std::cout << "| " << l.skip << " | " << l.scene << " | " << l.counter << " | " << std::fixed << std::setprecision(3)
            << l.withMs << " | " << l.withoutMs << " (" << l.without << ") | " << std::setprecision(1)
            << (l.withMs > 0 ? l.withoutMs / l.withMs : 0.0) << "x |" << std::endl;
}

// Boxes for the broad phase lines: unit boxes at random in a cube whose side keeps the density the same at any n.
struct BoxCloud {
  std::vector<btVector3> centre;
  btVector3 half{0.5f, 0.5f, 0.5f};

  BoxCloud(std::size_t n, float side, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, side);
    for (std::size_t i = 0; i < n; ++i) centre.emplace_back(u(rng), u(rng), u(rng));
  }
};

// Median ms of a step (setAabb of the boxes that move, then calculateOverlappingPairs) over `steps` steps; every
// `moveEvery`-th box moves by 1 cm per step (1: all of them). `static` boxes get Bullet's static filter.
double broadphaseStepMs(GridBroadphase& bp, BoxCloud cloud, int steps, std::size_t moveEvery, bool allStatic,
                        std::size_t dynamicCount = 0) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  std::vector<btBroadphaseProxy*> proxies;
  for (std::size_t i = 0; i < cloud.centre.size(); ++i) {
    const bool isStatic = allStatic && i >= dynamicCount;
    proxies.push_back(bp.createProxy(
        cloud.centre[i] - cloud.half, cloud.centre[i] + cloud.half, BOX_SHAPE_PROXYTYPE, reinterpret_cast<void*>(i),
        isStatic ? int(btBroadphaseProxy::StaticFilter) : int(btBroadphaseProxy::DefaultFilter),
        isStatic ? int(btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter)
                 : int(btBroadphaseProxy::AllFilter),
        &dispatcher));
  }
  std::vector<double> samples;
  samples.push_back(millisecondsOf([&] { bp.calculateOverlappingPairs(&dispatcher); }));  // the full first search
  for (int t = 0; t < steps; ++t) {
    samples.push_back(millisecondsOf([&] {
      for (std::size_t i = 0; i < proxies.size(); i += moveEvery) {
        if (allStatic && i >= dynamicCount) continue;
        cloud.centre[i] += btVector3(0.01f, 0, 0);
        bp.setAabb(proxies[i], cloud.centre[i] - cloud.half, cloud.centre[i] + cloud.half, &dispatcher);
      }
      bp.calculateOverlappingPairs(&dispatcher);
    }));
  }
  samples.erase(samples.begin());  // the first search is not a step
  return median(samples);
}

SkipLine noGridForSmallScenes(int steps) {
  SkipLine l;
  l.skip = "no grid for small scenes";
  l.scene = "100 moving unit boxes";
  const BoxCloud cloud(100, std::cbrt(8.0f * 100.0f), 1);
  GridBroadphase small;  // default bruteForceBelow
  l.withMs = broadphaseStepMs(small, cloud, steps, 1, false);
  l.counter = std::string("usedGrid = ") + (small.stats().usedGrid ? "true" : "false");
  Config forced;
  forced.bruteForceBelow = 0;
  GridBroadphase grid(forced);
  l.withoutMs = broadphaseStepMs(grid, cloud, steps, 1, false);
  l.without = "grid forced";
  return l;
}

SkipLine restingProxies(std::size_t n, int steps) {
  SkipLine l;
  l.skip = "static and sleeping proxies not re-binned";
  l.scene = std::to_string(n) + " unit boxes, 1% moving";
  const BoxCloud cloud(n, std::cbrt(8.0f * float(n)), 2);  // one box per 8 m^3, as gpucol-bench broadphase
  GridBroadphase resting;
  l.withMs = broadphaseStepMs(resting, cloud, steps, 100, false);
  l.counter = "restingProxies = " + std::to_string(resting.stats().restingProxies);
  GridBroadphase moving;
  l.withoutMs = broadphaseStepMs(moving, cloud, steps, 1, false);
  l.without = "every box moving";
  return l;
}

SkipLine staticPairs(int steps) {
  SkipLine l;
  l.skip = "static-static pairs refused by Bullet's static masks";
  l.scene = "1,000 static boxes in one heap + 10 moving";
  const BoxCloud heap(1010, 3.0f, 3);
  GridBroadphase withStatic;
  l.withMs = broadphaseStepMs(withStatic, heap, steps, 1, true, 10);
  l.counter = "staticProxies = " + std::to_string(withStatic.stats().staticProxies) + ", pairs in cache = " +
              std::to_string(withStatic.getOverlappingPairCache()->getNumOverlappingPairs());
  GridBroadphase allDynamic;
  l.withoutMs = broadphaseStepMs(allDynamic, heap, steps, 1, true, heap.centre.size());
  l.without = std::to_string(allDynamic.getOverlappingPairCache()->getNumOverlappingPairs()) +
              " pairs when all are dynamic";
  return l;
}

// A 4 m rod: turned 45° about z, its world box is 3 m wide (see tests/bullet/skip_counters_test.cpp).
std::shared_ptr<MeshShape> rod() {
  return std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeBox(2.0f, 0.1f, 0.1f, 8)));
}

btTransform turned(float angle, const btVector3& origin) {
  btTransform t;
  t.setIdentity();
  t.setRotation(btQuaternion(btVector3(0, 0, 1), angle));
  t.setOrigin(origin);
  return t;
}

SkipLine rootBoxesMiss(int runs) {
  SkipLine l;
  l.skip = "no middle phase when root boxes miss";
  l.scene = "1,000 rod pairs whose world boxes overlap";
  const auto shape = rod();
  const float angle = 0.785398f;
  std::vector<MeshPairQuery> missing(1000), apart(1000);
  for (auto& q : missing) q = {shape.get(), turned(angle, btVector3(0, 0, 0)), shape.get(), turned(angle, btVector3(0.7071f, -0.7071f, 0))};
  // Crossed rods 1 mm apart in z: their root boxes overlap, the traversal runs and finds no touching triangle.
  for (auto& q : apart) q = {shape.get(), turned(angle, btVector3(0, 0, 0)), shape.get(), turned(-angle, btVector3(0, 0, 0.201f))};
  std::vector<double> with, without;
  std::uint64_t missed = 0;
  for (int r = 0; r < runs; ++r) {
    with.push_back(millisecondsOf([&] {
      missed = 0;
      for (const MeshPairResult& result : collideMeshesBatch(missing)) missed += result.stats.rootBoxesMissed;
    }));
    without.push_back(millisecondsOf([&] { collideMeshesBatch(apart); }));
  }
  l.withMs = median(with);
  l.withoutMs = median(without);
  l.counter = "rootBoxesMissed = " + std::to_string(missed);
  l.without = "roots overlap, triangles 1 mm apart";
  return l;
}

SkipLine lazyOpenCl(const MeshShape& shape, const btTransform& a, const btTransform& b) {
  SkipLine l;
  l.skip = "OpenCL started only when wanted";
  l.scene = "every line above (Backend::Auto)";
  l.counter = std::string("openClStarted() = ") + (openClStarted() ? "true" : "false");
  Config forced;
  forced.meshBackend = Backend::OpenCL;
  l.withMs = 0;
  Backend used = Backend::Cpu;
  l.withoutMs = millisecondsOf([&] { used = collideMeshes(shape, a, shape, b, forced).stats.backendUsed; });
  l.without = used == Backend::OpenCL ? "first OpenCL batch: device, programs" : "no OpenCL device: CPU fallback";
  return l;
}

SkipLine cpuForSmallPairs(const MeshShape& shape, const btTransform& a, const btTransform& b, int runs) {
  SkipLine l;
  l.skip = "CPU for small mesh pairs";
  l.scene = "two icospheres, " + std::to_string(shape.mesh().triangleCount()) + " triangles each";
  Config forced;
  forced.meshBackend = Backend::OpenCL;
  std::vector<double> with, without;
  Backend used = Backend::Cpu;
  for (int r = 0; r < runs; ++r) {
    with.push_back(millisecondsOf([&] { used = collideMeshes(shape, a, shape, b).stats.backendUsed; }));
    without.push_back(millisecondsOf([&] { collideMeshes(shape, a, shape, b, forced); }));
  }
  l.withMs = median(with);
  l.withoutMs = median(without);
  l.counter = std::string("backendUsed = ") + (used == Backend::Cpu ? "Cpu" : "OpenCL");
  l.without = "OpenCL forced";
  return l;
}

void run(bool quick, int runs) {
  const int steps = quick ? 3 : 7;
  std::cout << "| skip | scene | counter | with the skip, ms | without, ms | saved |\n|---|---|---|---:|---:|---:|\n";
  print(noGridForSmallScenes(steps));
  print(restingProxies(quick ? 10000 : 100000, steps));
  print(staticPairs(steps));
  print(rootBoxesMiss(runs));
  const auto sphere =
      std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(scenes::makeIcosphere(0.5f, 4)));
  const btTransform a = turned(0.0f, btVector3(0, 0, 0));
  const btTransform b = turned(0.3f, btVector3(0.9f, 0.1f, 0));
  print(lazyOpenCl(*sphere, a, b));
  print(cpuForSmallPairs(*sphere, a, b, runs));
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto quick = std::make_shared<bool>(false);
  auto runs = std::make_shared<int>(7);
  CLI::App* command = app.add_subcommand("skips", "what each skip of a scene's unneeded work saves");
  command->add_flag("--quick", *quick, "smaller scenes");
  command->add_option("--runs", *runs, "timed repetitions (medians)")->check(CLI::PositiveNumber);
  command->callback([quick, runs] { run(*quick, *runs); });
});

}  // namespace
}  // namespace gpucol::bench
