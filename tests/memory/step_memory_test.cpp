// GridBroadphaseStats::memoryBytes and peakBytes against the heap itself (counting_heap.h), so the figures
// the memory targets (docs/measured-results.md, "Broad phase") rest on are checked against what was really allocated (through operator new:
// the broad phase's vectors; Bullet's own arrays use malloc and are not counted, as the stats leave Bullet's
// pair cache out).
#include <btBulletCollisionCommon.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "counting_heap.h"
#include "gpucol/grid_broadphase.h"

namespace {

using gpucol::test::HeapOfStep;
using gpucol::test::measureHeap;

/// `count` random boxes of half sizes 0.2-1.2 in a cube of half side `side` (denser when smaller): a first
/// step, two where every box moves a little (full searches; the pairs barely change, so Bullet's pair
/// cache, which neither side counts, hardly grows), and two where 1% move (a full search that keeps its grid,
/// then stage 11 on it). After each step:
/// - what the stats hold more or less than before is what the heap kept (but on the first step, which also
///   holds the proxies: Bullet allocates those itself, out of the heap's sight);
/// - the stats' peak above what they hold after the step is the heap's high-water mark above what it kept,
///   within `kSlack` bytes either way (allocations the stats do not count: small lists of a few entries,
///   TBB's and the test's own), so it neither misses memory nor counts memory that never was there.
/// `mixedSizes`: every 16th box three times as large, so that the boxes are not of about one size (no search
/// by home cell).
void expectStatsMatchTheHeap(int count, float side, std::uint64_t minPairs, bool mixedSizes = false) {
  constexpr std::ptrdiff_t kSlack = 16 * 1024;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  gpucol::Config config;
  config.broadphaseBackend = gpucol::Backend::Cpu;  // no OpenCL set-up in the heap's figures
  gpucol::GridBroadphase bp(config);                // boxes read in place, slab search
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> pos(-side, side), size(0.2f, 1.2f);
  const std::size_t n = std::size_t(count);
  std::vector<btVector3> lo(n), hi(n);
  std::vector<btBroadphaseProxy*> proxies(n);
  for (std::size_t i = 0; i < n; ++i) {
    const btVector3 c(pos(rng), pos(rng), pos(rng));
    const btVector3 h =
        btVector3(size(rng), size(rng), size(rng)) * (mixedSizes && i % 16 == 0 ? 3.0f : 1.0f);
    lo[i] = c - h, hi[i] = c + h;
  }
  const HeapOfStep created = measureHeap([&] {
    for (std::size_t i = 0; i < n; ++i)
      proxies[i] = bp.createProxy(lo[i], hi[i], BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher);
  });
  std::ptrdiff_t heldBefore = 0;
  for (int step = 0; step < 5; ++step) {
    const HeapOfStep heap = measureHeap([&] {
      const btVector3 d(0.001f * float(step), 0.0f, 0.0f);
      for (std::size_t i = 0; step > 0 && i < n; i += step < 3 ? 1 : 100)
        bp.setAabb(proxies[i], lo[i] + d, hi[i] + d, &dispatcher);
      bp.calculateOverlappingPairs(&dispatcher);
    });
    const gpucol::GridBroadphaseStats& st = bp.stats();
    ASSERT_TRUE(st.searched && st.usedGrid) << "step " << step;
    ASSERT_GE(st.overlappingPairs, minPairs) << "step " << step;
    ASSERT_EQ(st.restingProxies, step == 4 ? std::uint32_t(count - count / 100) : 0u) << "step " << step;
    const std::ptrdiff_t held = std::ptrdiff_t(st.memoryBytes);
    if (step == 0) {
      // The proxies' blocks: Bullet's aligned allocator, not operator new.
      const std::ptrdiff_t unseen = held - heap.kept - created.kept;
      EXPECT_GE(unseen, std::ptrdiff_t(n * sizeof(btBroadphaseProxy)));
      EXPECT_LE(unseen, std::ptrdiff_t((n + 256) * (sizeof(btBroadphaseProxy) + 16)));
    } else {
      EXPECT_NEAR(double(heap.kept), double(held - heldBefore), double(kSlack))
          << "step " << step << ": bytes kept by the step";
    }
    const std::ptrdiff_t reported = std::ptrdiff_t(st.peakBytes) - held;
    EXPECT_NEAR(double(heap.mark - heap.kept), double(reported), double(kSlack))
        << "step " << step << ": the peak above what the step kept";
    heldBefore = held;
  }
}

TEST(StepMemory, SparseCloudAsTheHeapSeesIt) {
  // About 0.5 pairs per proxy: the slab search's working memory makes the peak.
  expectStatsMatchTheHeap(40000, 48.0f, 10000);
}

TEST(StepMemory, SparseCloudOnOneThreadAsTheHeapSeesIt) {
  // One thread holds one slab's working memory: the search that drops the first step's kept grid never
  // comes back up to what the step started with, which is then its peak.
  tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
  expectStatsMatchTheHeap(40000, 48.0f, 10000);
}

TEST(StepMemory, DensePileAsTheHeapSeesIt) {
  // About 15 pairs per proxy: the step's pair lists make the peak.
  expectStatsMatchTheHeap(20000, 12.0f, 200000);
}

TEST(StepMemory, DensePileOfMixedSizesAsTheHeapSeesIt) {
  // Boxes of mixed sizes: each in every cell it overlaps, not by home cell.
  expectStatsMatchTheHeap(20000, 12.0f, 200000, true);
}

}  // namespace
