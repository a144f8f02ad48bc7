// OpenCL implementation of the grid pair finder; stage numbers are those of grid_pair_finder.h.
#include "opencl/host/opencl_pair_finder.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

#include "broadphase/grid_choice.h"
#include "broadphase/pair_mapping.h"
#include "gpucol_kernels/kernels.h"
#include "opencl/host/device_array.h"
#include "opencl/host/opencl_context.h"
#include "opencl/host/radix_sort.h"
#include "opencl/host/scan.h"
#include "opencl/shared/grid_params.h"

namespace gpucol::opencl {

static_assert(sizeof(GpucolGridParams) == 32, "GpucolGridParams layout differs from the kernels'");
static_assert(offsetof(GpucolGridParams, invCell) == 12 && offsetof(GpucolGridParams, dimX) == 16 &&
                  offsetof(GpucolGridParams, dimZ) == 24,
              "GpucolGridParams offsets differ from the kernels'");
static_assert(GPUCOL_PROXY_ACTIVE == kProxyActive && GPUCOL_PROXY_STATIC == kProxyStatic,
              "proxy flag bits differ between grid_params.h and grid_pair_finder.h");

namespace {

class OpenClPairFinder final : public PairFinder {
 public:
  OpenClPairFinder(OpenClContext& context, const OpenClPairFinderTuning& tuning)
      : m_context(context), m_tuning(tuning), m_scan(context), m_sort(context) {}

  void findPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                 std::vector<std::uint64_t>& pairs) override;
  const PairFinderStats& stats() const override { return m_stats; }
  std::string name() const override { return "opencl"; }
  bool runsOnGpu() const override { return m_context.isGpu(); }

 private:
  struct Kernels {
    cl::Kernel countCells, writeKeys, markRuns, writeRuns, countRunPairs, testCandidates, testHuge, bruteTest;
  };
  Kernels& kernels(bool newton);
  void chooseGrid(const ProxyArrays& p, const PairFinderOptions& options, GpucolGridParams& g);
  void upload(const ProxyArrays& p);
  void setProxyArgs(cl::Kernel& kernel);
  std::size_t launchSize(const cl::Kernel& kernel, std::uint64_t items, std::size_t& local);
  void launch(cl::Kernel& kernel, std::uint64_t items);
  void launchStrided(cl::Kernel& kernel, std::uint64_t items);

  OpenClContext& m_context;
  OpenClPairFinderTuning m_tuning;
  OpenClScan m_scan;
  OpenClRadixSort m_sort;
  Kernels m_kernels[2];
  bool m_kernelsBuilt[2] = {false, false};
  PairFinderStats m_stats;

  std::vector<std::uint32_t> m_active, m_binned, m_huge;
  std::vector<std::uint8_t> m_isHuge;
  std::vector<float> m_extent;
  std::vector<std::uint64_t> m_packed;
  DeviceArray m_minX, m_minY, m_minZ, m_maxX, m_maxY, m_maxZ, m_group, m_mask, m_flags;
  DeviceArray m_grid, m_activeBuf, m_binnedBuf, m_hugeBuf, m_isHugeBuf, m_counts, m_cellKeys, m_keySlots,
      m_runHeads, m_runStart, m_runCell, m_runPairs, m_pairs, m_pairValues, m_counter, m_overflow;
  std::uint32_t m_lastPairs = 0;
};

OpenClPairFinder::Kernels& OpenClPairFinder::kernels(bool newton) {
  Kernels& k = m_kernels[newton ? 1 : 0];
  if (!m_kernelsBuilt[newton ? 1 : 0]) {
    cl::Program program = m_context.program("grid_find_pairs", kernels::grid_find_pairs,
                                            newton ? "-DGPUCOL_MAPPING_NEWTON" : "");
    k.countCells = cl::Kernel(program, "grid_count_cells");
    k.writeKeys = cl::Kernel(program, "grid_write_keys");
    k.markRuns = cl::Kernel(program, "grid_mark_runs");
    k.writeRuns = cl::Kernel(program, "grid_write_runs");
    k.countRunPairs = cl::Kernel(program, "grid_count_run_pairs");
    k.testCandidates = cl::Kernel(program, "grid_test_candidates");
    k.testHuge = cl::Kernel(program, "grid_test_huge");
    k.bruteTest = cl::Kernel(program, "brute_test_pairs");
    m_kernelsBuilt[newton ? 1 : 0] = true;
  }
  return k;
}

void OpenClPairFinder::chooseGrid(const ProxyArrays& p, const PairFinderOptions& options,
                                  GpucolGridParams& g) {
  // Stages 2-3, the same grid as the CPU finder's (broadphase/grid_choice.h). The grid only decides the
  // speed: whatever the grid, the pairs found are exactly the overlapping ones, because binning and the
  // dedupe rule use the same cell function on the device.
  const Grid grid = gpucol::chooseGrid(p, m_active, options, m_extent, m_binned, m_huge);
  m_stats.hugeProxies = std::uint32_t(m_huge.size());
  // Per active index: huge or not (m_huge is in m_active order, each slot once).
  m_isHuge.assign(m_active.size(), 0);
  for (std::size_t i = 0, h = 0; i < m_active.size() && h < m_huge.size(); ++i) {
    if (m_active[i] == m_huge[h]) {
      m_isHuge[i] = 1;
      ++h;
    }
  }
  g = GpucolGridParams{grid.origin[0], grid.origin[1], grid.origin[2], grid.invCell,
                       grid.dims[0],   grid.dims[1],   grid.dims[2],   0};
  if (m_binned.empty()) return;
  m_stats.cellSize = grid.cell;
  for (int a = 0; a < 3; ++a) m_stats.dims[a] = grid.dims[a];
}

void OpenClPairFinder::upload(const ProxyArrays& p) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  const std::size_t n = p.count;
  const std::pair<DeviceArray*, const float*> floats[] = {{&m_minX, p.minX}, {&m_minY, p.minY},
                                                          {&m_minZ, p.minZ}, {&m_maxX, p.maxX},
                                                          {&m_maxY, p.maxY}, {&m_maxZ, p.maxZ}};
  for (const auto& f : floats) {
    q.enqueueWriteBuffer(f.first->ensure(c, n * 4), CL_FALSE, 0, n * 4, f.second);
  }
  q.enqueueWriteBuffer(m_group.ensure(c, n * 4), CL_FALSE, 0, n * 4, p.group);
  q.enqueueWriteBuffer(m_mask.ensure(c, n * 4), CL_FALSE, 0, n * 4, p.mask);
  q.enqueueWriteBuffer(m_flags.ensure(c, n), CL_FALSE, 0, n, p.flags);
}

void OpenClPairFinder::setProxyArgs(cl::Kernel& kernel) {
  const DeviceArray* arrays[] = {&m_minX, &m_minY,  &m_minZ, &m_maxX, &m_maxY,
                                 &m_maxZ, &m_group, &m_mask, &m_flags};
  for (cl_uint i = 0; i < 9; ++i) {
    kernel.setArg(i, arrays[i]->buffer);
  }
}

void OpenClPairFinder::launch(cl::Kernel& kernel, std::uint64_t items) {
  if (items == 0) {
    return;
  }
  const std::size_t local = m_context.workGroupSize(kernel);
  const std::size_t global = std::size_t((items + local - 1) / local * local);
  m_context.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
}

void OpenClPairFinder::launchStrided(cl::Kernel& kernel, std::uint64_t items) {
  // Grid-stride kernels: enough items to fill the device several times, each looping over the rest, so
  // that candidate counts past the NDRange limits still run.
  if (items == 0) {
    return;
  }
  const std::size_t local = m_context.workGroupSize(kernel);
  const std::uint64_t units = m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
  const std::uint64_t cap = units * local * 64;
  const std::uint64_t wanted = std::min(items, cap);
  const std::size_t global = std::size_t((wanted + local - 1) / local * local);
  m_context.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(global), cl::NDRange(local));
}

void OpenClPairFinder::findPairs(const ProxyArrays& p, const PairFinderOptions& options,
                                 std::vector<std::uint64_t>& pairs) {
  m_stats = PairFinderStats{};
  pairs.clear();
  m_active.clear();
  for (std::uint32_t s = 0; s < p.count; ++s) {
    if (p.flags[s] & kProxyActive) {
      m_active.push_back(s);
    }
  }
  if (m_active.size() < 2) {
    return;
  }
  translateClErrors("OpenCL grid pair search", [&] {
    const cl::Context& c = m_context.context();
    cl::CommandQueue& q = m_context.queue();
    Kernels& k = kernels(options.mappingSqrt == MappingSqrt::Newton);
    upload(p);
    const std::uint32_t activeCount = std::uint32_t(m_active.size());
    q.enqueueWriteBuffer(m_activeBuf.ensure(c, activeCount * 4), CL_FALSE, 0, activeCount * 4,
                         m_active.data());
    const cl_uint slotBits = indexBits(p.count);
    const cl_uint zero = 0;
    m_counter.ensure(c, 4);
    m_overflow.ensure(c, 4);
    q.enqueueFillBuffer(m_overflow.buffer, zero, 0, 4);

    const bool useGrid = activeCount >= options.bruteForceBelow;
    GpucolGridParams grid{};
    std::uint32_t runCount = 0;
    std::uint32_t candidates = 0;
    if (useGrid) {
      m_stats.usedGrid = true;
      chooseGrid(p, options, grid);
      const std::uint32_t binnedCount = std::uint32_t(m_binned.size());
      if (binnedCount > 0) {
        q.enqueueWriteBuffer(m_grid.ensure(c, sizeof grid), CL_FALSE, 0, sizeof grid, &grid);
        q.enqueueWriteBuffer(m_binnedBuf.ensure(c, binnedCount * 4), CL_FALSE, 0, binnedCount * 4,
                             m_binned.data());
        // Stage 4: count cells per box, scan, fill (cell, slot) entries.
        setProxyArgs(k.countCells);
        k.countCells.setArg(9, m_grid.buffer);
        k.countCells.setArg(10, m_binnedBuf.buffer);
        k.countCells.setArg(11, binnedCount);
        k.countCells.setArg(12, m_counts.ensure(c, binnedCount * 4));
        k.countCells.setArg(13, m_overflow.buffer);
        launch(k.countCells, binnedCount);
        const std::uint32_t keyCount = m_scan.exclusiveScan(m_counts.buffer, binnedCount);
        m_stats.keys = keyCount;
        setProxyArgs(k.writeKeys);
        k.writeKeys.setArg(9, m_grid.buffer);
        k.writeKeys.setArg(10, m_binnedBuf.buffer);
        k.writeKeys.setArg(11, binnedCount);
        k.writeKeys.setArg(12, m_counts.buffer);
        k.writeKeys.setArg(13, m_cellKeys.ensure(c, std::size_t(keyCount) * 8));
        k.writeKeys.setArg(14, m_keySlots.ensure(c, std::size_t(keyCount) * 4));
        launch(k.writeKeys, keyCount == 0 ? 0 : binnedCount);
        // Stage 5: stable sort by cell; slots stay ascending inside a cell.
        const std::uint64_t cells = std::uint64_t(grid.dimX) * grid.dimY * grid.dimZ;
        m_sort.sort(m_cellKeys.buffer, m_keySlots.buffer, keyCount, indexBits(cells));
        // Stage 6: runs of equal cells, m(m-1)/2 candidates each, scanned.
        k.markRuns.setArg(0, m_cellKeys.buffer);
        k.markRuns.setArg(1, keyCount);
        k.markRuns.setArg(2, m_runHeads.ensure(c, std::size_t(keyCount) * 4));
        launch(k.markRuns, keyCount);
        runCount = m_scan.exclusiveScan(m_runHeads.buffer, keyCount);
        k.writeRuns.setArg(0, m_cellKeys.buffer);
        k.writeRuns.setArg(1, keyCount);
        k.writeRuns.setArg(2, m_runHeads.buffer);
        k.writeRuns.setArg(3, runCount);
        k.writeRuns.setArg(4, m_runStart.ensure(c, (std::size_t(runCount) + 1) * 4));
        k.writeRuns.setArg(5, m_runCell.ensure(c, std::size_t(runCount) * 4));
        launch(k.writeRuns, keyCount);
        k.countRunPairs.setArg(0, m_runStart.buffer);
        k.countRunPairs.setArg(1, runCount);
        k.countRunPairs.setArg(2, m_runPairs.ensure(c, std::size_t(runCount) * 4));
        k.countRunPairs.setArg(3, m_overflow.buffer);
        launch(k.countRunPairs, runCount);
        candidates = m_scan.exclusiveScan(m_runPairs.buffer, runCount);
        cl_uint overflow = 0;
        q.enqueueReadBuffer(m_overflow.buffer, CL_TRUE, 0, 4, &overflow);
        if (overflow != 0) {
          throw std::overflow_error(
              "gpucol OpenCL pair finder: a box or a cell exceeds 2^32 - 1 entries or candidates");
        }
        m_stats.candidates = candidates;
      }
      m_stats.candidates += std::uint64_t(m_huge.size()) * activeCount;
      if (!m_huge.empty()) {
        const std::uint32_t hugeCount = std::uint32_t(m_huge.size());
        q.enqueueWriteBuffer(m_hugeBuf.ensure(c, hugeCount * 4), CL_FALSE, 0, hugeCount * 4, m_huge.data());
        q.enqueueWriteBuffer(m_isHugeBuf.ensure(c, activeCount), CL_FALSE, 0, activeCount, m_isHuge.data());
      }
    } else {
      m_stats.candidates = gpucol_pair_count(activeCount);
    }

    // Stages 7–10: test every candidate and append the survivors; grow and run again when they overflow
    // the output (its size comes from the last search, so a steady scene runs once).
    std::uint32_t capacity = std::max<std::uint32_t>(1024, m_lastPairs + m_lastPairs / 4);
    for (;;) {
      q.enqueueFillBuffer(m_counter.buffer, zero, 0, 4);
      const cl::Buffer& out = m_pairs.ensure(c, std::size_t(capacity) * 8);
      if (useGrid) {
        if (candidates > 0) {
          // A CPU device steps through chunks of candidates (see grid_test_candidates); a GPU takes one each.
          const std::size_t local = m_context.workGroupSize(k.testCandidates);
          const std::uint64_t units = m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
          const std::uint64_t targetItems = units * local * (m_context.isGpu() ? 64 : 1);
          const std::uint64_t minChunk = m_context.isGpu() ? 1 : 16;
          const std::uint64_t chunkLength =
              m_tuning.candidatesPerItem != 0
                  ? m_tuning.candidatesPerItem
                  : std::max(minChunk, (candidates + targetItems - 1) / targetItems);
          setProxyArgs(k.testCandidates);
          k.testCandidates.setArg(9, m_grid.buffer);
          k.testCandidates.setArg(10, m_runStart.buffer);
          k.testCandidates.setArg(11, m_runCell.buffer);
          k.testCandidates.setArg(12, m_runPairs.buffer);
          k.testCandidates.setArg(13, runCount);
          k.testCandidates.setArg(14, candidates);
          k.testCandidates.setArg(15, cl_uint(chunkLength));
          k.testCandidates.setArg(16, m_keySlots.buffer);
          k.testCandidates.setArg(17, slotBits);
          k.testCandidates.setArg(18, out);
          k.testCandidates.setArg(19, capacity);
          k.testCandidates.setArg(20, m_counter.buffer);
          launch(k.testCandidates, (candidates + chunkLength - 1) / chunkLength);
        }
        if (!m_huge.empty()) {
          setProxyArgs(k.testHuge);
          k.testHuge.setArg(9, m_hugeBuf.buffer);
          k.testHuge.setArg(10, std::uint32_t(m_huge.size()));
          k.testHuge.setArg(11, m_activeBuf.buffer);
          k.testHuge.setArg(12, activeCount);
          k.testHuge.setArg(13, m_isHugeBuf.buffer);
          k.testHuge.setArg(14, slotBits);
          k.testHuge.setArg(15, out);
          k.testHuge.setArg(16, capacity);
          k.testHuge.setArg(17, m_counter.buffer);
          launchStrided(k.testHuge, std::uint64_t(m_huge.size()) * activeCount);
        }
      } else {
        setProxyArgs(k.bruteTest);
        k.bruteTest.setArg(9, m_activeBuf.buffer);
        k.bruteTest.setArg(10, activeCount);
        k.bruteTest.setArg(11, cl_ulong(gpucol_pair_count(activeCount)));
        k.bruteTest.setArg(12, slotBits);
        k.bruteTest.setArg(13, out);
        k.bruteTest.setArg(14, capacity);
        k.bruteTest.setArg(15, m_counter.buffer);
        launchStrided(k.bruteTest, gpucol_pair_count(activeCount));
      }
      cl_uint found = 0;
      q.enqueueReadBuffer(m_counter.buffer, CL_TRUE, 0, 4, &found);
      if (found == 0xffffffffu) {
        throw std::overflow_error(
            "gpucol OpenCL pair finder: 2^32 - 1 or more overlapping pairs in one step");
      }
      if (found <= capacity) {
        m_lastPairs = found;
        break;
      }
      capacity = found;
    }
    // Stage 10: one order whatever the device: sort the compressed keys, then widen them.
    const std::uint32_t found = m_lastPairs;
    if (found > 1) {
      m_sort.sort(m_pairs.buffer, m_pairValues.ensure(c, std::size_t(found) * 4), found, 2 * slotBits);
    }
    m_packed.resize(found);
    if (found > 0) {
      q.enqueueReadBuffer(m_pairs.buffer, CL_TRUE, 0, std::size_t(found) * 8, m_packed.data());
    }
    const std::uint64_t lowMask = (std::uint64_t(1) << slotBits) - 1;
    pairs.resize(found);
    for (std::uint32_t i = 0; i < found; ++i) {
      pairs[i] = ((m_packed[i] >> slotBits) << 32) | (m_packed[i] & lowMask);
    }
  });
  std::size_t bytes = 0;
  for (const DeviceArray* a :
       {&m_minX,   &m_minY,       &m_minZ,     &m_maxX,      &m_maxY,      &m_maxZ,    &m_group,
        &m_mask,   &m_flags,      &m_grid,     &m_activeBuf, &m_binnedBuf, &m_hugeBuf, &m_isHugeBuf,
        &m_counts, &m_cellKeys,   &m_keySlots, &m_runHeads,  &m_runStart,  &m_runCell, &m_runPairs,
        &m_pairs,  &m_pairValues, &m_counter,  &m_overflow}) {
    bytes += a->bytes;
  }
  m_stats.scratchBytes = bytes;
}

}  // namespace

std::unique_ptr<PairFinder> makePairFinder(const Config& config, const OpenClPairFinderTuning& tuning) {
  OpenClContext* context = OpenClContext::tryGet(config.openclDevice);
  if (context == nullptr) {
    return nullptr;
  }
  return std::make_unique<OpenClPairFinder>(*context, tuning);
}

void registerOpenClPairFinder() {
  gpucol::registerOpenClPairFinder([](const Config& config) { return makePairFinder(config); });
}

namespace {
// Installs the factory when this object file is linked in (see registerOpenClPairFinder()).
const bool kRegistered = (registerOpenClPairFinder(), true);
}  // namespace

}  // namespace gpucol::opencl

/// Anchor with a plain C name: libgpucol's consumers link with --undefined=gpucol_link_opencl_pair_finder
/// (plugin/CMakeLists.txt), which pulls this object file, and so its registration, out of a static library.
extern "C" void gpucol_link_opencl_pair_finder() {
  gpucol::opencl::registerOpenClPairFinder();
}
