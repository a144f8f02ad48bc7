// gpucol-bench broadphase: per step (setAabb of every proxy + calculateOverlappingPairs) of
// gpucol::GridBroadphase (CPU, and OpenCL when a pair finder is registered) beside btDbvtBroadphase,
// bt32BitAxisSweep3 and Bullet3's b3GpuGridBroadphase (b3_gpu_grid_peer.h, same OpenCL device) on the same
// moving boxes; median ms, ratios, pair counts, memory (issue 4, "Speed").
#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "b3_gpu_grid_peer.h"
#include "bench_commands.h"
#include "bench_stats.h"
#include "broadphase/grid_pair_finder.h"
#include "bullet/grid_broadphase_options.h"
#include "gpucol/grid_broadphase.h"
#include "opencl/host/opencl_context.h"

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
    s.centre.emplace_back(float(x) * 1.1f + jitter(rng), 0.6f + float(y) * 1.1f,
                          float(z) * 1.1f + jitter(rng));
    s.half.emplace_back(0.5f, 0.5f, 0.5f);
    s.velocity.emplace_back(0, -0.3f + jitter(rng), 0);
  }
  const float top = 1.1f * float(n / (base * base) + 2);
  s.lo = btVector3(-10, -10, -10),
  s.hi = btVector3(float(base) * 1.1f + 10, top + 10, float(base) * 1.1f + 10);
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
  for (std::size_t i = 0; i < std::max<std::size_t>(1, n / 20000); ++i)
    s.half[i] = btVector3(0.1f, 0.1f, 0.1f) * side;
  return s;
}

/// Mostly asleep: the uniform cloud where only every 100th box moves (the rest re-send unchanged boxes, as
/// Bullet does for sleeping bodies): what "skip what a scene does not need" saves.
Scene sleepingCloud(std::size_t n, std::uint32_t seed) {
  Scene s = uniformCloud(n, seed);
  s.name = "sleeping";
  for (std::size_t i = 0; i < n; ++i)
    if (i % 100 != 0) s.velocity[i] = btVector3(0, 0, 0);
  return s;
}

/// At rest: unit boxes stacked on a lattice, faces touching, each jiggling about its place every step (a
/// settled pile whose bodies the solver still nudges, as in Bullet's BenchmarkDemo). Their AABBs hold a
/// margin of 0.02, as Bullet's do, so neighbours' boxes overlap and the jiggle changes no pair.
Scene restingPile(std::size_t n, std::uint32_t seed) {
  Scene s;
  s.name = "resting";
  const std::size_t base = std::max<std::size_t>(1, std::size_t(std::cbrt(double(n)) + 0.5));
  for (std::size_t i = 0; i < n; ++i) {
    s.centre.emplace_back(float(i % base), 0.5f + float(i / (base * base)), float((i / base) % base));
    s.half.emplace_back(0.52f, 0.52f, 0.52f);
  }
  s.velocity = s.centre;  // the places the boxes jiggle about
  s.lo = btVector3(-10, -10, -10), s.hi = btVector3(float(base) + 10, float(n / (base * base)) + 10, float(base) + 10);
  s.advance = [rng = std::mt19937(seed)](Scene& sc, int) mutable {
    std::uniform_real_distribution<float> jiggle(-0.002f, 0.002f);
    for (std::size_t i = 0; i < sc.centre.size(); ++i)
      sc.centre[i] = sc.velocity[i] + btVector3(jiggle(rng), jiggle(rng), jiggle(rng));
  };
  return s;
}

using Clock = std::chrono::steady_clock;

struct Result {
  std::string broadphase;
  double medianMs = 0;
  std::size_t pairs = 0;        // pairs reported after the last step (in the cache, or by the b3 peer)
  std::size_t realPairs = 0;    // of those, the ones whose AABBs really overlap
  std::size_t memoryBytes = 0;  // held between steps; 0 where not known
  std::size_t peakBytes = 0;    // at the peak of the last step; 0 where not known
  std::string note;             // why a broad phase did not run ("" when it ran)
};

Result notRun(const std::string& label, const std::string& why) {
  Result r;
  r.broadphase = label;
  r.note = why;
  return r;
}

/// One broad phase on its own copy of a scene: set up when made, then one timed step per call, so that
/// several broad phases can take turns step by step (--interleave) and meet the same load on a shared
/// machine; finish() gives the median and the pair counts.
class Stepper {
 public:
  virtual ~Stepper() = default;
  /// Advances the scene and times one step (ms).
  virtual double step() = 0;
  /// The result after the last step (median of the steps taken).
  virtual Result finish() = 0;
  /// Milliseconds of every step so far.
  std::vector<double> ms;
};

/// A btBroadphaseInterface: a step is setAabb of every proxy plus calculateOverlappingPairs.
class BulletStepper final : public Stepper {
 public:
  BulletStepper(std::string label, btBroadphaseInterface& bp, Scene scene,
                std::function<std::pair<std::size_t, std::size_t>()> memory = nullptr,
                std::function<void()> afterStep = nullptr)
      : m_label(std::move(label)),
        m_bp(bp),
        m_scene(std::move(scene)),
        m_dispatcher(&m_configuration),
        m_memory(std::move(memory)),
        m_afterStep(std::move(afterStep)) {
    m_proxies.reserve(m_scene.centre.size());
    for (std::size_t i = 0; i < m_scene.centre.size(); ++i)
      m_proxies.push_back(m_bp.createProxy(m_scene.centre[i] - m_scene.half[i],
                                           m_scene.centre[i] + m_scene.half[i], BOX_SHAPE_PROXYTYPE,
                                           reinterpret_cast<void*>(i), btBroadphaseProxy::DefaultFilter,
                                           btBroadphaseProxy::AllFilter, &m_dispatcher));
    m_bp.calculateOverlappingPairs(&m_dispatcher);  // initial pairs, not timed
  }
  double step() override {
    m_scene.advance(m_scene, m_step++);
    const auto start = Clock::now();
    for (std::size_t i = 0; i < m_proxies.size(); ++i)
      m_bp.setAabb(m_proxies[i], m_scene.centre[i] - m_scene.half[i], m_scene.centre[i] + m_scene.half[i],
                   &m_dispatcher);
    m_bp.calculateOverlappingPairs(&m_dispatcher);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    if (m_afterStep) m_afterStep();
    return ms.back();
  }
  Result finish() override {
    Result r;
    r.broadphase = m_label;
    r.medianMs = median(ms);
    btOverlappingPairCache* cache = m_bp.getOverlappingPairCache();
    r.pairs = std::size_t(cache->getNumOverlappingPairs());
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
      const btBroadphasePair& p = cache->getOverlappingPairArray()[i];
      r.realPairs += TestAabbAgainstAabb2(p.m_pProxy0->m_aabbMin, p.m_pProxy0->m_aabbMax,
                                          p.m_pProxy1->m_aabbMin, p.m_pProxy1->m_aabbMax);
    }
    if (m_memory) std::tie(r.memoryBytes, r.peakBytes) = m_memory();
    // No destroyProxy loop: Bullet's caches scan every pair per removed proxy (quadratic teardown, the same
    // for every broad phase here); the broad phases free their proxies when they are destroyed.
    return r;
  }

 private:
  std::string m_label;
  btBroadphaseInterface& m_bp;
  Scene m_scene;
  btDefaultCollisionConfiguration m_configuration;
  btCollisionDispatcher m_dispatcher;
  std::function<std::pair<std::size_t, std::size_t>()> m_memory;  // (held between steps, peak)
  std::function<void()> m_afterStep;
  std::vector<btBroadphaseProxy*> m_proxies;
  int m_step = 0;
};

/// The scene's boxes as the plain arrays b3GpuGridBroadphase's peer reads (all active, default filters).
struct SceneArrays {
  std::vector<float> lo[3], hi[3];
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> flags;

  explicit SceneArrays(std::size_t n)
      : group(n, btBroadphaseProxy::DefaultFilter),
        mask(n, btBroadphaseProxy::AllFilter),
        flags(n, kProxyActive) {
    for (int a = 0; a < 3; ++a) lo[a].resize(n), hi[a].resize(n);
  }
  void store(const Scene& s) {
    for (std::size_t i = 0; i < s.centre.size(); ++i)
      for (int a = 0; a < 3; ++a)
        lo[a][i] = s.centre[i][a] - s.half[i][a], hi[a][i] = s.centre[i][a] + s.half[i][a];
  }
  ProxyArrays view() const {
    ProxyArrays v;
    v.count = std::uint32_t(flags.size());
    v.minX = lo[0].data(), v.minY = lo[1].data(), v.minZ = lo[2].data();
    v.maxX = hi[0].data(), v.maxY = hi[1].data(), v.maxZ = hi[2].data();
    v.group = group.data(), v.mask = mask.data(), v.flags = flags.data();
    return v;
  }
};

/// Bullet3's b3GpuGridBroadphase through B3GpuGridPeer: a step is writing the moved boxes and uploading
/// them (its setAabb) plus its calculateOverlappingPairs; pairs are the peer's, real pairs those of them
/// whose boxes overlap.
class B3Stepper final : public Stepper {
 public:
  B3Stepper(std::string label, B3GpuGridPeer& peer, Scene scene)
      : m_label(std::move(label)), m_peer(peer), m_scene(std::move(scene)), m_arrays(m_scene.centre.size()) {
    m_arrays.store(m_scene);
    m_peer.reset();                    // a new scene: new proxies even when the slots are the same
    m_peer.setBoxes(m_arrays.view());  // creates the proxies, not timed
    m_peer.step();
  }
  double step() override {
    m_scene.advance(m_scene, m_step++);
    const auto start = Clock::now();
    m_arrays.store(m_scene);
    m_peer.setBoxes(m_arrays.view());
    m_found = m_peer.step();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    return ms.back();
  }
  Result finish() override {
    Result r;
    r.broadphase = m_label;
    r.medianMs = median(ms);
    r.pairs = m_found;
    const ProxyArrays v = m_arrays.view();
    for (std::uint64_t key : m_peer.pairs()) {
      const std::uint32_t a = std::uint32_t(key >> 32), b = std::uint32_t(key);
      r.realPairs += v.minX[a] <= v.maxX[b] && v.minX[b] <= v.maxX[a] && v.minY[a] <= v.maxY[b] &&
                     v.minY[b] <= v.maxY[a] && v.minZ[a] <= v.maxZ[b] && v.minZ[b] <= v.maxZ[a];
    }
    return r;
  }

 private:
  std::string m_label;
  B3GpuGridPeer& m_peer;
  Scene m_scene;
  SceneArrays m_arrays;
  std::size_t m_found = 0;
  int m_step = 0;
};

/// --stages: median wall ms per stage of GridBroadphase's steps (the rest of a step is setAabb and the scan
/// of the proxies' filters).
void printStages(const std::string& scene, std::size_t n, const std::string& label,
                 const std::vector<GridBroadphaseStats>& steps) {
  auto med = [&](double GridBroadphaseStats::*field) {
    std::vector<double> v;
    for (const GridBroadphaseStats& s : steps) v.push_back(s.*field);
    return median(v);
  };
  std::printf(
      "%-8s %9zu %-18s stages (median ms): search %.3f [grid choice %.3f, binning %.3f, tests %.3f, huge "
      "%.3f, "
      "pair sort %.3f], diff + pair cache %.3f\n",
      scene.c_str(), n, label.c_str(), med(&GridBroadphaseStats::searchMs),
      med(&GridBroadphaseStats::chooseMs), med(&GridBroadphaseStats::binMs),
      med(&GridBroadphaseStats::testMs), med(&GridBroadphaseStats::hugeMs), med(&GridBroadphaseStats::sortMs),
      med(&GridBroadphaseStats::cacheMs));
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
  while (std::getline(ss, item, ','))
    if (!item.empty()) v.push_back(item);
  return v;
}

struct Options {
  std::string sizes = "1000,10000,100000";
  std::string scenes = "uniform,column,mixed";
  std::string runs = "cpu,opencl,dbvt,sap,b3";
  int steps = 7;
  std::string csv;
  std::string cellRule = "size";
  std::string output = "compacted";
  std::string sqrtMode = "double";
  std::string device;
  bool stages = false;
  bool interleave = false;
  int bruteForceBelow = Config{}.bruteForceBelow;
  std::uint32_t hugeCellLimit = kHugeCellLimit;
  std::size_t peerMax = 1000000;
  // bt32BitAxisSweep3 inserts each new proxy by walking its edges down the three sorted axes: n proxies
  // cost O(n^2) to create (measured here: 30K take 14 s, so 100K would take minutes), so it is left out above
  // this.
  std::size_t sapMax = 30000;
};

void runAll(const Options& o) {
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    if (!csv) throw std::runtime_error("cannot write " + o.csv);
    csv << "scene,n,broadphase,median_ms,ratio_vs_gpucol_cpu,pairs,real_pairs,bytes_per_proxy_minus_8_per_"
           "pair,peak_bytes_per_proxy_minus_8_per_pair,note\n";
  }
  const std::vector<std::string> runs = parseNames(o.runs);
  auto wanted = [&](const char* name) { return std::find(runs.begin(), runs.end(), name) != runs.end(); };
  for (const std::string& name : runs)
    if (name != "cpu" && name != "opencl" && name != "dbvt" && name != "sap" && name != "b3")
      throw std::runtime_error("unknown broad phase " + name + " (cpu, opencl, dbvt, sap, b3)");

  // Ours on OpenCL and Bullet3's peer run on the same device: the one gpucol's OpenCL layer chooses.
  Config base;
  base.openclDevice = o.device;
  base.bruteForceBelow = o.bruteForceBelow;
  std::string openClWhy;
  std::string deviceName;
  if (wanted("opencl") || wanted("b3")) {
    if (opencl::OpenClContext* context = opencl::OpenClContext::tryGet(o.device)) {
      deviceName = context->deviceName();
      if (!makeOpenClPairFinder(base)) openClWhy = "not run: no OpenCL pair finder (no device, or built without OpenCL)";
    } else {
      openClWhy = "not run: no usable OpenCL device";
    }
  }
  std::unique_ptr<B3GpuGridPeer> b3;
  std::string b3Why = openClWhy;
  if (wanted("b3") && b3Why.empty()) {
    try {
      b3 = std::make_unique<B3GpuGridPeer>(deviceName);
    } catch (const std::exception& e) {
      b3Why = std::string("not run: ") + e.what();
    }
  }
  std::printf("OpenCL device: %s\n", deviceName.empty() ? "(none)" : deviceName.c_str());
  std::printf("%-8s %9s %-18s %11s %9s %11s %11s %9s %9s\n", "scene", "N", "broadphase", "median ms",
              "x gpucol", "pairs", "real pairs", "B/proxy", "peak B/p");
  for (const std::string& sceneName : parseNames(o.scenes))
    for (std::size_t n : parseList(o.sizes)) {
      auto make = [&]() {
        if (sceneName == "uniform") return uniformCloud(n, 1);
        if (sceneName == "column") return fallingColumn(n, 2);
        if (sceneName == "mixed") return mixedSizes(n, 3);
        if (sceneName == "sleeping") return sleepingCloud(n, 4);
        if (sceneName == "resting") return restingPile(n, 5);
        throw std::runtime_error("unknown scene " + sceneName + " (uniform, column, mixed, sleeping, resting)");
      };
      // Every broad phase that runs gets a stepper (and keeps its objects alive until the case is done);
      // those that do not run get their reason in `results` at their place in the table.
      std::vector<Result> results;
      std::vector<std::unique_ptr<Stepper>> steppers;
      std::vector<std::size_t> slot;  // steppers[i]'s place in results
      std::vector<std::unique_ptr<GridBroadphase>> grids;
      std::vector<std::unique_ptr<btBroadphaseInterface>> peers;
      std::deque<std::vector<GridBroadphaseStats>> stepStats;  // a deque: the steppers hold pointers into it
      auto add = [&](std::unique_ptr<Stepper> stepper) {
        slot.push_back(results.size());
        results.emplace_back();
        steppers.push_back(std::move(stepper));
      };
      GridBroadphaseOptions internal;
      internal.densityCellSize = o.cellRule == "density";
      internal.bitMaskOutput = o.output == "bitmask";
      internal.newtonSqrt = o.sqrtMode == "newton";
      internal.hugeCellLimit = o.hugeCellLimit;
      for (const char* variant : {"cpu", "opencl"}) {
        const bool cpu = std::string(variant) != "opencl";
        const std::string label = std::string("gpucol-") + variant;
        if (!wanted(variant)) continue;
        if (!cpu && !openClWhy.empty()) {
          results.push_back(notRun(label, openClWhy));
          continue;
        }
        Config config = base;
        config.broadphaseBackend = cpu ? Backend::Cpu : Backend::OpenCL;
        grids.push_back(std::make_unique<GridBroadphase>(config));
        GridBroadphase* grid = grids.back().get();
        detail::GridBroadphaseAccess::setOptions(*grid, internal);
        stepStats.emplace_back();
        std::vector<GridBroadphaseStats>* stats = &stepStats.back();
        add(std::make_unique<BulletStepper>(
            label, *grid, make(),
            [grid] { return std::make_pair(grid->stats().memoryBytes, grid->stats().peakBytes); },
            [grid, stats] { stats->push_back(grid->stats()); }));
      }
      if (wanted("dbvt")) {
        if (n > o.peerMax) {
          results.push_back(notRun("btDbvt", "not run: above --peer-max"));
        } else {
          peers.push_back(std::make_unique<btDbvtBroadphase>());
          add(std::make_unique<BulletStepper>("btDbvt", *peers.back(), make()));
        }
      }
      if (wanted("sap")) {
        if (n > o.sapMax) {
          results.push_back(notRun("bt32BitAxisSweep3", "not run: setup O(n^2) (above --sap-max)"));
        } else {
          Scene sc = make();
          if (n + 2 > 2147483646u) throw std::runtime_error("too many proxies for bt32BitAxisSweep3");
          peers.push_back(std::make_unique<bt32BitAxisSweep3>(sc.lo, sc.hi, unsigned(n + 2)));
          add(std::make_unique<BulletStepper>("bt32BitAxisSweep3", *peers.back(), std::move(sc)));
        }
      }
      if (wanted("b3")) {
        if (!b3)
          results.push_back(notRun("b3GpuGrid", b3Why));
        else if (n > o.peerMax)
          results.push_back(notRun("b3GpuGrid", "not run: above --peer-max"));
        else
          add(std::make_unique<B3Stepper>("b3GpuGrid", *b3, make()));
      }
      // --interleave: step 1 of every broad phase, then step 2 of every one, ...; else each runs all its
      // steps in turn.
      if (o.interleave) {
        for (int t = 0; t < o.steps; ++t)
          for (auto& stepper : steppers) stepper->step();
      } else {
        for (auto& stepper : steppers)
          for (int t = 0; t < o.steps; ++t) stepper->step();
      }
      for (std::size_t i = 0; i < steppers.size(); ++i) results[slot[i]] = steppers[i]->finish();
      for (std::size_t g = 0; g < grids.size(); ++g) {
        Result& r = results[slot[g]];
        if (o.stages)
          printStages(sceneName, n, r.broadphase, stepStats[g]);
        if (r.broadphase == "gpucol-opencl" && !grids[g]->stats().usedOpenCl)
          r.note = "ran on the CPU: OpenCL path fell back";
      }
      const double reference = !results.empty() && results[0].note.empty() ? results[0].medianMs : 0.0;
      for (const Result& r : results) {
        if (!r.note.empty() && r.medianMs == 0) {
          std::printf("%-8s %9zu %-18s %s\n", sceneName.c_str(), n, r.broadphase.c_str(), r.note.c_str());
          if (csv) csv << sceneName << ',' << n << ',' << r.broadphase << ",,,,,,," << r.note << '\n';
          continue;
        }
        // Memory is known for GridBroadphase only; the others show "-" (empty in the CSV).
        std::string perProxy = "-", perProxyCsv, peak = "-", peakCsv;
        if (r.memoryBytes) {
          char text[32];
          std::snprintf(text, sizeof text, "%.1f",
                        (double(r.memoryBytes) - 8.0 * double(r.pairs)) / double(n));
          perProxy = perProxyCsv = text;
          std::snprintf(text, sizeof text, "%.1f", (double(r.peakBytes) - 8.0 * double(r.pairs)) / double(n));
          peak = peakCsv = text;
        }
        const double ratio = reference > 0 ? r.medianMs / reference : 0.0;
        std::printf("%-8s %9zu %-18s %11.3f %9.2f %11zu %11zu %9s %9s %s\n", sceneName.c_str(), n,
                    r.broadphase.c_str(), r.medianMs, ratio, r.pairs, r.realPairs, perProxy.c_str(),
                    peak.c_str(), r.note.c_str());
        if (csv)
          csv << sceneName << ',' << n << ',' << r.broadphase << ',' << r.medianMs << ',' << ratio << ','
              << r.pairs << ',' << r.realPairs << ',' << perProxyCsv << ',' << peakCsv << ',' << r.note
              << '\n';
      }
      std::fflush(stdout);
    }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("broadphase",
                                     "Per step (setAabb of every proxy + calculateOverlappingPairs), median "
                                     "ms of gpucol::GridBroadphase on the "
                                     "CPU and through OpenCL beside btDbvtBroadphase, bt32BitAxisSweep3 and "
                                     "Bullet3's b3GpuGridBroadphase (same "
                                     "OpenCL device), on moving boxes.");
  cmd->footer(
      "Columns: 'x gpucol' = median ms / gpucol-cpu's median ms (above 1: slower than gpucol-cpu); 'pairs' = "
      "pairs "
      "in the pair cache after the last step (b3GpuGrid: pairs it found); 'real pairs' = of those, the pairs "
      "whose "
      "AABBs overlap (btDbvt keeps fattened, stale pairs); 'B/proxy' = (bytes held by GridBroadphase - 8 x "
      "pairs) / "
      "N; 'peak B/p' = the same at the peak of the last step (GridBroadphaseStats::peakBytes). A broad phase "
      "that does not run says why.\n"
      "Example: gpucol-bench broadphase --n 1000,10000,100000 --scenes uniform --csv bp.csv");
  cmd->add_option("--n", options->sizes, "comma-separated proxy counts (1e6 allowed)")->capture_default_str();
  cmd->add_option("--scenes", options->scenes,
                  "comma-separated scenes: uniform (cloud), column (falling, the paper's), "
                  "mixed (sizes, a few huge boxes), sleeping (cloud, 1% moving), resting (a small pile, every box jiggling "
                  "about its place)")
      ->capture_default_str();
  cmd->add_option(
         "--run", options->runs,
         "comma-separated broad phases: cpu, opencl (gpucol), dbvt (btDbvtBroadphase), sap "
         "(bt32BitAxisSweep3), b3 (b3GpuGridBroadphase)")
      ->capture_default_str();
  cmd->add_option("--steps", options->steps, "timed steps per case (median reported)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--csv", options->csv, "also write the table to this CSV file");
  cmd->add_option(
      "--device", options->device,
      "OpenCL device name substring (Config::openclDevice; GPUCOL_OPENCL_DEVICE overrides); b3 uses "
      "the same device");
  cmd->add_flag(
      "--stages", options->stages,
      "also print each gpucol broad phase's median wall ms per stage (search, the CPU grid's stages, diff + pair cache)");
  cmd->add_flag("--interleave", options->interleave,
                "take turns: step 1 of every broad phase, then step 2, ... (so all meet the same load on a "
                "shared machine); default: each runs all its steps in turn");
  cmd->add_option("--cell-rule", options->cellRule, "grid cell size rule: size or density")
      ->check(CLI::IsMember({"size", "density"}))
      ->capture_default_str();
  cmd->add_option("--output", options->output, "candidate output: compacted or bitmask (paper §3.4; CPU, whole grid)")
      ->check(CLI::IsMember({"compacted", "bitmask"}))
      ->capture_default_str();
  cmd->add_option("--sqrt", options->sqrtMode, "mapping-function square root: double or newton")
      ->check(CLI::IsMember({"double", "newton"}))
      ->capture_default_str();
  cmd->add_option("--brute-force-below", options->bruteForceBelow, "Config::bruteForceBelow")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--huge-cell-limit", options->hugeCellLimit,
                  "a box over this many cells is tested against all (GridBroadphaseOptions::hugeCellLimit)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--peer-max", options->peerMax, "skip btDbvt and b3GpuGrid above this many proxies")
      ->capture_default_str();
  cmd->add_option("--sap-max", options->sapMax,
                  "skip bt32BitAxisSweep3 above this many proxies (its setup is O(n^2))")
      ->capture_default_str();
  cmd->callback([options] { runAll(*options); });
});

}  // namespace
}  // namespace gpucol::bench
