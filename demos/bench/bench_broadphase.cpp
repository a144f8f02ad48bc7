// gpucol-bench broadphase: per step (setAabb of every proxy + calculateOverlappingPairs) of
// gpucol::GridBroadphase (CPU, and OpenCL when a pair finder is registered) beside btDbvtBroadphase and
// bt32BitAxisSweep3 on the same moving boxes; median ms, ratios, pair counts, memory (issue 4, "Speed").
#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "broadphase/grid_pair_finder.h"
#include "gpucol/grid_broadphase.h"

namespace gpucol::bench {
namespace {

/// One scene: boxes as centre + half extents, moved in place by advance().
struct Scene {
  std::string name;
  std::vector<btVector3> centre, half, velocity;
  btVector3 lo, hi;  // world bounds (for the sweep and prune)
  std::function<void(Scene&, int)> advance;
};

/// Uniform cloud: unit boxes at a density of about one box per 8 unit volumes, drifting, bouncing at walls.
Scene uniformCloud(std::size_t n, std::uint32_t seed) {
  Scene s;
  s.name = "uniform";
  const float side = std::cbrt(float(n) * 8.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(0, side), vel(-0.05f, 0.05f);
  for (std::size_t i = 0; i < n; ++i) {
    s.centre.emplace_back(pos(rng), pos(rng), pos(rng));
    s.half.emplace_back(0.5f, 0.5f, 0.5f);
    s.velocity.emplace_back(vel(rng), vel(rng), vel(rng));
  }
  s.lo = btVector3(-10, -10, -10), s.hi = btVector3(side + 10, side + 10, side + 10);
  s.advance = [side](Scene& sc, int) {
    for (std::size_t i = 0; i < sc.centre.size(); ++i) {
      sc.centre[i] += sc.velocity[i];
      for (int a = 0; a < 3; ++a)
        if (sc.centre[i][a] < 0 || sc.centre[i][a] > side) sc.velocity[i][a] = -sc.velocity[i][a];
    }
  };
  return s;
}

/// Falling column (the paper's scene, §6): unit boxes stacked in a square column with small gaps,
/// falling onto the plane y = 0; boxes stop at the ground and the column compresses into a dense pile.
Scene fallingColumn(std::size_t n, std::uint32_t seed) {
  Scene s;
  s.name = "column";
  const std::size_t base = std::max<std::size_t>(1, std::size_t(std::cbrt(double(n)) + 0.5));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t x = i % base, z = (i / base) % base, y = i / (base * base);
    s.centre.emplace_back(float(x) * 1.1f + jitter(rng), 0.6f + float(y) * 1.1f, float(z) * 1.1f + jitter(rng));
    s.half.emplace_back(0.5f, 0.5f, 0.5f);
    s.velocity.emplace_back(0, -0.3f + jitter(rng), 0);
  }
  const float top = 1.1f * float(n / (base * base) + 2);
  s.lo = btVector3(-10, -10, -10), s.hi = btVector3(float(base) * 1.1f + 10, top + 10, float(base) * 1.1f + 10);
  s.advance = [](Scene& sc, int) {
    for (std::size_t i = 0; i < sc.centre.size(); ++i) {
      sc.centre[i] += sc.velocity[i];
      if (sc.centre[i].y() < 0.5f) sc.centre[i].setY(0.5f + 0.001f * float(i % 7));  // resting, jostled
    }
  };
  return s;
}

/// Mixed sizes: the uniform cloud with half extents from 0.1 to 2 (few large), plus a few huge boxes.
Scene mixedSizes(std::size_t n, std::uint32_t seed) {
  Scene s = uniformCloud(n, seed);
  s.name = "mixed";
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> u(0, 1);
  const float side = std::cbrt(float(n) * 8.0f);
  for (auto& h : s.half) {
    const float r = 0.1f + 1.9f * std::pow(u(rng), 4.0f);
    h = btVector3(r, 0.1f + 1.9f * std::pow(u(rng), 4.0f), r);
  }
  for (std::size_t i = 0; i < std::max<std::size_t>(1, n / 20000); ++i) s.half[i] = btVector3(0.1f, 0.1f, 0.1f) * side;
  return s;
}

using Clock = std::chrono::steady_clock;

struct Result {
  std::string broadphase;
  double medianMs = 0;
  std::size_t pairs = 0;        // pairs in the cache after the last step
  std::size_t realPairs = 0;    // of those, the ones whose AABBs really overlap
  std::size_t memoryBytes = 0;  // 0 where not known
  bool skipped = false;
};

Result run(const std::string& label, btBroadphaseInterface& bp, Scene scene, int steps,
           const std::function<std::size_t()>& memory = nullptr) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  std::vector<btBroadphaseProxy*> proxies;
  proxies.reserve(scene.centre.size());
  for (std::size_t i = 0; i < scene.centre.size(); ++i)
    proxies.push_back(bp.createProxy(scene.centre[i] - scene.half[i], scene.centre[i] + scene.half[i], BOX_SHAPE_PROXYTYPE,
                                     reinterpret_cast<void*>(i), btBroadphaseProxy::DefaultFilter,
                                     btBroadphaseProxy::AllFilter, &dispatcher));
  bp.calculateOverlappingPairs(&dispatcher);  // initial pairs, not timed
  std::vector<double> ms;
  for (int t = 0; t < steps; ++t) {
    scene.advance(scene, t);
    const auto start = Clock::now();
    for (std::size_t i = 0; i < proxies.size(); ++i)
      bp.setAabb(proxies[i], scene.centre[i] - scene.half[i], scene.centre[i] + scene.half[i], &dispatcher);
    bp.calculateOverlappingPairs(&dispatcher);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  std::sort(ms.begin(), ms.end());
  Result r;
  r.broadphase = label;
  r.medianMs = ms[ms.size() / 2];
  btOverlappingPairCache* cache = bp.getOverlappingPairCache();
  r.pairs = std::size_t(cache->getNumOverlappingPairs());
  for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
    const btBroadphasePair& p = cache->getOverlappingPairArray()[i];
    r.realPairs += TestAabbAgainstAabb2(p.m_pProxy0->m_aabbMin, p.m_pProxy0->m_aabbMax, p.m_pProxy1->m_aabbMin,
                                        p.m_pProxy1->m_aabbMax);
  }
  if (memory) r.memoryBytes = memory();
  // No destroyProxy loop: Bullet's caches scan every pair per removed proxy (quadratic teardown, the same
  // for every broad phase here); the broad phases free their proxies when they are destroyed.
  return r;
}

std::vector<std::size_t> parseList(const std::string& text) {
  std::vector<std::size_t> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::size_t(std::stod(item)));
  return v;
}

std::vector<std::string> parseNames(const std::string& text) {
  std::vector<std::string> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(item);
  return v;
}

struct Options {
  std::string sizes = "1000,10000,100000";
  std::string scenes = "uniform,column,mixed";
  std::string peers = "dbvt,sap";
  int steps = 7;
  std::string csv;
  std::string cellRule = "size";
  std::string output = "compacted";
  std::string sqrtMode = "double";
  int bruteForceBelow = Config{}.bruteForceBelow;
  std::size_t peerMax = 1000000;
};

void runAll(const Options& o) {
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    if (!csv) throw std::runtime_error("cannot write " + o.csv);
    csv << "scene,n,broadphase,median_ms,ratio_vs_gpucol_cpu,pairs,real_pairs,bytes_per_proxy_minus_8_per_pair\n";
  }
  const bool haveOpenCl = makeOpenClPairFinder(Config{}) != nullptr;
  std::printf("%-8s %9s %-16s %11s %9s %11s %11s %9s\n", "scene", "N", "broadphase", "median ms", "x gpucol", "pairs",
              "real pairs", "B/proxy");
  for (const std::string& sceneName : parseNames(o.scenes))
    for (std::size_t n : parseList(o.sizes)) {
      auto make = [&]() {
        if (sceneName == "uniform") return uniformCloud(n, 1);
        if (sceneName == "column") return fallingColumn(n, 2);
        if (sceneName == "mixed") return mixedSizes(n, 3);
        throw std::runtime_error("unknown scene " + sceneName + " (uniform, column, mixed)");
      };
      std::vector<Result> results;
      GridBroadphaseTuning tuning;
      tuning.densityCellSize = o.cellRule == "density";
      tuning.bitMaskOutput = o.output == "bitmask";
      tuning.newtonSqrt = o.sqrtMode == "newton";
      {
        Config config;
        config.broadphaseBackend = Backend::Cpu;
        config.bruteForceBelow = o.bruteForceBelow;
        GridBroadphase grid(config);
        grid.setTuning(tuning);
        results.push_back(run("gpucol-cpu", grid, make(), o.steps, [&] { return grid.stats().memoryBytes; }));
      }
      if (haveOpenCl) {
        Config config;
        config.broadphaseBackend = Backend::OpenCL;
        config.bruteForceBelow = o.bruteForceBelow;
        GridBroadphase grid(config);
        grid.setTuning(tuning);
        results.push_back(run("gpucol-opencl", grid, make(), o.steps, [&] { return grid.stats().memoryBytes; }));
      }
      for (const std::string& peer : parseNames(o.peers)) {
        if (n > o.peerMax) {
          Result r;
          r.broadphase = peer;
          r.skipped = true;
          results.push_back(r);
          continue;
        }
        if (peer == "dbvt") {
          btDbvtBroadphase dbvt;
          results.push_back(run("btDbvt", dbvt, make(), o.steps));
        } else if (peer == "sap") {
          Scene sc = make();
          if (n + 2 > 2147483646u) throw std::runtime_error("too many proxies for bt32BitAxisSweep3");
          bt32BitAxisSweep3 sap(sc.lo, sc.hi, unsigned(n + 2));
          results.push_back(run("bt32BitAxisSweep3", sap, sc, o.steps));
        } else {
          throw std::runtime_error("unknown peer " + peer + " (dbvt, sap)");
        }
      }
      const double base = results[0].medianMs;
      for (const Result& r : results) {
        const double perProxy = r.memoryBytes ? (double(r.memoryBytes) - 8.0 * double(r.pairs)) / double(n) : 0.0;
        if (r.skipped) {
          std::printf("%-8s %9zu %-16s %11s\n", sceneName.c_str(), n, r.broadphase.c_str(), "skipped");
          continue;
        }
        std::printf("%-8s %9zu %-16s %11.3f %9.2f %11zu %11zu %9.1f\n", sceneName.c_str(), n, r.broadphase.c_str(),
                    r.medianMs, r.medianMs / base, r.pairs, r.realPairs, perProxy);
        if (csv)
          csv << sceneName << ',' << n << ',' << r.broadphase << ',' << r.medianMs << ',' << r.medianMs / base << ','
              << r.pairs << ',' << r.realPairs << ',' << perProxy << '\n';
      }
      std::fflush(stdout);
    }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("broadphase", "GridBroadphase beside btDbvtBroadphase and bt32BitAxisSweep3");
  cmd->add_option("--n", options->sizes, "comma-separated proxy counts (1e6 allowed)");
  cmd->add_option("--scenes", options->scenes, "comma-separated scenes: uniform, column, mixed");
  cmd->add_option("--peers", options->peers, "comma-separated Bullet peers: dbvt, sap (empty for none)");
  cmd->add_option("--steps", options->steps, "timed steps per case (median reported)")->check(CLI::PositiveNumber);
  cmd->add_option("--csv", options->csv, "also write the table to this CSV file");
  cmd->add_option("--cell-rule", options->cellRule, "grid cell size rule: size or density")
      ->check(CLI::IsMember({"size", "density"}));
  cmd->add_option("--output", options->output, "candidate output: compacted or bitmask")
      ->check(CLI::IsMember({"compacted", "bitmask"}));
  cmd->add_option("--sqrt", options->sqrtMode, "mapping-function square root: double or newton")
      ->check(CLI::IsMember({"double", "newton"}));
  cmd->add_option("--brute-force-below", options->bruteForceBelow, "Config::bruteForceBelow")->check(CLI::NonNegativeNumber);
  cmd->add_option("--peer-max", options->peerMax, "skip the Bullet peers above this many proxies");
  cmd->callback([options] { runAll(*options); });
});

}  // namespace
}  // namespace gpucol::bench
