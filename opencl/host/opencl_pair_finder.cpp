// OpenCL implementation of the grid pair finder; stage numbers are those of grid_pair_finder.h.
#include "opencl/host/opencl_pair_finder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "broadphase/grid_choice.h"
#include "broadphase/packed_pairs.h"
#include "shared_math/pair_mapping.h"
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
static_assert(sizeof(GpucolProxyBox) == 32 && offsetof(GpucolProxyBox, group) == 12 &&
                  offsetof(GpucolProxyBox, maxX) == 16 && offsetof(GpucolProxyBox, mask) == 28,
              "GpucolProxyBox layout differs from the kernels'");
static_assert(sizeof(GpucolProxyUpdate) == 40 && offsetof(GpucolProxyUpdate, slot) == 32 &&
                  offsetof(GpucolProxyUpdate, flags) == 36,
              "GpucolProxyUpdate layout differs from the kernels'");
static_assert(GPUCOL_PROXY_ACTIVE == kProxyActive && GPUCOL_PROXY_STATIC == kProxyStatic,
              "proxy flag bits differ between grid_params.h and grid_pair_finder.h");

namespace {

/// Stage 11: the kept grid is reused while at most this fraction of the active proxies changed since it was
/// built (measured on PoCL: measurement history, "Broad phase"); beyond it a full search is about as fast.
constexpr double kIncrementalFraction = 0.125;

/// The kernels' first arguments (PROXY_PARAMS in grid_find_pairs.cl): the boxes and the flags.
constexpr cl_uint kProxyArgs = 2;

/// Stages 4-6 of one list of binned proxies on the device: their slots sorted by cell (keySlots; the cells
/// themselves in cellKeys on a sparse grid only), the runs of equal cells, and the runs' scanned candidate
/// counts. A full search fills one and keeps it for stage 11; the proxies moved since then get their own.
struct Bins {
  DeviceArray slots, counts, cellKeys, keySlots, runHeads, runStart, runCell, runPairs;
  std::uint32_t count = 0;       ///< Binned proxies.
  std::uint32_t keys = 0;        ///< (cell, slot) entries.
  std::uint32_t runs = 0;        ///< Runs of equal cells (runStart has runs + 1 entries).
  std::uint32_t candidates = 0;  ///< Sum of m(m-1)/2 over the runs.
  /// On a dense grid whose cells are mostly filled, every cell is a run, empty ones too: runStart is the
  /// counting sort's first entry per cell and runCell is left empty (runsAreCells).
  bool runsAreCells = false;
  /// Device bytes held.
  std::size_t bytes() const {
    return slots.bytes + counts.bytes + cellKeys.bytes + keySlots.bytes + runHeads.bytes + runStart.bytes +
           runCell.bytes + runPairs.bytes;
  }
};

class OpenClPairFinder final : public PairFinder {
 public:
  OpenClPairFinder(OpenClContext& context, const OpenClPairFinderTuning& tuning)
      : m_context(context),
        m_tuning(tuning),
        m_releases(
            tuning.release == OpenClPairFinderTuning::BufferRelease::Always ||
            (tuning.release == OpenClPairFinderTuning::BufferRelease::Auto && context.sharesHostMemory())),
        m_baseAlignment(context.device().getInfo<CL_DEVICE_MEM_BASE_ADDR_ALIGN>() / 8),
        m_scan(context),
        m_sort(context) {}
  /// Waits for the queue: a write not waited for reads the finder's host lists until the queue runs it (a
  /// step cut short by an OpenCL error may leave some queued). clFinish, which throws nothing; its error, on
  /// a queue that already failed, changes nothing here.
  ~OpenClPairFinder() override { clFinish(m_context.queue()()); }
  OpenClPairFinder(const OpenClPairFinder&) = delete;
  OpenClPairFinder& operator=(const OpenClPairFinder&) = delete;

  void findPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                 std::vector<std::uint64_t>& pairs) override;
  const PairFinderStats& stats() const override { return m_stats; }
  std::string name() const override { return "opencl"; }
  /// The boxes go to the device through one pass over them (upload), from the caller's records as well as
  /// from six arrays, so the caller need not copy them first.
  bool readsBoxRecords() const override { return true; }
  bool runsOnGpu() const override { return m_context.isGpu(); }

 private:
  struct Kernels {
    cl::Kernel countCells, writeKeys, countOrPlaceEntries, countFilledCells, markFilledCells, writeFilledCells,
        markRuns, writeRuns, countRunPairs, testCandidates, testHuge, bruteTest, updateProxies, testMoved;
  };
  Kernels& kernels(bool newton, const ProxyArrays& p);
  bool readsRecordsInPlace(const ProxyArrays& p) const;
  void bindRecords(const ProxyArrays& p);
  void chooseGrid(const ProxyArrays& p, const PairFinderOptions& options, GpucolGridParams& g);
  static GpucolProxyBox deviceBox(const ProxyArrays& p, std::uint32_t s);
  static double millisecondsSince(std::chrono::steady_clock::time_point start);
  void upload(const ProxyArrays& p);
  bool keepGrid(const ProxyArrays& p, const PairFinderOptions& options);
  void sendChanges(const ProxyArrays& p, Kernels& k);
  void writeSlots(const std::vector<std::uint32_t>& slots, Bins& b);
  void bin(Kernels& k, const GpucolGridParams& grid, Bins& b, bool slotsAfterBinning);
  void testBins(Kernels& k, Bins& b, const cl::Buffer& out, std::uint32_t capacity, cl_uint slotBits);
  void testHuge(Kernels& k, const DeviceArray& huge, std::uint32_t hugeCount, std::uint32_t slotCount,
                const cl::Buffer& out, std::uint32_t capacity, cl_uint slotBits);
  bool fewMoved(const ProxyArrays& p) const;
  void fullSearch(const ProxyArrays& p, const PairFinderOptions& options, Kernels& k,
                  std::vector<std::uint64_t>& pairs);
  void incremental(const ProxyArrays& p, const PairFinderOptions& options, Kernels& k,
                   std::vector<std::uint64_t>& pairs);
  bool pairsFit(std::uint32_t& capacity);
  std::size_t heldBytes() const;
  void notePeak();
  void releaseEarly(std::initializer_list<DeviceArray*> arrays, bool sortScratch);
  void releaseUnkept();
  void readPairs(cl_uint slotBits, std::vector<std::uint64_t>& pairs);
  void setProxyArgs(cl::Kernel& kernel);
  void launch(cl::Kernel& kernel, std::uint64_t items);
  void launchStrided(cl::Kernel& kernel, std::uint64_t items);

  OpenClContext& m_context;
  OpenClPairFinderTuning m_tuning;
  bool m_releases;                 // OpenClPairFinderTuning::release, resolved for the device
  std::uintptr_t m_baseAlignment;  // bytes: where a host address the device takes as its own must start
  OpenClScan m_scan;
  OpenClRadixSort m_sort;
  std::map<std::string, Kernels> m_kernels;  // by build options (square root, where the boxes are read)
  PairFinderStats m_stats;

  std::vector<std::uint32_t> m_active, m_binned, m_huge;
  std::vector<float> m_extent;
  DeviceArray m_boxes, m_flags;  // every slot's GpucolProxyBox and flags
  bool m_inPlace = false;        // this search reads the boxes in the caller's records (readsRecordsInPlace)
  cl::Buffer m_records;          // the records as the device's buffer, for this search only
  DeviceArray m_grid, m_activeBuf, m_hugeBuf, m_pairs, m_counter, m_overflow;
  std::uint32_t m_activeCount = 0;  // active slots of this search (m_active, freed once uploaded)
  const std::vector<std::uint64_t>* m_output = nullptr;  // findPairs' `pairs`, counted in the peak
  Bins m_bins;                    // the last full grid search's entries and runs (kept for stage 11)
  std::uint32_t m_lastPairs = 0;  // pairs the device found in the last search (sizes the next output)
  std::chrono::steady_clock::time_point m_searchStart;  // the stage times' origin (PairFinderStats::chooseMs)

  // Stage 11: what the device keeps of the last full grid search, and what changed since.
  bool m_kept = false;                     // m_bins, m_grid, m_hugeBuf and m_restingBuf describe that search
  bool m_keptInPlace = false;              // it read the boxes in place (m_boxes holds none)
  PairFinderOptions m_keptOptions;         // the options it ran with
  GpucolGridParams m_keptGrid{};           // its grid
  float m_keptCell = 0;                    // its cell edge (stage 3's test for moved proxies)
  std::uint32_t m_keptHugeCount = 0;       // its huge proxies, in m_hugeBuf
  std::uint32_t m_syncedCount = 0;         // slots whose boxes, filters and flags the device arrays hold
  std::vector<std::uint8_t> m_resting;     // per slot: active in that search and unchanged since
  bool m_callerKeepsPairs = false;         // the pairs of that search are the caller's ProxyArrays::lastPairs
  PackedPairs m_keptPairs;                 // else our copy of them (plain)
  std::vector<std::uint32_t> m_moved;      // active slots changed since that search, ascending
  std::vector<std::uint32_t> m_movedBinned;  // of those, the binned ones
  std::vector<std::uint32_t> m_movedHuge;    // and the huge ones
  std::vector<GpucolProxyUpdate> m_updates;  // slots to write into the device's arrays this search
  std::vector<std::uint64_t> m_found;        // pairs with a moved proxy, found on the device
  DeviceArray m_restingBuf, m_updatesBuf, m_movedHugeBuf;
  Bins m_movedBins;  // the binned moved proxies' own entries on the kept grid
};

OpenClPairFinder::Kernels& OpenClPairFinder::kernels(bool newton, const ProxyArrays& p) {
  std::string options = newton ? "-DGPUCOL_MAPPING_NEWTON" : "";
  if (m_inPlace) {
    const BoxRecords& r = p.records;
    options += " -DGPUCOL_RECORD_STRIDE=" + std::to_string(r.stride) +
               " -DGPUCOL_RECORD_MIN=" + std::to_string(r.minOffset) +
               " -DGPUCOL_RECORD_MAX=" + std::to_string(r.maxOffset) +
               " -DGPUCOL_RECORD_GROUP=" + std::to_string(r.groupOffset) +
               " -DGPUCOL_RECORD_MASK=" + std::to_string(r.maskOffset);
  }
  const auto [found, isNew] = m_kernels.try_emplace(options);
  Kernels& k = found->second;
  if (isNew) {
    cl::Program program = m_context.program("grid_find_pairs", kernels::grid_find_pairs, options);
    k.countCells = cl::Kernel(program, "grid_count_cells");
    k.writeKeys = cl::Kernel(program, "grid_write_keys");
    k.countOrPlaceEntries = cl::Kernel(program, "grid_count_or_place_entries");
    k.countFilledCells = cl::Kernel(program, "grid_count_filled_cells");
    k.markFilledCells = cl::Kernel(program, "grid_mark_filled_cells");
    k.writeFilledCells = cl::Kernel(program, "grid_write_filled_cells");
    k.markRuns = cl::Kernel(program, "grid_mark_runs");
    k.writeRuns = cl::Kernel(program, "grid_write_runs");
    k.countRunPairs = cl::Kernel(program, "grid_count_run_pairs");
    k.testCandidates = cl::Kernel(program, "grid_test_candidates");
    k.testHuge = cl::Kernel(program, "grid_test_huge");
    k.bruteTest = cl::Kernel(program, "brute_test_pairs");
    k.updateProxies = cl::Kernel(program, "grid_update_proxies");
    k.testMoved = cl::Kernel(program, "grid_test_moved");
  }
  return k;
}

bool OpenClPairFinder::readsRecordsInPlace(const ProxyArrays& p) const {
  const BoxRecords& r = p.records;
  if (!m_tuning.recordsInPlace || !m_context.sharesHostMemory() || p.minX != nullptr || r.blocks == nullptr ||
      p.count == 0 || r.groupOffset == kNoRecordField || r.maskOffset == kNoRecordField) {
    return false;
  }
  // Slot s's record at blocks[0] + s * stride for every slot; fields the kernels load as 4-byte words; and an
  // address the device uses as it is (elsewhere a driver may copy the memory, which is what this avoids).
  return std::uint64_t(p.count) * r.stride <= r.contiguousBytes &&
         (r.stride | r.minOffset | r.maxOffset | r.groupOffset | r.maskOffset) % 4 == 0 &&
         reinterpret_cast<std::uintptr_t>(r.blocks[0]) % std::max<std::uintptr_t>(m_baseAlignment, 1) == 0;
}

void OpenClPairFinder::bindRecords(const ProxyArrays& p) {
  // A buffer over the host's records, made afresh for every search: made after the host last wrote them, it
  // holds what they hold now on any implementation (one that caches a copy takes it at creation), and none
  // is held between searches over memory the caller may free.
  const std::size_t bytes = std::size_t(p.count) * p.records.stride;
  m_records = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes,
                         const_cast<unsigned char*>(p.records.blocks[0]));
  m_stats.recordsReadInPlace = true;
}

void OpenClPairFinder::chooseGrid(const ProxyArrays& p, const PairFinderOptions& options,
                                  GpucolGridParams& g) {
  // Stages 2-3, the same grid as the CPU finder's (broadphase/grid_choice.h). The grid only decides the
  // speed: whatever the grid, the pairs found are exactly the overlapping ones, because binning and the
  // dedupe rule use the same cell function on the device.
  const Grid grid = gpucol::chooseGrid(p, m_active, options, m_extent, m_binned, m_huge);
  m_stats.hugeProxies = std::uint32_t(m_huge.size());  // ascending, as grid_test_huge wants them
  g = GpucolGridParams{grid.origin[0], grid.origin[1], grid.origin[2], grid.invCell,
                       grid.dims[0],   grid.dims[1],   grid.dims[2],   0};
  m_keptCell = grid.cell;
  if (m_binned.empty()) return;
  m_stats.cellSize = grid.cell;
  for (int a = 0; a < 3; ++a) m_stats.dims[a] = grid.dims[a];
}

double OpenClPairFinder::millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

GpucolProxyBox OpenClPairFinder::deviceBox(const ProxyArrays& p, std::uint32_t s) {
  const BoxCorners b = p.box(s);
  return GpucolProxyBox{b.lo[0], b.lo[1], b.lo[2], p.group[s], b.hi[0], b.hi[1], b.hi[2], p.mask[s]};
}

void OpenClPairFinder::upload(const ProxyArrays& p) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  const std::size_t n = p.count;
  q.enqueueWriteBuffer(m_flags.ensureFitted(c, n), CL_FALSE, 0, n, p.flags);
  m_syncedCount = p.count;
  if (m_inPlace) {
    m_boxes.release();  // a copy from a search that could not read them in place
    bindRecords(p);
    return;
  }
  // Written through a mapping, not from a host copy of every box: on a CPU device the mapping is the
  // buffer itself, so the boxes are gathered once and held once.
  const std::size_t bytes = n * sizeof(GpucolProxyBox);
  const cl::Buffer& boxes = m_boxes.ensureFitted(c, bytes);
  auto* out = static_cast<GpucolProxyBox*>(
      q.enqueueMapBuffer(boxes, CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, bytes));
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, p.count, 4096),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t s = r.begin(); s < r.end(); ++s) out[s] = deviceBox(p, s);
                    });
  q.enqueueUnmapMemObject(boxes, out);
}

void OpenClPairFinder::setProxyArgs(cl::Kernel& kernel) {
  kernel.setArg(0, m_inPlace ? m_records : m_boxes.buffer);
  kernel.setArg(1, m_flags.buffer);
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

/// The binned proxies' slots into b.slots, not waited for (the caller keeps `slots` until the queue is done).
void OpenClPairFinder::writeSlots(const std::vector<std::uint32_t>& slots, Bins& b) {
  b.count = std::uint32_t(slots.size());
  if (b.count > 0) {
    m_context.queue().enqueueWriteBuffer(b.slots.ensureFitted(m_context.context(), b.count * 4), CL_FALSE, 0,
                                         b.count * 4, slots.data());
  }
}

/// Stages 4-6 of the b.count proxies in b.slots (writeSlots); `slotsAfterBinning`: b.slots stays (stage 11's
/// moved proxies are tested from it), else it goes once the entries hold the slots.
void OpenClPairFinder::bin(Kernels& k, const GpucolGridParams& grid, Bins& b, bool slotsAfterBinning) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  b.keys = b.runs = b.candidates = 0;
  b.runsAreCells = false;
  if (b.count == 0) {
    return;
  }
  const cl_uint zero = 0;
  q.enqueueFillBuffer(m_overflow.ensure(c, 4), zero, 0, 4);
  const std::uint64_t cells = std::uint64_t(grid.dimX) * grid.dimY * grid.dimZ;
  if (sortsByCounting(cells, b.count)) {
    // Stages 4-6 on a dense grid (sortsByCounting), as the CPU finder: a counting sort over the cells
    // (each cell's count, scanned into its first entry, then each entry placed), and the runs are the filled
    // cells, or every cell (runsAreCells). No (cell, slot) keys are written.
    const cl_uint cellCount = cl_uint(cells);
    q.enqueueFillBuffer(b.counts.ensureFitted(c, (cells + 1) * 4), zero, 0, (cells + 1) * 4);
    setProxyArgs(k.countOrPlaceEntries);
    // Counting writes no entry: any buffer stands for the entries' argument.
    setKernelArgs(k.countOrPlaceEntries, kProxyArgs, m_grid.buffer, b.slots.buffer, b.count, b.counts.buffer,
                  cl_uint(0), b.slots.buffer);
    launch(k.countOrPlaceEntries, b.count);
    // The filled cells are counted before the scan, which waits for the queue anyway: reading their count
    // after it costs no wait of its own.
    constexpr cl_uint kCellsPerItem = 256;
    q.enqueueFillBuffer(m_counter.ensure(c, 4), zero, 0, 4);
    setKernelArgs(k.countFilledCells, 0, b.counts.buffer, cellCount, kCellsPerItem, m_counter.buffer);
    launch(k.countFilledCells, (cells + kCellsPerItem - 1) / kCellsPerItem);
    b.keys = m_scan.exclusiveScan(b.counts.buffer, cells + 1);
    cl_uint filled = 0;
    q.enqueueReadBuffer(m_counter.buffer, CL_TRUE, 0, 4, &filled);
    setKernelArgs(k.countOrPlaceEntries, kProxyArgs + 4, cl_uint(1),
                  b.keySlots.ensureFitted(c, std::size_t(b.keys) * 4));
    launch(k.countOrPlaceEntries, b.keys == 0 ? 0 : b.count);
    if (!slotsAfterBinning) releaseEarly({&b.slots}, false);  // the entries hold them now
    if (m_tuning.runsAreCells && runsAreCells(cells, filled)) {
      // Every cell a run: the placed counts are the runs' first entries, and a run's cell is its number.
      // Swapped rather than moved: where buffers are kept (a discrete GPU), the next counts reuse the old
      // runStart; where they are released, that is already empty.
      std::swap(b.runStart, b.counts);
      b.runCell.release();  // a null argument: the kernels take the run's number as its cell
      b.runs = cellCount;
      b.runsAreCells = true;
    } else {
      setKernelArgs(k.markFilledCells, 0, b.counts.buffer, cellCount, b.runHeads.ensureFitted(c, cells * 4));
      launch(k.markFilledCells, cells);
      b.runs = m_scan.exclusiveScan(b.runHeads.buffer, cells);
      setKernelArgs(k.writeFilledCells, 0, b.counts.buffer, cellCount, b.runHeads.buffer, b.runs,
                    b.runStart.ensureFitted(c, (std::size_t(b.runs) + 1) * 4),
                    b.runCell.ensureFitted(c, std::size_t(b.runs) * 4));
      launch(k.writeFilledCells, cells);
      releaseEarly({&b.counts, &b.runHeads}, false);  // what only led to the runs
    }
  } else {
    // Stage 4: count cells per box, scan, fill (cell, slot) entries.
    setProxyArgs(k.countCells);
    setKernelArgs(k.countCells, kProxyArgs, m_grid.buffer, b.slots.buffer, b.count,
                  b.counts.ensureFitted(c, b.count * 4), m_overflow.buffer);
    launch(k.countCells, b.count);
    b.keys = m_scan.exclusiveScan(b.counts.buffer, b.count);
    setProxyArgs(k.writeKeys);
    setKernelArgs(k.writeKeys, kProxyArgs, m_grid.buffer, b.slots.buffer, b.count, b.counts.buffer,
                  b.cellKeys.ensureFitted(c, std::size_t(b.keys) * 8),
                  b.keySlots.ensureFitted(c, std::size_t(b.keys) * 4));
    launch(k.writeKeys, b.keys == 0 ? 0 : b.count);
    releaseEarly({&b.counts}, false);  // the entries' offsets
    if (!slotsAfterBinning) releaseEarly({&b.slots}, false);
    // Stage 5 on a sparse or large grid: radix sort by cell.
    m_sort.sort(b.cellKeys.buffer, b.keySlots.buffer, b.keys, indexBits(cells));
    releaseEarly({}, true);  // the pair sort's is 8 bytes per pair, usually far fewer than the entries
    // Stage 6: runs of equal cells.
    setKernelArgs(k.markRuns, 0, b.cellKeys.buffer, b.keys,
                  b.runHeads.ensureFitted(c, std::size_t(b.keys) * 4));
    launch(k.markRuns, b.keys);
    b.runs = m_scan.exclusiveScan(b.runHeads.buffer, b.keys);
    setKernelArgs(k.writeRuns, 0, b.cellKeys.buffer, b.keys, b.runHeads.buffer, b.runs,
                  b.runStart.ensureFitted(c, (std::size_t(b.runs) + 1) * 4),
                  b.runCell.ensureFitted(c, std::size_t(b.runs) * 4));
    launch(k.writeRuns, b.keys);
    releaseEarly({&b.cellKeys, &b.runHeads}, false);  // what only led to the runs (the counts went above)
  }
  // Stage 6: m(m-1)/2 candidates per run, scanned.
  setKernelArgs(k.countRunPairs, 0, b.runStart.buffer, b.runs,
                b.runPairs.ensureFitted(c, std::size_t(b.runs) * 4), m_overflow.buffer);
  launch(k.countRunPairs, b.runs);
  b.candidates = m_scan.exclusiveScan(b.runPairs.buffer, b.runs);
  cl_uint overflow = 0;
  q.enqueueReadBuffer(m_overflow.buffer, CL_TRUE, 0, 4, &overflow);
  if (overflow != 0) {
    throw std::overflow_error(
        "gpucol OpenCL pair finder: a box or a cell exceeds 2^32 - 1 entries or candidates");
  }
}

void OpenClPairFinder::releaseEarly(std::initializer_list<DeviceArray*> arrays, bool sortScratch) {
  // The search's peak is in binning: its intermediates go as soon as they are used, before the candidates
  // are tested. The device frees each buffer once the commands that use it are done.
  if (!m_releases) return;
  notePeak();
  for (DeviceArray* a : arrays) a->release();
  if (sortScratch) m_sort.releaseScratch();
}

void OpenClPairFinder::notePeak() {
  // With the output as it stands (PairFinderStats::peakIncludesOutput): the finder's memory is largest while
  // it bins, before there is any output.
  const std::size_t output = m_output != nullptr ? m_output->capacity() * sizeof(std::uint64_t) : 0;
  m_stats.peakScratchBytes = std::max(m_stats.peakScratchBytes, heldBytes() + output);
}

void OpenClPairFinder::testBins(Kernels& k, Bins& b, const cl::Buffer& out, std::uint32_t capacity,
                                cl_uint slotBits) {
  if (b.candidates == 0) {
    return;
  }
  // A CPU device steps through chunks of candidates (see grid_test_candidates); a GPU takes one each.
  const std::size_t local = m_context.workGroupSize(k.testCandidates);
  const std::uint64_t units = m_context.device().getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
  const std::uint64_t targetItems = units * local * (m_context.gpuShaped() ? 64 : 1);
  const std::uint64_t minChunk = m_context.gpuShaped() ? 1 : 16;
  const std::uint64_t chunkLength = m_tuning.candidatesPerItem != 0
                                        ? m_tuning.candidatesPerItem
                                        : std::max(minChunk, (b.candidates + targetItems - 1) / targetItems);
  setProxyArgs(k.testCandidates);
  setKernelArgs(k.testCandidates, kProxyArgs, m_grid.buffer, b.runStart.buffer, b.runCell.buffer,
                b.runPairs.buffer, b.runs, b.candidates, cl_uint(chunkLength), b.keySlots.buffer, slotBits,
                out, capacity, m_counter.buffer);
  launch(k.testCandidates, (b.candidates + chunkLength - 1) / chunkLength);
}

void OpenClPairFinder::testHuge(Kernels& k, const DeviceArray& huge, std::uint32_t hugeCount,
                                std::uint32_t slotCount, const cl::Buffer& out, std::uint32_t capacity,
                                cl_uint slotBits) {
  if (hugeCount == 0) {
    return;
  }
  setProxyArgs(k.testHuge);
  setKernelArgs(k.testHuge, kProxyArgs, huge.buffer, hugeCount, slotCount, slotBits, out, capacity,
                m_counter.buffer);
  launchStrided(k.testHuge, slotCount);
}

/// Reads the pair counter after a pass: true when the pairs found fit `capacity` (m_lastPairs set), else
/// `capacity` becomes the count and the caller runs the pass again (nothing is truncated).
bool OpenClPairFinder::pairsFit(std::uint32_t& capacity) {
  cl_uint found = 0;
  m_context.queue().enqueueReadBuffer(m_counter.buffer, CL_TRUE, 0, 4, &found);
  if (found == 0xffffffffu) {
    throw std::overflow_error("gpucol OpenCL pair finder: 2^32 - 1 or more overlapping pairs in one step");
  }
  if (found <= capacity) {
    m_lastPairs = found;
    return true;
  }
  capacity = found;
  return false;
}

void OpenClPairFinder::readPairs(cl_uint slotBits, std::vector<std::uint64_t>& pairs) {
  // Stage 10: one order whatever the device: sort the compressed keys, then widen them.
  cl::CommandQueue& q = m_context.queue();
  const std::uint32_t found = m_lastPairs;
  if (found > 1) {
    m_sort.sortKeys(m_pairs.buffer, found, 2 * slotBits);
  }
  // Read into the output itself and widened there: no host copy of the compressed keys (8 bytes a pair).
  pairs.resize(found);
  if (found > 0) {
    q.enqueueReadBuffer(m_pairs.buffer, CL_TRUE, 0, std::size_t(found) * 8, pairs.data());
  }
  const std::uint64_t lowMask = (std::uint64_t(1) << slotBits) - 1;
  for (std::uint64_t& key : pairs) {
    key = ((key >> slotBits) << 32) | (key & lowMask);
  }
  notePeak();  // the pairs on the device, the sort's scratch and the list read
}

void OpenClPairFinder::findPairs(const ProxyArrays& p, const PairFinderOptions& options,
                                 std::vector<std::uint64_t>& pairs) {
  if (p.count > 0 && !(p.minX && p.minY && p.minZ && p.maxX && p.maxY && p.maxZ) && !p.records.blocks) {
    throw std::invalid_argument(
        "gpucol OpenCL pair finder: ProxyArrays with neither the six axis arrays nor records");
  }
  m_searchStart = std::chrono::steady_clock::now();
  m_stats = PairFinderStats{};
  m_stats.peakIncludesOutput = true;
  m_output = &pairs;
  pairs.clear();
  m_active.clear();
  m_active.reserve(p.count);  // at its full size at once: released after every search
  for (std::uint32_t s = 0; s < p.count; ++s) {
    if (p.flags[s] & kProxyActive) {
      m_active.push_back(s);
    }
  }
  m_activeCount = std::uint32_t(m_active.size());
  m_inPlace = readsRecordsInPlace(p);
  // Whatever happens below, the device's arrays and kept grid are only trusted again once this search has
  // finished (an OpenCL error or an early return leaves them out of step with `p`).
  const bool canKeep = keepGrid(p, options);
  m_kept = false;
  translateClErrors("OpenCL grid pair search", [&] {
    if (detail::takeInjectedOpenClFailure()) {
      throw cl::Error(CL_OUT_OF_RESOURCES, "clEnqueueNDRangeKernel (a failure injected by a test)");
    }
    if (m_activeCount >= 2) {
      Kernels& k = kernels(options.mappingSqrt == MappingSqrt::Newton, p);
      m_counter.ensure(m_context.context(), 4);
      m_overflow.ensure(m_context.context(), 4);
      if (canKeep) {
        incremental(p, options, k, pairs);
        m_kept = true;
      } else {
        fullSearch(p, options, k, pairs);
      }
      // The next search carries pairs over from the caller's copy of these when it keeps one (not held
      // twice), else from ours.
      m_callerKeepsPairs = m_kept && p.lastPairs != nullptr;
      if (m_kept && !m_callerKeepsPairs) m_keptPairs.assign(pairs, true);
      m_keptInPlace = m_inPlace;
      m_stats.rebinnedProxies = m_activeCount - m_stats.restingProxies;
    }
    notePeak();
    releaseUnkept();
  });
  m_stats.scratchBytes = heldBytes();
  m_output = nullptr;
}

std::size_t OpenClPairFinder::heldBytes() const {
  // The scan's and the sort's scratch are the finder's too: the pair sort's is 8 bytes per pair and its digit
  // counts, and on a sparse grid the cell sort's 12 per entry.
  std::size_t bytes = m_bins.bytes() + m_movedBins.bytes() + m_scan.bytes() + m_sort.bytes();
  for (const DeviceArray* a : {&m_boxes, &m_flags, &m_grid, &m_activeBuf, &m_hugeBuf, &m_pairs, &m_counter,
                               &m_overflow, &m_restingBuf, &m_updatesBuf, &m_movedHugeBuf}) {
    bytes += a->bytes;
  }
  // And the host's lists.
  return bytes + m_resting.capacity() + m_extent.capacity() * sizeof(float) +
         m_updates.capacity() * sizeof(GpucolProxyUpdate) +
         (m_active.capacity() + m_binned.capacity() + m_huge.capacity() + m_moved.capacity() +
          m_movedBinned.capacity() + m_movedHuge.capacity()) *
             sizeof(std::uint32_t) +
         m_keptPairs.bytes() + m_found.capacity() * 8;
}

void OpenClPairFinder::releaseUnkept() {
  // Between searches the finder holds only what the next one reuses, as the CPU finder does: stage 11's kept
  // grid (the flags and resting marks on the device, and the boxes where they are copied, the entries and
  // runs the moved proxies are tested against, the huge list, and the last pairs unless the caller keeps
  // them) when this search kept one. A full search writes every box again, so without a kept grid even the
  // boxes go. The host's lists go in any case; the device's
  // buffers where the finder releases them (OpenClPairFinderTuning::release). The next search allocates
  // afresh (measured: measurement history, "OpenCL memory between steps").
  m_context.queue().finish();  // writes not waited for read the host lists until they run
  m_records = cl::Buffer();
  for (auto* v : {&m_active, &m_binned, &m_huge, &m_moved, &m_movedBinned, &m_movedHuge}) {
    std::vector<std::uint32_t>().swap(*v);
  }
  std::vector<float>().swap(m_extent);
  std::vector<GpucolProxyUpdate>().swap(m_updates);
  std::vector<std::uint64_t>().swap(m_found);
  if (!m_kept) std::vector<std::uint8_t>().swap(m_resting);
  if (!m_kept || m_callerKeepsPairs) m_keptPairs.clear();
  if (!m_releases) return;
  for (DeviceArray* a :
       {&m_activeBuf, &m_pairs, &m_updatesBuf, &m_movedHugeBuf, &m_bins.slots, &m_bins.runPairs}) {
    a->release();
  }
  m_movedBins = Bins{};
  m_sort.releaseScratch();
  if (!m_kept) {
    m_bins = Bins{};
    for (DeviceArray* a : {&m_boxes, &m_flags, &m_hugeBuf, &m_restingBuf}) a->release();
    m_syncedCount = 0;
  }
}

bool OpenClPairFinder::keepGrid(const ProxyArrays& p, const PairFinderOptions& options) {
  // Stage 11, as the CPU finder decides it: the kept grid serves while the options that shape it are the
  // same, `moved` is known, and few active proxies changed since it was built (new slots among them: the
  // device's arrays grow to hold them in sendChanges).
  if (!m_kept || m_inPlace != m_keptInPlace || p.moved == nullptr || (m_callerKeepsPairs && !p.lastPairs) ||
      m_active.size() < options.bruteForceBelow || m_active.size() < 2 ||
      options.cellSizeRule != m_keptOptions.cellSizeRule ||
      options.hugeCellLimit != m_keptOptions.hugeCellLimit || p.count < m_syncedCount) {
    return false;
  }
  // A slot stays resting while it stays active and does not change; new slots start changed. A slot that
  // changes, or becomes inactive, is written to the device (a destroyed one with its flags only).
  m_resting.resize(p.count, 0);
  m_moved.clear();
  m_updates.clear();
  const std::size_t limit = std::size_t(kIncrementalFraction * double(m_active.size()));
  for (std::uint32_t s = 0; s < p.count; ++s) {
    const bool active = (p.flags[s] & kProxyActive) != 0;
    if (p.moved[s] || s >= m_syncedCount || (m_resting[s] && !active)) {
      m_resting[s] = 0;
      m_updates.push_back(GpucolProxyUpdate{deviceBox(p, s), s, p.flags[s]});
    }
    if (active && !m_resting[s]) {
      m_moved.push_back(s);
      if (m_moved.size() > limit) {  // too many: a full search, which rebuilds m_resting anyway
        return false;
      }
    }
  }
  return true;
}

void OpenClPairFinder::sendChanges(const ProxyArrays& p, Kernels& k) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  // New slots: the arrays grow, keeping what they hold (every new slot is among the updates).
  if (m_inPlace) {
    bindRecords(p);
  } else {
    m_boxes.ensureKeeping(c, q, std::size_t(p.count) * sizeof(GpucolProxyBox));
  }
  m_flags.ensureKeeping(c, q, p.count);
  m_restingBuf.ensureKeeping(c, q, p.count);
  const std::uint32_t count = std::uint32_t(m_updates.size());
  if (count > 0) {
    const std::size_t bytes = std::size_t(count) * sizeof(GpucolProxyUpdate);
    q.enqueueWriteBuffer(m_updatesBuf.ensureFitted(c, bytes), CL_FALSE, 0, bytes, m_updates.data());
    setKernelArgs(k.updateProxies, 0, m_inPlace ? m_records : m_boxes.buffer, m_flags.buffer,
                  m_restingBuf.buffer, m_updatesBuf.buffer, count);
    launch(k.updateProxies, count);
  }
  m_syncedCount = p.count;
}

bool OpenClPairFinder::fewMoved(const ProxyArrays& p) const {
  // Stage 11: keep this grid after a first search (nothing is known about motion yet) or when few proxies
  // changed since the last one, as the CPU finder does; where most move, the next search is a full one.
  if (p.moved == nullptr) return true;
  const std::size_t limit = std::size_t(kIncrementalFraction * double(m_activeCount));
  std::size_t moved = 0;
  for (std::uint32_t s : m_active) {
    if (p.moved[s] && ++moved > limit) return false;
  }
  return true;
}

void OpenClPairFinder::fullSearch(const ProxyArrays& p, const PairFinderOptions& options, Kernels& k,
                                  std::vector<std::uint64_t>& pairs) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  upload(p);
  const std::uint32_t activeCount = m_activeCount;
  const cl_uint slotBits = indexBits(p.count);
  const cl_uint zero = 0;
  // The active list goes to the device only for the kernels that walk it: brute force and huge boxes.
  auto uploadActive = [&] {
    q.enqueueWriteBuffer(m_activeBuf.ensureFitted(c, activeCount * 4), CL_FALSE, 0, activeCount * 4,
                         m_active.data());
  };

  const bool useGrid = activeCount >= options.bruteForceBelow;
  // Whether this grid is kept for the next search is known now, so that what it would not reuse goes as soon
  // as this search is done with it.
  const bool keep = useGrid && fewMoved(p);
  // A kept grid's state: this search makes its own, at its size (keepGrid's lists of the moved and their
  // updates too, made before it found too many).
  notePeak();
  std::vector<std::uint32_t>().swap(m_moved);
  std::vector<GpucolProxyUpdate>().swap(m_updates);
  std::vector<std::uint8_t>().swap(m_resting);
  if (m_releases) {
    m_bins = Bins{};
    m_restingBuf.release();
  }
  GpucolGridParams grid{};
  m_bins.count = m_bins.candidates = 0;
  m_huge.clear();
  if (useGrid) {
    m_stats.usedGrid = true;
    chooseGrid(p, options, grid);
    q.enqueueWriteBuffer(m_grid.ensure(c, sizeof grid), CL_FALSE, 0, sizeof grid, &grid);
    if (!m_huge.empty()) {
      const std::uint32_t hugeCount = std::uint32_t(m_huge.size());
      q.enqueueWriteBuffer(m_hugeBuf.ensureFitted(c, hugeCount * 4), CL_FALSE, 0, hugeCount * 4,
                           m_huge.data());
    }
    writeSlots(m_binned, m_bins);
    // The host's lists of every proxy go before binning takes its memory, once on the device (waited for:
    // the writes read them until done).
    q.finish();
    notePeak();
    for (auto* v : {&m_active, &m_binned}) std::vector<std::uint32_t>().swap(*v);
    std::vector<float>().swap(m_extent);
    m_stats.chooseMs = millisecondsSince(m_searchStart);
    const auto binStart = std::chrono::steady_clock::now();
    bin(k, grid, m_bins, false);
    m_stats.binMs = millisecondsSince(binStart);
    m_stats.keys = m_bins.keys;
    m_stats.runsAreCells = m_bins.runsAreCells;
    m_stats.candidates = m_bins.candidates + std::uint64_t(m_huge.size()) * activeCount;
  } else {
    uploadActive();
    m_stats.candidates = gpucol_pair_count(activeCount);
    m_stats.chooseMs = millisecondsSince(m_searchStart);
  }

  // Stages 7–10: test every candidate and append the survivors; grow and run again when they overflow
  // the output (its size comes from the last search, so a steady scene runs once).
  const auto testStart = std::chrono::steady_clock::now();
  std::uint32_t capacity = std::max<std::uint32_t>(1024, m_lastPairs + m_lastPairs / 4);
  for (;;) {
    q.enqueueFillBuffer(m_counter.buffer, zero, 0, 4);
    const cl::Buffer& out = m_pairs.ensureFitted(c, std::size_t(capacity) * 8);
    if (useGrid) {
      testBins(k, m_bins, out, capacity, slotBits);
      testHuge(k, m_hugeBuf, std::uint32_t(m_huge.size()), p.count, out, capacity, slotBits);
    } else {
      setProxyArgs(k.bruteTest);
      setKernelArgs(k.bruteTest, kProxyArgs, m_activeBuf.buffer, activeCount,
                    cl_ulong(gpucol_pair_count(activeCount)), slotBits, out, capacity, m_counter.buffer);
      launchStrided(k.bruteTest, gpucol_pair_count(activeCount));
    }
    if (pairsFit(capacity)) break;
  }
  // The pair sort's scratch is the search's last peak: what neither it nor the next search uses goes first.
  releaseEarly({&m_bins.runPairs, &m_activeBuf}, false);
  if (!keep) releaseEarly({&m_bins.keySlots, &m_bins.runStart, &m_bins.runCell}, false);
  m_stats.testMs = millisecondsSince(testStart);
  const auto sortStart = std::chrono::steady_clock::now();
  readPairs(slotBits, pairs);
  m_stats.sortMs = millisecondsSince(sortStart);

  if (keep) {
    m_keptOptions = options;
    m_keptGrid = grid;
    m_keptHugeCount = std::uint32_t(m_huge.size());
    m_resting.resize(p.count);
    for (std::uint32_t s = 0; s < p.count; ++s) m_resting[s] = p.flags[s] & kProxyActive;
    // Waited for: no read of this step comes after it, and the next step's keepGrid edits m_resting (and may
    // reallocate it) on the host before anything waits on the queue. Not waited for, PoCL's thread was seen
    // reading the list after the finder had freed it (AddressSanitizer, ClusteredScene).
    q.enqueueWriteBuffer(m_restingBuf.ensureFitted(c, p.count), CL_TRUE, 0, p.count, m_resting.data());
    m_kept = true;
  }
}

void OpenClPairFinder::incremental(const ProxyArrays& p, const PairFinderOptions& options, Kernels& k,
                                   std::vector<std::uint64_t>& pairs) {
  const cl::Context& c = m_context.context();
  cl::CommandQueue& q = m_context.queue();
  const GpucolGridParams& grid = m_keptGrid;
  m_stats.usedGrid = true;
  m_stats.incremental = true;
  m_stats.cellSize = m_keptCell;
  m_stats.dims[0] = grid.dimX, m_stats.dims[1] = grid.dimY, m_stats.dims[2] = grid.dimZ;
  m_stats.restingProxies = m_activeCount - std::uint32_t(m_moved.size());
  notePeak();
  std::vector<std::uint32_t>().swap(m_active);  // the moved list says all this search needs of it
  sendChanges(p, k);
  const cl_uint slotBits = indexBits(p.count);
  const cl_uint zero = 0;

  // Moved proxies: huge ones (on the kept cell size) test against every active proxy; the others against
  // the kept cells and huge boxes (grid_test_moved) and each other (stages 4-9 on their own entries).
  m_movedBinned.clear();
  m_movedHuge.clear();
  for (std::uint32_t s : m_moved) {
    (isHuge(p, s, m_keptCell, options.hugeCellLimit) ? m_movedHuge : m_movedBinned).push_back(s);
  }
  const std::uint32_t binnedCount = std::uint32_t(m_movedBinned.size());
  const std::uint32_t hugeCount = std::uint32_t(m_movedHuge.size());
  m_hugeBuf.ensure(c, 4);  // a valid argument even when the kept search had no huge box
  writeSlots(m_movedBinned, m_movedBins);
  bin(k, grid, m_movedBins, true);
  m_stats.keys = m_movedBins.keys;
  m_stats.candidates = m_movedBins.candidates;
  if (hugeCount > 0) {
    // grid_test_huge over every active slot, against the moved huge boxes (ascending, as m_moved).
    q.enqueueWriteBuffer(m_movedHugeBuf.ensureFitted(c, hugeCount * 4), CL_FALSE, 0, hugeCount * 4,
                         m_movedHuge.data());
  }

  std::uint32_t capacity = std::max<std::uint32_t>(1024, m_lastPairs + m_lastPairs / 4);
  for (;;) {
    q.enqueueFillBuffer(m_counter.buffer, zero, 0, 4);
    const cl::Buffer& out = m_pairs.ensureFitted(c, std::size_t(capacity) * 8);
    if (binnedCount > 0) {
      setProxyArgs(k.testMoved);
      setKernelArgs(k.testMoved, kProxyArgs, m_grid.buffer, m_restingBuf.buffer, m_bins.runStart.buffer,
                    m_bins.runCell.buffer, m_bins.runs, m_bins.keySlots.buffer, m_hugeBuf.buffer,
                    m_keptHugeCount, m_movedBins.slots.buffer, binnedCount, slotBits, out, capacity,
                    m_counter.buffer);
      launch(k.testMoved, binnedCount);
    }
    testBins(k, m_movedBins, out, capacity, slotBits);
    testHuge(k, m_movedHugeBuf, hugeCount, p.count, out, capacity, slotBits);
    if (pairsFit(capacity)) break;
  }
  // The new pairs, sorted on the device, merged with the carried ones: pairs of two resting proxies are
  // those of the last search (neither box nor filter changed). Every new pair has a moved proxy, so the two
  // lists never share a pair (mergeCarriedPairs: no second list of the carried pairs).
  readPairs(slotBits, m_found);
  mergeCarriedPairs(
      m_callerKeepsPairs ? *p.lastPairs : m_keptPairs,
      [&](std::uint64_t key) { return m_resting[std::uint32_t(key >> 32)] && m_resting[std::uint32_t(key)]; },
      m_found, pairs);
  notePeak();  // the output beside the new pairs
}

}  // namespace

std::unique_ptr<PairFinder> makePairFinder(const Config& config, const OpenClPairFinderTuning& tuning) {
  OpenClContext* context = OpenClContext::tryGet(config.openclDevice);
  if (context == nullptr) {
    return nullptr;
  }
  return std::make_unique<OpenClPairFinder>(*context, tuning);
}

}  // namespace gpucol::opencl
