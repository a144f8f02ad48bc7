// The OpenCL pair finder's PairFinderStats::scratchBytes against the process's heap. Its device buffers are
// allocated by the OpenCL driver, not through operator new, so tests/memory cannot see them; on PoCL's CPU
// device they come from malloc, which glibc's mallinfo2 counts over all arenas (and mmap'd blocks). A finder
// that keeps a buffer or a list it does not count shows up here as heap the stats do not explain.
#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"
#include "opencl/host/opencl_pair_finder.h"
#include "opencl/host/scan.h"
#include "opencl_test_device.h"
#include "proxy_records.h"

namespace gpucol::opencl {
namespace {

/// What the driver may hold for one finder besides its buffers (its kernels, queued commands' records):
/// 38-50 KB were measured; a list or a buffer per proxy left out is far more at the sizes below.
constexpr std::ptrdiff_t kUncountedSlack = 256 * 1024;

/// A cloud of unit boxes, one box per 8 unit cubes (about half a pair per box), optionally as two
/// clusters `gap` apart along x (a sparse grid: the finder sorts (cell, slot) keys by radix).
struct Cloud {
  std::vector<float> corner[6];
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> flags, moved;

  Cloud(std::size_t n, float gap, std::uint32_t seed) {
    std::mt19937 random(seed);
    const float side = std::cbrt(float(n) * 8.0f);
    std::uniform_real_distribution<float> position(0, side);
    for (std::size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        const float c = position(random) + (a == 0 && i % 2 ? gap : 0.0f);
        corner[a].push_back(c - 0.5f), corner[a + 3].push_back(c + 0.5f);
      }
    }
    group.assign(n, 1), mask.assign(n, -1), flags.assign(n, kProxyActive), moved.assign(n, 1);
  }
  /// Moves every `every`-th box by a small step (and marks only those moved).
  void move(std::size_t every, float step) {
    for (std::size_t i = 0; i < flags.size(); ++i) {
      moved[i] = i % every == 0;
      if (moved[i])
        for (float* x : {&corner[0][i], &corner[3][i]}) *x += step;
    }
  }
  /// Writes every box and filter into `records`.
  void writeInto(ProxyRecords& records) const {
    for (std::size_t i = 0; i < flags.size(); ++i) {
      const float lo[3] = {corner[0][i], corner[1][i], corner[2][i]};
      const float hi[3] = {corner[3][i], corner[4][i], corner[5][i]};
      records.set(i, lo, hi, group[i], mask[i]);
    }
  }
  ProxyArrays view() const {
    ProxyArrays p;
    p.count = std::uint32_t(flags.size());
    p.minX = corner[0].data(), p.minY = corner[1].data(), p.minZ = corner[2].data();
    p.maxX = corner[3].data(), p.maxY = corner[4].data(), p.maxZ = corner[5].data();
    p.group = group.data(), p.mask = mask.data(), p.flags = flags.data(), p.moved = moved.data();
    return p;
  }
};

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
std::size_t heapBytes() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

/// The heap once the driver has done what it had queued: it frees a released buffer when its commands are
/// done, from its own threads, so a finder destroyed just before can still be shrinking the heap. Waits
/// (up to a second) for two readings 10 ms apart to agree.
std::size_t settledHeapBytes(OpenClContext& context) {
  context.queue().finish();
  std::size_t last = heapBytes();
  for (int i = 0; i < 100; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const std::size_t now = heapBytes();
    if (now == last) break;
    last = now;
  }
  return last;
}
#endif

/// Steps a fresh finder over `cloud` (moving every `every`-th box between steps) and checks, after each
/// step, the heap it added against its scratch bytes and the pair list it returned. `inRecords`: the boxes
/// are given as records end to end (proxy_records.h), which the finder reads in place: the heap then shows
/// that the driver made no copy of them either.
void expectHeapExplained(
    OpenClContext& context, Cloud cloud, std::size_t every, const std::string& what,
    OpenClPairFinderTuning::BufferRelease release = OpenClPairFinderTuning::BufferRelease::Auto,
    bool inRecords = false) {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // A GPU's buffers are not in the host's heap, and another CPU runtime may map its own memory.
  const cl::Platform platform(context.device().getInfo<CL_DEVICE_PLATFORM>());
  if (platform.getInfo<CL_PLATFORM_NAME>() != "Portable Computing Language" || context.isGpu()) {
    GTEST_SKIP() << what << ": the heap holds the device's buffers only on PoCL's CPU device";
  }
  EXPECT_TRUE(context.sharesHostMemory()) << "PoCL's CPU device: its buffers are the process's memory";
  PairFinderOptions options;
  // The context's programs and the driver's first allocations, before the count starts. The warm-up finder
  // stays alive, so that none of its buffers is freed after the count has started (destroyed, under load,
  // the heap then grew by megabytes less than the finder holds).
  std::unique_ptr<PairFinder> warm = makePairFinder(Config{});
  ASSERT_NE(warm, nullptr);
  std::vector<std::uint64_t> pairs;
  ProxyRecords records(inRecords ? cloud.flags.size() : 0);
  auto input = [&](const Cloud& c) {
    if (!inRecords) return c.view();
    c.writeInto(records);
    ProxyArrays p =
        records.view(ProxyRecords::Blocks::EndToEnd, c.group.data(), c.mask.data(), c.flags.data());
    p.moved = c.moved.data();
    return p;
  };
  {
    // The same input as below, so that the programs it builds (one per way of reading the boxes) are built.
    Cloud copy = cloud;
    for (int step = 0; step < 3; ++step, copy.move(every, 0.05f))
      warm->findPairs(input(copy), options, pairs);
  }
  std::vector<std::uint64_t>().swap(pairs);
  pairs.reserve(1);
  const std::size_t before = settledHeapBytes(context);
  std::unique_ptr<PairFinder> finder = makePairFinder(Config{}, {0, release});
  ASSERT_NE(finder, nullptr);
  for (int step = 0; step < 4; ++step, cloud.move(every, 0.05f)) {
    finder->findPairs(input(cloud), options, pairs);
    // Settled: the finder releases its per-search buffers at the end of each search.
    const std::ptrdiff_t added = std::ptrdiff_t(settledHeapBytes(context) - before);
    const std::ptrdiff_t counted = std::ptrdiff_t(finder->stats().scratchBytes + pairs.capacity() * 8);
    EXPECT_NEAR(double(added), double(counted), double(kUncountedSlack))
        << what << ", step " << step << ": the heap grew by " << added << " bytes, the finder counts "
        << finder->stats().scratchBytes << " and its pair list holds " << pairs.capacity() * 8;
    EXPECT_GT(pairs.size(), 0u) << what;
    const PairFinderStats& stats = finder->stats();
    EXPECT_EQ(stats.recordsReadInPlace, inRecords) << what << ", step " << step;
    // The search's high-water mark is still reported once its buffers are gone: every box was on the device
    // (GpucolProxyBox, 32 bytes) unless it read them in place, and it held at least what it keeps.
    EXPECT_GE(stats.peakScratchBytes, std::max(stats.scratchBytes, inRecords ? 0 : cloud.flags.size() * 32))
        << what << ", step " << step;
    // A search that keeps no grid leaves nothing per proxy behind (PoCL's memory is the host's, so Auto
    // releases): the next one writes every box again.
    if (!stats.incremental && every == 1 && release != OpenClPairFinderTuning::BufferRelease::Never) {
      EXPECT_LT(stats.scratchBytes, 64u * 1024) << what << ", step " << step;
    }
    // One that keeps its buffers keeps at least the boxes.
    if (release == OpenClPairFinderTuning::BufferRelease::Never && !inRecords) {
      EXPECT_GE(stats.scratchBytes, cloud.flags.size() * 32) << what << ", step " << step;
    }
    // The first step moves every box, the second keeps the grid, the others search the moved boxes alone.
    if (every > 1 && step >= 2) {
      EXPECT_TRUE(finder->stats().incremental) << what << ", step " << step;
    }
  }
#else
  (void)context, (void)cloud, (void)every, (void)release, (void)inRecords;
  GTEST_SKIP() << what << ": needs glibc's mallinfo2 over the driver's own allocations (not under ASan)";
#endif
}

TEST(OpenClPairFinderMemory, ScratchBytesExplainTheHeapOfADenseGrid) {
  GPUCOL_REQUIRE_OPENCL(context);
  expectHeapExplained(context, Cloud(60000, 0.0f, 11), 1, "60K boxes, all moving");
}

TEST(OpenClPairFinderMemory, ScratchBytesExplainTheHeapOfAFinderKeepingItsBuffers) {
  GPUCOL_REQUIRE_OPENCL(context);
  expectHeapExplained(context, Cloud(60000, 0.0f, 14), 1, "60K boxes, all moving, buffers kept",
                      OpenClPairFinderTuning::BufferRelease::Never);
  expectHeapExplained(context, Cloud(60000, 0.0f, 15), 100, "60K boxes, 1% moving, buffers kept",
                      OpenClPairFinderTuning::BufferRelease::Never);
}

TEST(OpenClPairFinderMemory, HostMemoryIsReadInPlaceWhereTheDeviceSharesIt) {
  // What the finder's memory figures assume when it reads the caller's records in place: a buffer made over
  // host memory (CL_MEM_USE_HOST_PTR) on a device that shares the host's memory is that memory, with no copy
  // at any time. Here a scan over such a buffer writes straight into the host's array, and the heap grows by
  // no copy of it.
  GPUCOL_REQUIRE_OPENCL(context);
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  const cl::Platform platform(context.device().getInfo<CL_DEVICE_PLATFORM>());
  if (platform.getInfo<CL_PLATFORM_NAME>() != "Portable Computing Language" || context.isGpu()) {
    GTEST_SKIP() << "the heap holds the device's buffers only on PoCL's CPU device";
  }
  constexpr std::size_t kValues = std::size_t(1) << 22;  // 16 MB
  std::unique_ptr<std::uint32_t[]> values(new std::uint32_t[kValues]);
  OpenClScan scan(context);
  {
    // The scan's program and scratch, before the count starts.
    cl::Buffer warm(context.context(), CL_MEM_READ_WRITE, kValues * 4);
    context.queue().enqueueFillBuffer(warm, cl_uint(1), 0, kValues * 4);
    scan.exclusiveScan(warm, kValues);
  }
  std::fill(values.get(), values.get() + kValues, 1u);
  const std::size_t before = settledHeapBytes(context);
  cl::Buffer buffer(context.context(), CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR, kValues * 4, values.get());
  EXPECT_EQ(scan.exclusiveScan(buffer, kValues), std::uint64_t(kValues));
  context.queue().finish();
  EXPECT_LT(std::ptrdiff_t(heapBytes()) - std::ptrdiff_t(before), std::ptrdiff_t(kValues))
      << "a copy was made";
  // No read, no map: the device wrote into the host's array itself.
  EXPECT_EQ(values[0], 0u);
  EXPECT_EQ(values[2], 2u);
  EXPECT_EQ(values[kValues - 1], std::uint32_t(kValues - 1));
#else
  GTEST_SKIP() << "needs glibc's mallinfo2 over the driver's own allocations (not under ASan)";
#endif
}

TEST(OpenClPairFinderMemory, ScratchBytesExplainTheHeapWithBoxesReadInPlace) {
  GPUCOL_REQUIRE_OPENCL(context);
  using Release = OpenClPairFinderTuning::BufferRelease;
  expectHeapExplained(context, Cloud(60000, 0.0f, 16), 1, "60K boxes in records, all moving", Release::Auto,
                      true);
  expectHeapExplained(context, Cloud(60000, 0.0f, 17), 100, "60K boxes in records, 1% moving", Release::Auto,
                      true);
  expectHeapExplained(context, Cloud(60000, 0.0f, 18), 100, "60K boxes in records, 1% moving, buffers kept",
                      Release::Never, true);
}

TEST(OpenClPairFinderMemory, ScratchBytesExplainTheHeapWhileTheGridIsKept) {
  GPUCOL_REQUIRE_OPENCL(context);
  // 1% moving: after the first search the finder keeps its grid and bins the moved boxes alone (stage 11).
  expectHeapExplained(context, Cloud(60000, 0.0f, 12), 100, "60K boxes, 1% moving");
}

TEST(OpenClPairFinderMemory, ScratchBytesExplainTheHeapOfASparseGrid) {
  GPUCOL_REQUIRE_OPENCL(context);
  Cloud cloud(60000, 4000.0f, 13);
  PairFinderOptions options;
  std::unique_ptr<PairFinder> probe = makePairFinder(Config{});
  std::vector<std::uint64_t> pairs;
  probe->findPairs(cloud.view(), options, pairs);
  const PairFinderStats& s = probe->stats();
  ASSERT_FALSE(sortsByCounting(std::uint64_t(s.dims[0]) * s.dims[1] * s.dims[2], 60000))
      << "the two clusters should give a sparse grid (the radix sort of (cell, slot) keys)";
  expectHeapExplained(context, cloud, 1, "60K boxes in two clusters");
}

}  // namespace
}  // namespace gpucol::opencl
