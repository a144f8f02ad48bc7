#include "opencl/host/opencl_pair_finder.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "broadphase/brute_force_pair_finder.h"
#include "broadphase/grid_pair_finder.h"
#include "broadphase/packed_pairs.h"
#include "opencl_test_device.h"
#include "proxy_records.h"

namespace gpucol::opencl {
namespace {

constexpr OpenClPairFinderTuning::BufferRelease kKeepBuffers = OpenClPairFinderTuning::BufferRelease::Never;

/// The default tuning but with the filled cells of a dense grid always listed as its runs (never every cell a
/// run: OpenClPairFinderTuning::runsAreCells).
OpenClPairFinderTuning listedRuns() {
  OpenClPairFinderTuning tuning;
  tuning.runsAreCells = false;
  return tuning;
}

/// A scene as the structure of arrays that ProxyArrays views.
struct Scene {
  std::vector<float> minX, minY, minZ, maxX, maxY, maxZ;
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> flags;

  void add(float x, float y, float z, float hx, float hy, float hz, std::uint8_t extraFlags = 0,
           std::int32_t g = 1, std::int32_t m = -1) {
    minX.push_back(x - hx), minY.push_back(y - hy), minZ.push_back(z - hz);
    maxX.push_back(x + hx), maxY.push_back(y + hy), maxZ.push_back(z + hz);
    group.push_back(g), mask.push_back(m), flags.push_back(std::uint8_t(kProxyActive | extraFlags));
  }
  ProxyArrays view() const {
    ProxyArrays p;
    p.count = std::uint32_t(flags.size());
    p.minX = minX.data(), p.minY = minY.data(), p.minZ = minZ.data();
    p.maxX = maxX.data(), p.maxY = maxY.data(), p.maxZ = maxZ.data();
    p.group = group.data(), p.mask = mask.data(), p.flags = flags.data();
    return p;
  }
};

/// A scene's boxes and filters as records (proxy_records.h).
ProxyRecords recordsOf(const Scene& s) {
  ProxyRecords records(s.flags.size());
  for (std::size_t i = 0; i < s.flags.size(); ++i) {
    const float lo[3] = {s.minX[i], s.minY[i], s.minZ[i]}, hi[3] = {s.maxX[i], s.maxY[i], s.maxZ[i]};
    records.set(i, lo, hi, s.group[i], s.mask[i]);
  }
  return records;
}

Scene uniformScene(std::size_t n, float world, float half, std::uint32_t seed, float offset = 0.0f) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> position(offset, offset + world);
  std::uniform_real_distribution<float> size(0.2f * half, half);
  Scene s;
  for (std::size_t i = 0; i < n; ++i) {
    s.add(position(random), position(random), position(random), size(random), size(random), size(random));
  }
  return s;
}

/// The stats of a full grid search of `scene` by a default OpenCL finder.
PairFinderStats fullSearchStats(const Scene& scene) {
  std::unique_ptr<PairFinder> finder = makePairFinder(Config{});
  PairFinderOptions options;
  options.bruteForceBelow = 0;
  std::vector<std::uint64_t> pairs;
  finder->findPairs(scene.view(), options, pairs);
  return finder->stats();
}

/// Whether a full grid search of `scene` sorts its entries by counting over the cells rather than by the
/// radix sort (stage 5).
bool sortsByCountingOn(const Scene& scene) {
  const PairFinderStats s = fullSearchStats(scene);
  return sortsByCounting(std::uint64_t(s.dims[0]) * s.dims[1] * s.dims[2], s.rebinnedProxies - s.hugeProxies);
}

/// Runs the OpenCL finder (grid and brute-force paths, both square roots, three launch shapes and the runs of
/// dense grids always listed; boxes in six arrays and in records) and checks it against the CPU finder (bit
/// for bit, same order) and the double-precision brute force (same set).
void expectMatchesReferences(const Scene& scene, const std::string& what,
                             std::uint32_t bruteForceBelow = 1000) {
  OpenClContext* context = OpenClContext::tryGet();
  ASSERT_NE(context, nullptr);
  // The device's own launch shape, one candidate per item (a GPU's), and an odd chunk length with the
  // buffers kept between searches (a discrete GPU's policy) rather than released; and a dense grid's filled
  // cells always listed as its runs.
  // Made once and never destroyed: OpenCL objects released by a static destructor at exit race the driver's
  // own teardown (NVIDIA's driver is known to crash there), as the contexts do (opencl_context.cpp).
  static std::unique_ptr<PairFinder>* finders =
      new std::unique_ptr<PairFinder>[4]{makePairFinder(Config{}), makePairFinder(Config{}, {1}),
                                         makePairFinder(Config{}, {7, kKeepBuffers}),
                                         makePairFinder(Config{}, listedRuns())};
  std::unique_ptr<PairFinder> cpu = makeCpuPairFinder();
  const ProxyArrays proxies = scene.view();
  const std::vector<std::uint64_t> expected = BruteForcePairFinder::pairsOf(proxies);
  // The boxes in six arrays, and in records read in place (where the device shares the host's memory) or
  // copied from them.
  const ProxyRecords records = recordsOf(scene);
  const ProxyArrays views[3] = {
      proxies, records.view(ProxyRecords::Blocks::EndToEnd, proxies.group, proxies.mask, proxies.flags),
      records.view(ProxyRecords::Blocks::Apart, proxies.group, proxies.mask, proxies.flags)};
  for (int f = 0; f < 4; ++f) {
    std::unique_ptr<PairFinder>& gpu = finders[f];
    ASSERT_NE(gpu, nullptr);
    for (int v = 0; v < 3; ++v) {
      const std::string how = what + (v == 0 ? "" : v == 1 ? ", records end to end" : ", records apart");
      for (MappingSqrt root : {MappingSqrt::Double, MappingSqrt::Newton}) {
        for (std::uint32_t below : {std::uint32_t(0), bruteForceBelow}) {
          PairFinderOptions options;
          options.bruteForceBelow = below;
          options.mappingSqrt = root;
          std::vector<std::uint64_t> fromGpu, fromCpu;
          gpu->findPairs(views[v], options, fromGpu);
          cpu->findPairs(proxies, options, fromCpu);
          if (below == 0 && proxies.count >= 2) {
            EXPECT_TRUE(gpu->stats().usedGrid) << how << ": the grid path was not taken";
          }
          if (proxies.count >= 2) {
            EXPECT_EQ(gpu->stats().recordsReadInPlace, v == 1 && context->sharesHostMemory()) << how;
          }
          EXPECT_EQ(fromGpu.size(), expected.size()) << how << ", bruteForceBelow " << below;
          EXPECT_TRUE(fromGpu == expected)
              << how << ": OpenCL pairs differ from brute force, bruteForceBelow " << below;
          EXPECT_TRUE(fromGpu == fromCpu) << how << ": OpenCL pairs differ from the CPU finder";
        }
      }
    }
  }
}

TEST(OpenClPairFinder, UniformCloud) {
  GPUCOL_REQUIRE_OPENCL(context);
  expectMatchesReferences(uniformScene(3000, 100.0f, 1.5f, 1), "uniform");
  expectMatchesReferences(uniformScene(500, 30.0f, 1.5f, 2), "small uniform");
  EXPECT_GT(BruteForcePairFinder::pairsOf(uniformScene(3000, 100.0f, 1.5f, 1).view()).size(), 100u)
      << "scene too sparse";
  EXPECT_TRUE(sortsByCountingOn(uniformScene(3000, 100.0f, 1.5f, 1))) << "the counting sort was not run";
  // Runs of a dense grid: the filled cells listed (under two thirds filled), and every cell a run.
  EXPECT_FALSE(fullSearchStats(uniformScene(3000, 100.0f, 1.5f, 1)).runsAreCells);
  EXPECT_TRUE(fullSearchStats(uniformScene(500, 30.0f, 1.5f, 2)).runsAreCells);
}

TEST(OpenClPairFinder, ClusteredScene) {
  GPUCOL_REQUIRE_OPENCL(context);
  std::mt19937 random(3);
  std::normal_distribution<float> around(0.0f, 2.0f);
  Scene s;
  for (int cluster = 0; cluster < 5; ++cluster) {
    const float cx = 200.0f * cluster, cy = -50.0f * cluster, cz = 10.0f;
    for (int i = 0; i < 600; ++i) {
      s.add(cx + around(random), cy + around(random), cz + around(random), 0.5f, 0.5f, 0.5f);
    }
  }
  expectMatchesReferences(s, "clustered");
  EXPECT_FALSE(sortsByCountingOn(s)) << "the radix sort of a sparse grid was not run";
}

TEST(OpenClPairFinder, DenseGridOfMoreThan2To19CellsSortedByCounting) {
  GPUCOL_REQUIRE_OPENCL(context);
  // A grid past the cache-sized 2^19 cells that the counting sort takes for memory (at most 1.5 cells per box):
  // the atomic placing over half a million cells, against the CPU finder (itself checked against brute force
  // at this size by the slab search's tests). Too many boxes for the brute force here.
  const Scene s = uniformScene(420000, 122.0f, 0.45f, 21);
  const ProxyRecords records = recordsOf(s);
  const ProxyArrays views[2] = {
      s.view(), records.view(ProxyRecords::Blocks::EndToEnd, s.group.data(), s.mask.data(), s.flags.data())};
  std::unique_ptr<PairFinder> gpu = makePairFinder(Config{}), cpu = makeCpuPairFinder();
  ASSERT_NE(gpu, nullptr);
  PairFinderOptions options;
  std::vector<std::uint64_t> fromCpu;
  cpu->findPairs(views[0], options, fromCpu);
  ASSERT_GT(fromCpu.size(), 10000u) << "scene too sparse";
  for (const ProxyArrays& view : views) {
    std::vector<std::uint64_t> fromGpu;
    gpu->findPairs(view, options, fromGpu);
    const PairFinderStats& st = gpu->stats();
    const std::uint64_t cells = std::uint64_t(st.dims[0]) * st.dims[1] * st.dims[2];
    const std::uint32_t binned = st.rebinnedProxies - st.hugeProxies;
    ASSERT_GT(cells, std::uint64_t(1) << 19) << "the grid should pass 2^19 cells";
    ASSERT_LE(2 * cells, 3 * std::uint64_t(binned)) << "the grid should hold at most 1.5 cells per box";
    ASSERT_TRUE(sortsByCounting(cells, binned));
    EXPECT_EQ(fromGpu.size(), fromCpu.size());
    EXPECT_TRUE(fromGpu == fromCpu) << "OpenCL pairs differ from the CPU finder";
  }
}

TEST(OpenClPairFinder, MixedSizesWithHugeBoxes) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene s = uniformScene(2500, 80.0f, 1.0f, 4);
  s.add(40.0f, -1.0f, 40.0f, 100.0f, 1.0f, 100.0f, kProxyStatic);  // ground
  s.add(10.0f, 10.0f, 10.0f, 30.0f, 30.0f, 30.0f);                 // huge dynamic box
  s.add(70.0f, 70.0f, 70.0f, 20.0f, 5.0f, 20.0f);
  Scene more = uniformScene(300, 80.0f, 6.0f, 5);
  for (std::size_t i = 0; i < more.flags.size(); ++i) {
    s.add(more.minX[i] + 3, more.minY[i] + 3, more.minZ[i] + 3, 3, 3, 3);
  }
  expectMatchesReferences(s, "mixed sizes");
  std::unique_ptr<PairFinder> finder = makePairFinder(Config{});
  PairFinderOptions options;
  options.bruteForceBelow = 0;
  std::vector<std::uint64_t> pairs;
  finder->findPairs(s.view(), options, pairs);
  EXPECT_GE(finder->stats().hugeProxies, 2u) << "the huge boxes did not take the huge-box path";
}

TEST(OpenClPairFinder, AllInOnePlane) {
  GPUCOL_REQUIRE_OPENCL(context);
  std::mt19937 random(6);
  std::uniform_real_distribution<float> position(0.0f, 100.0f);
  Scene s;
  for (int i = 0; i < 2500; ++i) {
    s.add(position(random), 0.0f, position(random), 1.0f, 0.0f, 1.0f);  // flat boxes, y extent zero
  }
  expectMatchesReferences(s, "one plane");
}

TEST(OpenClPairFinder, HundredsOfIdenticalBoxesAtOneSpot) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene s;
  for (int i = 0; i < 700; ++i) {
    s.add(5.0f, 5.0f, 5.0f, 1.0f, 1.0f, 1.0f);
  }
  for (int i = 0; i < 400; ++i) {
    s.add(9.0f, 9.0f, 9.0f, 0.0f, 0.0f, 0.0f);  // points, all at one spot
  }
  expectMatchesReferences(s, "identical boxes", 500);
}

TEST(OpenClPairFinder, FarFromTheOriginAndNegative) {
  GPUCOL_REQUIRE_OPENCL(context);
  expectMatchesReferences(uniformScene(2000, 100.0f, 1.5f, 7, 1.0e6f), "far from origin");
  expectMatchesReferences(uniformScene(2000, 100.0f, 1.5f, 8, -1.0e6f), "far negative");
  expectMatchesReferences(uniformScene(2000, 60.0f, 1.5f, 9, -30.0f), "around the origin");
}

TEST(OpenClPairFinder, HolesStaticsAndFilters) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene s = uniformScene(3000, 60.0f, 1.5f, 10);
  std::mt19937 random(11);
  for (std::size_t i = 0; i < s.flags.size(); ++i) {
    const std::uint32_t r = random() % 10;
    if (r == 0) s.flags[i] = 0;  // destroyed proxy: a hole
    if (r == 1) s.flags[i] = kProxyActive | kProxyStatic;
    if (r == 2) s.group[i] = 2, s.mask[i] = ~2;  // group 2 ignores its own group
    if (r == 3) s.mask[i] = 0;                   // collides with nothing
  }
  expectMatchesReferences(s, "holes, statics and filters");
}

TEST(OpenClPairFinder, TrivialInputs) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene empty;
  expectMatchesReferences(empty, "empty");
  Scene one;
  one.add(0, 0, 0, 1, 1, 1);
  expectMatchesReferences(one, "one box");
  one.add(2, 0, 0, 1, 1, 1);  // touching faces count
  expectMatchesReferences(one, "two touching");
  EXPECT_EQ(BruteForcePairFinder::pairsOf(one.view()).size(), 1u);
}

TEST(OpenClPairFinder, GrowsItsOutputAcrossSteps) {
  GPUCOL_REQUIRE_OPENCL(context);
  // A sparse scene, then a dense one: the second overflows the output sized from the first and must rerun.
  expectMatchesReferences(uniformScene(2000, 400.0f, 1.0f, 12), "sparse");
  expectMatchesReferences(uniformScene(2000, 20.0f, 1.5f, 13), "dense");
}

/// Stage 11 over steps: OpenCL finders (three launch shapes, the last keeping its buffers; a fourth that
/// reads the boxes in records, in place where the device shares the host's memory, and carries pairs over
/// from the test's coded copy of its last result, as from GridBroadphase's; a fifth whose dense grids always
/// list their filled cells as runs) and a CPU finder see the same scene and the same `moved` flags each step.
/// Each OpenCL finder's pairs must equal the CPU finder's (bit for bit, same order) and brute force, and its
/// resting/re-binned counts and path (grid, incremental) the CPU finder's.
class SteppedFinders {
 public:
  explicit SteppedFinders(const PairFinderOptions& options)
      : m_options(options),
        m_gpu{makePairFinder(Config{}), makePairFinder(Config{}, {1}),
              makePairFinder(Config{}, {7, kKeepBuffers}), makePairFinder(Config{}),
              makePairFinder(Config{}, listedRuns())},
        m_cpu(makeCpuPairFinder()) {}

  /// One search of every finder; `moved` may be nullptr (anything may have changed). Returns the OpenCL
  /// finders' common stats (the first finder's).
  PairFinderStats step(const Scene& scene, const std::uint8_t* moved, const std::string& what) {
    ProxyArrays view = scene.view();
    view.moved = moved;
    std::vector<std::uint64_t> fromCpu;
    m_cpu->findPairs(view, m_options, fromCpu);
    const std::vector<std::uint64_t> expected = BruteForcePairFinder::pairsOf(view);
    EXPECT_TRUE(fromCpu == expected) << what << ": the CPU finder differs from brute force";
    const PairFinderStats& cpu = m_cpu->stats();
    const ProxyRecords records = recordsOf(scene);
    ProxyArrays recordsView = records.view(ProxyRecords::Blocks::EndToEnd, view.group, view.mask, view.flags);
    recordsView.moved = moved;
    recordsView.lastPairs = &m_lastOfRecordsFinder;
    for (std::unique_ptr<PairFinder>& gpu : m_gpu) {
      std::vector<std::uint64_t> fromGpu;
      const bool inRecords = &gpu == &m_gpu[3];
      gpu->findPairs(inRecords ? recordsView : view, m_options, fromGpu);
      if (inRecords) m_lastOfRecordsFinder.assign(fromGpu);
      if (inRecords && view.count >= 2 && cpu.usedGrid) {
        EXPECT_EQ(gpu->stats().recordsReadInPlace, OpenClContext::tryGet()->sharesHostMemory()) << what;
      }
      EXPECT_EQ(fromGpu.size(), expected.size()) << what;
      EXPECT_TRUE(fromGpu == fromCpu) << what << ": OpenCL pairs differ from the CPU finder";
      EXPECT_TRUE(fromGpu == expected) << what << ": OpenCL pairs differ from brute force";
      const PairFinderStats& st = gpu->stats();
      EXPECT_EQ(st.usedGrid, cpu.usedGrid) << what;
      EXPECT_EQ(st.incremental, cpu.incremental) << what;
      EXPECT_EQ(st.restingProxies, cpu.restingProxies) << what;
      EXPECT_EQ(st.rebinnedProxies, cpu.rebinnedProxies) << what;
    }
    return m_gpu[0]->stats();
  }

 private:
  PairFinderOptions m_options;
  std::unique_ptr<PairFinder> m_gpu[5];
  PackedPairs m_lastOfRecordsFinder;  // the fourth finder's last result, coded
  std::unique_ptr<PairFinder> m_cpu;
};

std::uint32_t activeCount(const Scene& s) {
  std::uint32_t n = 0;
  for (std::uint8_t f : s.flags) n += (f & kProxyActive) != 0;
  return n;
}

void shift(Scene& s, std::size_t i, float dx, float dy, float dz) {
  s.minX[i] += dx, s.maxX[i] += dx, s.minY[i] += dy, s.maxY[i] += dy, s.minZ[i] += dz, s.maxZ[i] += dz;
}

TEST(OpenClPairFinder, RestingProxiesAtEachFractionMoving) {
  GPUCOL_REQUIRE_OPENCL(context);
  // 0%, 1%, 50% and 100% of the dynamic boxes move every step; a fifth of the boxes are static and never
  // move. While few have changed since the kept grid was built, exactly the others rest.
  for (const double fraction : {0.0, 0.01, 0.5, 1.0}) {
    const std::string what = "fraction " + std::to_string(fraction);
    Scene s = uniformScene(5000, 40.0f, 1.0f, 20);
    std::vector<std::uint32_t> dynamic;
    for (std::size_t i = 0; i < s.flags.size(); ++i) {
      if (i % 5 == 0) {
        s.flags[i] |= kProxyStatic;
      } else {
        dynamic.push_back(std::uint32_t(i));
      }
    }
    PairFinderOptions options;
    options.bruteForceBelow = 0;
    SteppedFinders finders(options);
    std::mt19937 random(21);
    std::uniform_real_distribution<float> step(-0.4f, 0.4f);
    std::vector<std::uint8_t> moved(s.flags.size(), 0), changedSinceKept(s.flags.size(), 0);
    PairFinderStats st = finders.step(s, nullptr, what + ", step 0");
    EXPECT_TRUE(st.usedGrid && !st.incremental) << what << ": the first search is a full one";
    // Its grid (mostly filled cells) takes every cell as a run, so the moved boxes are tested against such a
    // kept grid; the fifth finder lists its filled cells.
    EXPECT_TRUE(st.runsAreCells) << what;
    int incrementalSteps = 0;
    for (int t = 1; t <= 8; ++t) {
      std::fill(moved.begin(), moved.end(), std::uint8_t(0));
      std::shuffle(dynamic.begin(), dynamic.end(), random);
      const std::size_t count = std::size_t(fraction * double(dynamic.size()) + 0.5);
      for (std::size_t k = 0; k < count; ++k) {
        shift(s, dynamic[k], step(random), step(random), step(random));
        moved[dynamic[k]] = 1;
      }
      st = finders.step(s, moved.data(), what + ", step " + std::to_string(t));
      const std::uint32_t active = activeCount(s);
      EXPECT_EQ(st.restingProxies + st.rebinnedProxies, active) << what << ", step " << t;
      if (st.incremental) {
        ++incrementalSteps;
        std::uint32_t changed = 0;
        for (std::size_t i = 0; i < moved.size(); ++i) {
          changedSinceKept[i] |= moved[i];
          changed += changedSinceKept[i];
        }
        EXPECT_EQ(st.restingProxies, active - changed) << what << ", step " << t;
        EXPECT_EQ(st.keys == 0, changed == 0) << what << ": only the moved proxies are binned";
      } else {
        EXPECT_EQ(st.restingProxies, 0u) << what << ", step " << t;
        std::fill(changedSinceKept.begin(), changedSinceKept.end(), std::uint8_t(0));
      }
    }
    if (fraction <= 0.01) {
      EXPECT_EQ(incrementalSteps, 8) << what << ": the kept grid was not used";
    } else {
      EXPECT_EQ(incrementalSteps, 0) << what << ": too many moved for the kept grid";
    }
  }
}

TEST(OpenClPairFinder, RestingProxiesWithLifeAndFilterChanges) {
  GPUCOL_REQUIRE_OPENCL(context);
  // A few boxes each step vanish or come back, change filters while resting, jump far (out of the kept
  // grid), shift a little; a huge pillar moves now and then beside a huge static ground (kept huge boxes and
  // moved huge boxes); new proxies arrive. Pairs must stay exact and the skip must keep happening.
  Scene s = uniformScene(6000, 20.0f, 0.7f, 22);
  for (std::size_t i = 0; i < s.flags.size(); i += 5) s.flags[i] |= kProxyStatic;
  s.add(10.0f, -0.5f, 10.0f, 25.0f, 0.5f, 25.0f, kProxyStatic);  // huge static ground
  s.add(10.0f, 10.0f, 10.0f, 3.0f, 20.0f, 3.0f);                 // huge moving pillar
  const std::size_t pillar = s.flags.size() - 1;
  PairFinderOptions options;
  options.bruteForceBelow = 0;
  SteppedFinders finders(options);
  std::mt19937 random(23);
  std::uniform_real_distribution<float> step(-0.3f, 0.3f), far(-30.0f, 50.0f);
  std::vector<std::uint8_t> moved(s.flags.size(), 1);
  int incrementalSteps = 0;
  for (int t = 0; t < 14; ++t) {
    const PairFinderStats st = finders.step(s, moved.data(), "life and filters, step " + std::to_string(t));
    EXPECT_EQ(st.restingProxies + st.rebinnedProxies, activeCount(s)) << "step " << t;
    if (st.incremental) {
      ++incrementalSteps;
      EXPECT_GE(st.restingProxies, activeCount(s) * 3 / 4) << "step " << t;
    }
    std::fill(moved.begin(), moved.end(), std::uint8_t(0));
    if (t == 9) {
      // Half of the boxes at once: a full search and a new grid, then the skip resumes.
      for (std::size_t i = 0; i < s.flags.size(); i += 2) {
        shift(s, i, step(random), 0.0f, 0.0f);
        moved[i] = 1;
      }
      continue;
    }
    for (int k = 0; k < 60; ++k) {
      const std::size_t i = random() % s.flags.size();
      moved[i] = 1;
      switch (k % 6) {
        case 0:
          // Vanish or come back. A proxy that vanishes needs no moved flag (its flags say it is gone).
          s.flags[i] ^= kProxyActive;
          moved[i] = (s.flags[i] & kProxyActive) != 0;
          break;
        case 1:
          s.group[i] = (s.group[i] == 1 ? 2 : 1), s.mask[i] = 1;  // filter change, box at rest
          break;
        case 2: {
          const float h = 0.5f * (s.maxX[i] - s.minX[i]);
          shift(s, i, far(random) - (s.minX[i] + h), far(random) - (s.minY[i] + h),
                far(random) - (s.minZ[i] + h));
          break;
        }
        case 3:
          s.flags[i] ^= kProxyStatic;  // becomes static or dynamic while resting
          break;
        default:
          shift(s, i, step(random), step(random), step(random));
      }
    }
    if (t % 3 == 1) {
      shift(s, pillar, 1.5f, 0.0f, 0.0f);
      moved[pillar] = 1;
    }
    for (int k = 0; k < 10; ++k) {  // new proxies
      s.add(far(random) * 0.5f, far(random) * 0.5f, far(random) * 0.5f, 0.5f, 0.5f, 0.5f);
      moved.push_back(1);
    }
  }
  EXPECT_GE(incrementalSteps, 9) << "the kept grid was not used";
}

TEST(OpenClPairFinder, FullSearchWhenTheGridOptionsOrMotionAreUnknown) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene s = uniformScene(4000, 30.0f, 1.0f, 24);
  PairFinderOptions options;
  options.bruteForceBelow = 0;
  std::unique_ptr<PairFinder> gpu = makePairFinder(Config{});
  std::unique_ptr<PairFinder> cpu = makeCpuPairFinder();
  std::vector<std::uint8_t> moved(s.flags.size(), 0);
  auto search = [&](const PairFinderOptions& o, const std::uint8_t* m, const std::string& what) {
    ProxyArrays view = s.view();
    view.moved = m;
    std::vector<std::uint64_t> fromGpu, fromCpu;
    gpu->findPairs(view, o, fromGpu);
    cpu->findPairs(view, o, fromCpu);
    EXPECT_TRUE(fromGpu == fromCpu) << what;
    EXPECT_TRUE(fromGpu == BruteForcePairFinder::pairsOf(view)) << what;
    return gpu->stats();
  };
  search(options, nullptr, "first");
  shift(s, 3, 0.5f, 0.5f, 0.5f);
  moved[3] = 1;
  EXPECT_TRUE(search(options, moved.data(), "one moved").incremental);
  // Another cell size rule: the kept grid no longer fits the options.
  PairFinderOptions density = options;
  density.cellSizeRule = CellSizeRule::Density;
  moved[3] = 0;
  EXPECT_FALSE(search(density, moved.data(), "other cell size rule").incremental);
  EXPECT_TRUE(search(density, moved.data(), "same rule again").incremental);
  // Motion unknown: a full search.
  shift(s, 7, -0.5f, 0.0f, 0.0f);
  EXPECT_FALSE(search(density, nullptr, "moved unknown").incremental);
  // Below the brute-force threshold: no grid, nothing kept.
  PairFinderOptions brute = density;
  brute.bruteForceBelow = 100000;
  EXPECT_FALSE(search(brute, moved.data(), "brute force").usedGrid);
  EXPECT_FALSE(search(density, moved.data(), "grid again").incremental);
}

TEST(OpenClPairFinder, IsWhatTheBroadphaseGetsWhereOpenClIsBuiltIn) {
  GPUCOL_REQUIRE_OPENCL(context);
  std::unique_ptr<PairFinder> finder = gpucol::makeOpenClPairFinder(Config{});
  ASSERT_NE(finder, nullptr);
  EXPECT_EQ(finder->name(), "opencl");
}

}  // namespace
}  // namespace gpucol::opencl
