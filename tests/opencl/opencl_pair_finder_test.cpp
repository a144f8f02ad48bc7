#include "opencl/host/opencl_pair_finder.h"

#include "broadphase/grid_pair_finder.h"
#include "opencl_test_device.h"

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace gpucol::opencl {
namespace {

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

/// Runs the OpenCL finder (grid and brute-force paths, both square roots, three launch shapes) and checks it against the CPU
/// finder (bit for bit, same order) and the double-precision brute force (same set).
void expectMatchesReferences(const Scene& scene, const std::string& what, std::uint32_t bruteForceBelow = 1000) {
  OpenClContext* context = OpenClContext::tryGet();
  ASSERT_NE(context, nullptr);
  // The device's own launch shape, one candidate per item (a GPU's), and an odd chunk length.
  static std::unique_ptr<PairFinder> finders[3] = {makePairFinder(Config{}), makePairFinder(Config{}, {1}),
                                                   makePairFinder(Config{}, {7})};
  std::unique_ptr<PairFinder> cpu = makeCpuPairFinder();
  const ProxyArrays proxies = scene.view();
  const std::vector<std::uint64_t> expected = findPairsBruteForce(proxies);
  for (std::unique_ptr<PairFinder>& gpu : finders) {
    ASSERT_NE(gpu, nullptr);
    for (MappingSqrt root : {MappingSqrt::Double, MappingSqrt::Newton}) {
      for (std::uint32_t below : {std::uint32_t(0), bruteForceBelow}) {
        PairFinderOptions options;
        options.bruteForceBelow = below;
        options.mappingSqrt = root;
        std::vector<std::uint64_t> fromGpu, fromCpu;
        gpu->findPairs(proxies, options, fromGpu);
        cpu->findPairs(proxies, options, fromCpu);
        if (below == 0 && proxies.count >= 2) {
          EXPECT_TRUE(gpu->stats().usedGrid) << what << ": the grid path was not taken";
        }
        EXPECT_EQ(fromGpu.size(), expected.size()) << what << ", bruteForceBelow " << below;
        EXPECT_TRUE(fromGpu == expected) << what << ": OpenCL pairs differ from brute force, bruteForceBelow "
                                         << below;
        EXPECT_TRUE(fromGpu == fromCpu) << what << ": OpenCL pairs differ from the CPU finder";
      }
    }
  }
}

TEST(OpenClPairFinder, UniformCloud) {
  GPUCOL_REQUIRE_OPENCL(context);
  expectMatchesReferences(uniformScene(3000, 100.0f, 1.5f, 1), "uniform");
  expectMatchesReferences(uniformScene(500, 30.0f, 1.5f, 2), "small uniform");
  EXPECT_GT(findPairsBruteForce(uniformScene(3000, 100.0f, 1.5f, 1).view()).size(), 100u) << "scene too sparse";
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
}

TEST(OpenClPairFinder, MixedSizesWithHugeBoxes) {
  GPUCOL_REQUIRE_OPENCL(context);
  Scene s = uniformScene(2500, 80.0f, 1.0f, 4);
  s.add(40.0f, -1.0f, 40.0f, 100.0f, 1.0f, 100.0f, kProxyStatic);  // ground
  s.add(10.0f, 10.0f, 10.0f, 30.0f, 30.0f, 30.0f);                  // huge dynamic box
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
    if (r == 0) s.flags[i] = 0;                                      // destroyed proxy: a hole
    if (r == 1) s.flags[i] = kProxyActive | kProxyStatic;
    if (r == 2) s.group[i] = 2, s.mask[i] = ~2;                      // group 2 ignores its own group
    if (r == 3) s.mask[i] = 0;                                       // collides with nothing
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
  EXPECT_EQ(findPairsBruteForce(one.view()).size(), 1u);
}

TEST(OpenClPairFinder, GrowsItsOutputAcrossSteps) {
  GPUCOL_REQUIRE_OPENCL(context);
  // A sparse scene, then a dense one: the second overflows the output sized from the first and must rerun.
  expectMatchesReferences(uniformScene(2000, 400.0f, 1.0f, 12), "sparse");
  expectMatchesReferences(uniformScene(2000, 20.0f, 1.5f, 13), "dense");
}

TEST(OpenClPairFinder, IsInstalledBehindTheBroadphaseSeam) {
  GPUCOL_REQUIRE_OPENCL(context);
  registerOpenClPairFinder();
  std::unique_ptr<PairFinder> finder = gpucol::makeOpenClPairFinder(Config{});
  ASSERT_NE(finder, nullptr);
  EXPECT_EQ(finder->name(), "opencl");
}

}  // namespace
}  // namespace gpucol::opencl
