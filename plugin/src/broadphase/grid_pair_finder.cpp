// CPU implementation of the grid pair finder; the stage numbers in comments refer to grid_pair_finder.h.
#include "broadphase/grid_pair_finder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <utility>

#include "broadphase/grid_choice.h"
#include "broadphase/local_box.h"
#include "broadphase/pair_buckets.h"
#include "shared_math/pair_mapping.h"
#include "broadphase/slab_search.h"
#include "memory/large_array_allocator.h"
#include "sorting/radix_sort.h"

namespace gpucol {
namespace {

/// Candidates per parallel chunk at least (a multiple of 64 so bit-mask words are never shared).
constexpr std::uint64_t kMinChunk = 16384;
/// The home-cell order of the binned boxes (for locality only) is renewed after this many searches.
constexpr std::uint32_t kHomeOrderSteps = 8;
/// Stage 11: a search keeps the last grid while at most this fraction of the active proxies changed since
/// it was built; beyond that, binning everything again costs about as much and gives a fitted grid.
constexpr double kIncrementalFraction = 0.125;
/// Moved proxies per parallel task of an incremental search.
constexpr std::size_t kMovedGrain = 256;
/// Chunks of the pair sort's parallel passes (fixed, so the passes do not depend on the thread count).
constexpr std::size_t kSortChunks = 16;
/// An entry of m_sorted on a dense grid: the index of its box in m_box, and kHomeEntry when the cell is the
/// box's home cell (the cell of its min corner), which the huge boxes' tests read without loading the box.
constexpr std::uint32_t kHomeEntry = 1u << 31;
constexpr std::uint32_t kEntryBox = kHomeEntry - 1;
/// SlabTiling::Auto cuts a grid into slabs only when at least this many come out, so both cores have work
/// while the slowest slab finishes. A few large slabs of a big scene (a pile in few cells) are left to the
/// whole-grid search, which spreads one cell's candidates over threads (stage 7).
constexpr std::uint32_t kMinSlabs = 8;
/// ... but a scene of fewer binned boxes takes any slabs at all: there the whole-grid search's working memory
/// (about 100 bytes per box) outweighs what its threads gain (mixed sizes at 2,000 boxes, in few slabs: 174
/// against 115 bytes per proxy at the peak, and no slower; measurement history).
constexpr std::size_t kAnySlabsBelow = 2048;
/// ... and only up to this many binned boxes. Each slab reads its boxes from the view at slots spread over
/// the whole scene. At 100K boxes the view stays in cache and the slab search was as fast as the whole-grid
/// search; at 1M each slab read the view from memory again, and steps took 8-31% longer (measurement
/// history). The limit lies between the two measured sizes.
constexpr std::size_t kMaxSlabBoxes = std::size_t(1) << 18;
/// SlabTiling::Auto and AnySize search by home cell (where chooseGrid finds a home grid) from this many binned
/// boxes: each thread then copies its slab's boxes in cell order beside a start per cell, which in a scene of
/// 1,000 boxes raised the peak of a step from 84-94 to 101-107 bytes per proxy, over issue 4's 100; the other
/// slab search reads a small scene's boxes in place.
constexpr std::size_t kHomeCellsFrom = 4096;
/// Chunks per search at most, so per-chunk bookkeeping stays small next to the work.
constexpr std::uint64_t kMaxChunks = 256;

inline bool passesFilter(const ProxyArrays& p, std::uint32_t a, std::uint32_t b) {
  // Bullet's default filter (btOverlappingPairCache::needsBroadphaseCollision without a callback), bit for bit:
  // static–static pairs go only where the masks refuse them, as Bullet's own filters do.
  return (p.group[a] & p.mask[b]) != 0 && (p.group[b] & p.mask[a]) != 0;
}

inline std::uint32_t homeCell(const ProxyArrays& p, std::uint32_t s, const Grid& g) {
  const BoxCorners b = p.box(s);
  const std::uint32_t x = cellOf(b.lo[0], g.origin[0], g.invCell, g.dims[0]);
  const std::uint32_t y = cellOf(b.lo[1], g.origin[1], g.invCell, g.dims[1]);
  const std::uint32_t z = cellOf(b.lo[2], g.origin[2], g.invCell, g.dims[2]);
  return std::uint32_t((std::uint64_t(z) * g.dims[1] + y) * g.dims[0] + x);
}

template <typename F>
inline void forEachCell(const CellRange& r, const Grid& g, F&& f) {
  forEachCellOf(r, g.dims, [&](std::uint32_t c, std::uint32_t, std::uint32_t, std::uint32_t) { f(c); });
}

/// Milliseconds since the last lap (stage timings of PairFinderStats).
class StageClock {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - m_last).count();
    m_last = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point m_last = std::chrono::steady_clock::now();
};

/// Splits [0, total) into deterministic chunks (boundaries depend only on total).
inline std::uint64_t chunkSize(std::uint64_t total) {
  std::uint64_t size = std::max(kMinChunk, (total + kMaxChunks - 1) / kMaxChunks);
  return (size + 63) / 64 * 64;
}

/// Grain of the parallel loops over cells and boxes: large enough that a task's overhead is negligible.
constexpr std::size_t kGrain = 16384;

/// Inclusive prefix sum of data[0, n) in place, in parallel; returns the total (integers: the result does
/// not depend on how oneTBB splits the range).
template <typename T>
T inclusiveScan(T* data, std::size_t n) {
  return tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, n, kGrain), T(0),
      [data](const tbb::blocked_range<std::size_t>& r, T sum, bool final) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          sum += data[i];
          if (final) data[i] = sum;
        }
        return sum;
      },
      std::plus<T>());
}

/// Relaxed atomic add on a plain counter array shared by the threads of one counting pass (GCC/Clang
/// builtin: the arrays stay plain std::vector<std::uint32_t> so they can be resized and reused).
inline std::uint32_t atomicAdd(std::uint32_t& counter, std::uint32_t value) {
  return __atomic_fetch_add(&counter, value, __ATOMIC_RELAXED);
}

/// Keys below which sortPairs compares instead (as fast there, and without the radix sort's memory).
constexpr std::size_t kComparisonSortBelow = 512;

/// Sorts pair keys (lower slot << 32 | higher slot, both below 2^slotBits) ascending with the radix sort of
/// sorting/radix_sort.h on the 2 x slotBits significant bits, in digits of at most 11 bits, using `scratch`
/// as the second buffer and `offsets` for the digit counts (up to 256 KB; the caller counts and frees both
/// with its scratch). Each pass is parallel over kSortChunks fixed chunks (the serial form was several times
/// slower at 1M boxes). Faster than a comparison sort here (a pair list is a few keys per proxy and slots are
/// dense), and the result is the sorted list whatever the input order.
void sortPairs(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& scratch,
               std::vector<std::size_t>& offsets, std::uint32_t slotBits) {
  constexpr unsigned kMaxDigitBits = 11;
  const std::size_t n = keys.size();
  if (n < kComparisonSortBelow) {
    // A few keys (the pairs of a handful of moved proxies): no second buffer and no 16 KB digit table.
    std::sort(keys.begin(), keys.end());
    return;
  }
  const std::size_t chunks = std::min<std::size_t>(kSortChunks, (n + kGrain - 1) / kGrain);
  const std::size_t chunk = (n + chunks - 1) / chunks;
  auto forChunks = [&](auto&& f) {
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      const std::size_t begin = c * chunk, end = std::min(n, begin + chunk);
      if (begin < end) f(begin, end);
    });
  };
  // Compact (a, b) to (a << slotBits) | b so that every pass sorts significant bits.
  forChunks([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      keys[i] = ((keys[i] >> 32) << slotBits) | (keys[i] & 0xffffffffu);
  });
  scratch.resize(n);
  const RadixDigits digits(2 * slotBits, kMaxDigitBits);
  offsets.resize(chunks * digits.buckets());
  if (radixSort(keys.data(), scratch.data(), n, 0, digits, offsets.data(), chunks) != keys.data())
    keys.swap(scratch);
  const std::uint64_t low = (std::uint64_t(1) << slotBits) - 1;
  forChunks([&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) keys[i] = ((keys[i] >> slotBits) << 32) | (keys[i] & low);
  });
}

/// Parallel counting sort of items 0..items-1 into `cells` buckets; `buckets(i, f)` calls f(cell) for each
/// bucket item i goes into, and place(i, position, bucket) stores item i at its position in the output.
/// Afterwards start[c]..start[c+1] (start has cells + 1 entries) is bucket c's range of the output. Threads
/// count with atomic increments, an inclusive scan turns counts into bucket ends, and threads place items by
/// atomic decrements, which leaves start[c] at the bucket's begin. The order inside a bucket depends on
/// thread timing; nothing downstream does: pairs are keyed by slot and the output is sorted (stage 10), so
/// the result is the same whatever the threads did.
template <typename Buckets, typename Place>
void countingSort(std::size_t items, std::uint64_t cells, LargeArrayVector<std::uint32_t>& start,
                  Buckets&& buckets, Place&& place) {
  start.resize(cells + 1);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, cells + 1, 1 << 18), [&](const tbb::blocked_range<std::size_t>& r) {
        std::fill(start.begin() + std::ptrdiff_t(r.begin()), start.begin() + std::ptrdiff_t(r.end()), 0u);
      });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, items, kGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        buckets(i, [&](std::uint32_t c) { atomicAdd(start[c], 1u); });
                    });
  inclusiveScan(start.data(), cells + 1);  // start[c] = end of bucket c; start[cells] = total
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, items, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          buckets(i, [&](std::uint32_t c) { place(i, atomicAdd(start[c], std::uint32_t(-1)) - 1, c); });
      });
}

class CpuPairFinder final : public PairFinder {
 public:
  void findPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                 std::vector<std::uint64_t>& pairs) override {
    search(proxies, options, pairs, nullptr);
  }
  void findCodedPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                      PackedPairs& pairs) override {
    std::vector<std::uint64_t> keys;
    search(proxies, options, keys, &pairs);
  }
  bool codesPairs() const override { return true; }
  const PairFinderStats& stats() const override { return m_stats; }
  std::string name() const override { return "cpu"; }
  bool readsBoxRecords() const override { return true; }
  bool surveyWanted(const PairFinderOptions& options, float& cell, int& axis) const override;

 private:
  /// The search: the keys into `pairs`, or when `coded` is given into it (`pairs` then a scratch list that
  /// the slab search does without).
  void search(const ProxyArrays& proxies, const PairFinderOptions& options, std::vector<std::uint64_t>& pairs,
              PackedPairs* coded);
  void bruteForce(const ProxyArrays& p, const PairFinderOptions& options, std::vector<std::uint64_t>& pairs);
  void grid(const ProxyArrays& p, const PairFinderOptions& options, bool keepGrid,
            std::vector<std::uint64_t>& pairs);
  bool searchSlabs(const ProxyArrays& p, const PairFinderOptions& options, const Grid& g, const Grid& home);
  void binKeptGrid(const ProxyArrays& p, const Grid& g, std::size_t binnedCount);
  void binSorted(const ProxyArrays& p, const Grid& g);
  void testRuns(const PairFinderOptions& options, const Grid& g);
  void testHuge(const ProxyArrays& p, const Grid& g);
  void gather(std::vector<std::uint64_t>& pairs);
  bool keepGrid(const ProxyArrays& p, const PairFinderOptions& options, std::uint32_t activeCount);
  void incremental(const ProxyArrays& p, const PairFinderOptions& options, std::uint32_t activeCount,
                   std::vector<std::uint64_t>& pairs);
  void listActive(const ProxyArrays& p, std::uint32_t activeCount);
  std::size_t scratchBytes() const;
  bool fewMoved(const ProxyArrays& p) const;
  void releaseScratch();
  void dropKeptGrid();
  /// Whether the home order is young enough and of the right length for binSorted to reuse it for `binned`
  /// boxes (binSorted then checks that they are the same boxes).
  bool homeOrderFits(std::size_t binned) const {
    return m_homeOrder.size() == binned && m_homeOrderAge < kHomeOrderSteps;
  }
  /// Raises the high-water mark of this search's memory, the output list included, to what is allocated now
  /// (called where a phase has all its memory, before it frees some).
  void notePeak() {
    m_peakBytes = std::max(m_peakBytes, scratchBytes() + (m_output ? m_output->capacity() * 8 : 0) +
                                            (m_codedOutput ? m_codedOutput->bytes() : 0));
  }

  PairFinderStats m_stats;
  std::vector<std::uint32_t> m_active;          // active slots, ascending
  std::vector<std::uint32_t> m_binned;          // active slots that go into the grid
  std::vector<std::uint32_t> m_huge;            // active slots kept out of the grid (stage 3)
  std::vector<float> m_extent;                  // scratch for the median extent
  LargeArrayVector<std::uint32_t> m_cellStart;  // dense counting sort: first entry per cell (+1 sentinel)
  std::vector<std::uint64_t> m_keys;            // sparse path: (cell << 32) | slot
  LargeArrayVector<LocalBox> m_box;             // binned boxes ordered by (home cell, slot)
  std::vector<std::uint64_t> m_homeKeys;        // scratch for that order on a sparse grid
  std::vector<std::uint32_t> m_homeOrder;       // binned slots by home cell, as of the last home sort
  std::uint32_t m_homeOrderAge = 0;             // searches since that sort
  std::vector<std::uint32_t> m_homePos;         // per slot: its index in m_homeOrder (binned slots only)
  LargeArrayVector<PackedCells> m_packed;       // dense grid: each box's cells (stage 4 to 5)
  LargeArrayVector<std::uint8_t> m_isBinned;    // per slot: binned in this search
  // Stage 11: the last full grid search (m_cellStart, m_sorted, m_box of a dense grid) kept for later
  // searches while few proxies change.
  bool m_kept = false;        // m_cellStart/m_sorted/m_box/m_keptHuge describe m_keptGrid
  bool m_denseBuilt = false;  // the last grid search filled m_cellStart (dense counting sort)
  Grid m_keptGrid;
  PairFinderOptions m_keptOptions;
  std::vector<std::uint8_t> m_unchanged;      // per slot: active in the kept search and unchanged since
  std::vector<std::uint32_t> m_keptHuge;      // huge proxies of the kept search
  PackedPairs m_lastPairs;                    // this finder's previous result (unless the caller keeps it)
  bool m_callerKeepsPairs = false;            // the kept grid's pairs are the caller's ProxyArrays::lastPairs
  std::vector<std::uint32_t> m_moved;         // active slots changed since the kept search
  std::vector<std::uint64_t> m_movedKeys;     // (cell << 32) | index into m_moved, binned moved proxies
  std::vector<std::uint64_t> m_sortScratch;   // second buffer of the pair radix sort
  std::vector<std::size_t> m_sortOffsets;     // its digit counts per chunk
  LargeArrayVector<std::uint32_t> m_sorted;   // m_box indices by cell (dense grid: with kHomeEntry; a grid
                                              // kept after a slab search: m_homeOrder indices, no bit)
  LargeArrayVector<std::uint32_t> m_runCell;  // runs of >= 2 entries: cell index
  LargeArrayVector<std::uint32_t> m_runStart;  // first entry in m_sorted
  LargeArrayVector<std::uint32_t> m_runLength;
  LargeArrayVector<std::uint64_t> m_runPrefix;  // exclusive prefix sum of m(m-1)/2, plus the total at the end
  std::vector<std::uint32_t> m_blockRuns;       // runs per block of cells, scanned (dense run compaction)
  std::vector<std::uint32_t> m_offsets;         // sparse path: first key of each box (exclusive prefix sum)
  std::vector<std::uint64_t> m_bits;            // bit mask output (stage 10)
  std::vector<std::vector<std::uint64_t>> m_chunkPairs;  // output per chunk (freed once gathered)
  SlabSearch m_slabs;                                    // the slab search's plan and working memory
  AxisExtents m_keptExtents;     // in place: the binned boxes' extents along the last slab axis (the plan's)
  float m_lastSizedCell = 0.0f;  // stage 2's cell edge of the last grid search (0: brute force since)
  std::size_t m_peakBytes = 0;   // high-water mark of this search (notePeak)
  const std::vector<std::uint64_t>* m_output = nullptr;  // findPairs' `pairs`, during the search
  PackedPairs* m_codedOutput = nullptr;                  // findCodedPairs' `pairs`, during the search
  bool m_coded = false;                                  // the search coded its keys into m_codedOutput
  PairBuckets m_buckets;         // the slab search's pairs by bucket when coded (pair_buckets.h)
  std::size_t m_chunksUsed = 0;  // chunks of m_chunkPairs filled by this search

  /// Reserves `count` more output chunks and returns the index of the first.
  std::size_t takeChunks(std::size_t count) {
    const std::size_t first = m_chunksUsed;
    m_chunksUsed += count;
    if (m_chunkPairs.size() < m_chunksUsed) m_chunkPairs.resize(m_chunksUsed);
    return first;
  }
};

void CpuPairFinder::search(const ProxyArrays& proxies, const PairFinderOptions& options,
                           std::vector<std::uint64_t>& pairs, PackedPairs* coded) {
  m_stats = PairFinderStats{};
  m_chunksUsed = 0;
  m_peakBytes = 0;
  m_output = &pairs;
  m_codedOutput = coded;
  m_coded = false;
  pairs.clear();
  if (coded) coded->clear();
  // Stage 0: the active proxies, counted; the full searches list them (listActive), the incremental one
  // (stage 11) needs no list of every proxy.
  std::uint32_t activeCount = 0;
  for (std::uint32_t s = 0; s < proxies.count; ++s) activeCount += proxies.flags[s] & kProxyActive;
  // Stage 1: the path. A search that does not take the kept grid (stage 11) drops it first: it is not held
  // beside the search's own memory.
  const bool incrementalSearch = activeCount >= std::max<std::uint32_t>(2, options.bruteForceBelow) &&
                                 keepGrid(proxies, options, activeCount);
  if (!incrementalSearch) m_kept = false, dropKeptGrid();
  if (activeCount < 2) {
    // No pair to find.
  } else if (activeCount < options.bruteForceBelow) {
    m_lastSizedCell = 0.0f;
    listActive(proxies, activeCount);
    bruteForce(proxies, options, pairs);
  } else if (incrementalSearch) {
    incremental(proxies, options, activeCount, pairs);
  } else {
    listActive(proxies, activeCount);
    // Stage 11: keep this grid (dense grids only: their cells are looked up directly) after a first search
    // (nothing is known about motion yet: a world starts at rest) or when few proxies changed since the
    // last one (a scene coming to rest). Where most move, the next search is a full one anyway, and keeping
    // the grid would only hold its memory between steps.
    const bool keep = proxies.moved == nullptr || fewMoved(proxies);
    grid(proxies, options, keep, pairs);
    m_kept = m_denseBuilt && keep;
    if (m_kept) {
      m_keptOptions = options;
      m_unchanged.assign(proxies.count, 0);
      for (std::uint32_t s = 0; s < proxies.count; ++s) m_unchanged[s] = proxies.flags[s] & kProxyActive;
      m_keptHuge = m_huge;
    }
  }
  if (coded && !m_coded) {
    // Found as a list (every path but the slab search's): coded, then the list freed.
    notePeak();
    if (PackedPairs::worthCoding(pairs.size(), proxies.count)) {
      coded->assign(pairs);
      notePeak();
      std::vector<std::uint64_t>().swap(pairs);
    } else {
      coded->adopt(std::move(pairs));  // kept plain: taken over, not copied
    }
  }
  // The pairs carried over by the next incremental search: the caller's copy when it says it keeps one
  // (not held twice), else our own.
  m_callerKeepsPairs = m_kept && proxies.lastPairs != nullptr;
  if (m_kept && !m_callerKeepsPairs) {
    if (coded)
      m_lastPairs = *coded;
    else
      m_lastPairs.assign(pairs, !PackedPairs::worthCoding(pairs.size(), proxies.count));
  } else {
    m_lastPairs.clear();
  }
  m_stats.rebinnedProxies = activeCount - m_stats.restingProxies;
  notePeak();
  m_stats.peakScratchBytes = m_peakBytes;
  m_stats.peakIncludesOutput = true;
  m_output = nullptr;
  m_codedOutput = nullptr;
  releaseScratch();
  m_stats.scratchBytes = scratchBytes();
}

void CpuPairFinder::listActive(const ProxyArrays& p, std::uint32_t activeCount) {
  // Ascending, so brute force emits keys already in order; reserved exactly (grown by push_back it could
  // hold twice its entries).
  m_active.clear();
  m_active.reserve(activeCount);
  for (std::uint32_t s = 0; s < p.count; ++s)
    if (p.flags[s] & kProxyActive) m_active.push_back(s);
}

bool CpuPairFinder::fewMoved(const ProxyArrays& p) const {
  const std::size_t limit = std::size_t(kIncrementalFraction * double(m_active.size()));
  std::size_t moved = 0;
  for (std::uint32_t s : m_active)
    if (p.moved[s] && ++moved > limit) return false;
  return true;
}

void CpuPairFinder::releaseScratch() {
  // Between searches the finder holds only what the next search reuses: the home-cell order of the binned
  // boxes (locality, stage 4), and while the grid is kept (stage 11) its cells, entries, unchanged flags,
  // huge proxies and pairs; the incremental search reads the kept boxes from the proxies through the home
  // order, so the local box copies go too.
  auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  release(m_active), release(m_binned), release(m_huge), release(m_extent), release(m_keys);
  release(m_box), release(m_homeKeys), release(m_packed), release(m_isBinned), release(m_moved);
  release(m_movedKeys), release(m_sortScratch), release(m_sortOffsets), release(m_runCell);
  release(m_runStart);
  release(m_runLength), release(m_runPrefix), release(m_blockRuns), release(m_offsets), release(m_bits);
  release(m_chunkPairs);
  m_slabs.release();
  if (!m_kept) release(m_cellStart), release(m_sorted), release(m_unchanged), release(m_keptHuge);
  // While the grid is kept, searches are incremental and name kept boxes through the home order alone; the
  // slots' places in it are rebuilt by a full search that reuses the order (binSorted).
  if (m_kept) release(m_homePos);
}

void CpuPairFinder::dropKeptGrid() {
  auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  release(m_cellStart), release(m_sorted), release(m_unchanged), release(m_keptHuge), release(m_lastPairs);
  // The home order stays for the whole-grid search's locality (binSorted) while it may still be reused.
  if (m_homeOrderAge >= kHomeOrderSteps) release(m_homeOrder), release(m_homePos);
}

bool CpuPairFinder::keepGrid(const ProxyArrays& p, const PairFinderOptions& options,
                             std::uint32_t activeCount) {
  if (!m_kept || p.moved == nullptr || (m_callerKeepsPairs && p.lastPairs == nullptr) ||
      options.cellSizeRule != m_keptOptions.cellSizeRule ||
      options.hugeCellLimit != m_keptOptions.hugeCellLimit || options.output != m_keptOptions.output ||
      options.mappingSqrt != m_keptOptions.mappingSqrt) {
    m_kept = false;
    return false;
  }
  // A slot stays unchanged while it stays active and does not move; new slots start changed. Counted first
  // and listed only when few enough, at their number: a full search does not hold the list beside the kept
  // grid it is about to drop.
  if (m_unchanged.size() < p.count) m_unchanged.resize(p.count, 0);
  const std::size_t limit = std::size_t(kIncrementalFraction * double(activeCount));
  std::size_t moved = 0;
  for (std::uint32_t s = 0; s < p.count; ++s) {
    if (p.moved[s] || !(p.flags[s] & kProxyActive)) m_unchanged[s] = 0;
    if ((p.flags[s] & kProxyActive) && !m_unchanged[s] && ++moved > limit) {
      m_kept = false;  // too many: a full search, which rebuilds m_unchanged anyway
      return false;
    }
  }
  m_moved.clear();
  m_moved.reserve(moved);
  for (std::uint32_t s = 0; s < p.count; ++s)
    if ((p.flags[s] & kProxyActive) && !m_unchanged[s]) m_moved.push_back(s);
  return true;
}

void CpuPairFinder::incremental(const ProxyArrays& p, const PairFinderOptions& options,
                                std::uint32_t activeCount, std::vector<std::uint64_t>& pairs) {
  const Grid& g = m_keptGrid;
  m_stats.usedGrid = true;
  m_stats.incremental = true;
  m_stats.cellSize = g.cell;
  for (int a = 0; a < 3; ++a) m_stats.dims[a] = g.dims[a];
  m_stats.restingProxies = std::uint32_t(activeCount - m_moved.size());

  // Moved proxies: huge ones (on the kept cell size) test against every active proxy; the others are
  // binned on the kept grid, looked up in its cells (stage 9's rule reports each pair in one cell) and
  // tested against the kept huge boxes.
  const std::size_t moved = m_moved.size();
  const std::size_t tasks = (moved + kMovedGrain - 1) / kMovedGrain;
  const std::size_t firstChunk = takeChunks(tasks);
  LargeArrayVector<std::uint8_t>& movedHuge = m_isBinned;  // per moved index (free here: no chooseGrid)
  movedHuge.resize(moved);
  for (std::size_t i = 0; i < moved; ++i) movedHuge[i] = isHuge(p, m_moved[i], g.cell, options.hugeCellLimit);
  tbb::parallel_for(std::size_t(0), tasks, [&](std::size_t t) {
    auto& out = m_chunkPairs[firstChunk + t];
    out.clear();
    for (std::size_t i = t * kMovedGrain, e = std::min(moved, (t + 1) * kMovedGrain); i < e; ++i) {
      const std::uint32_t sm = m_moved[i];
      const LocalBox a = boxOf(p, sm);
      if (movedHuge[i]) {
        for (std::uint32_t s = 0; s < p.count; ++s) {
          if (s == sm || !(p.flags[s] & kProxyActive)) continue;
          if (!m_unchanged[s]) {
            // Another moved proxy: a huge one's pair belongs to the lower slot's row; a binned one's to ours.
            const std::size_t j =
                std::size_t(std::lower_bound(m_moved.begin(), m_moved.end(), s) - m_moved.begin());
            if (movedHuge[j] && s < sm) continue;
          }
          if (boxesOverlap(a, boxOf(p, s)) && passesFilter(p, sm, s)) out.push_back(makePairKey(sm, s));
        }
        continue;
      }
      forEachCell(cellRange(a, g), g, [&](std::uint32_t c) {
        for (std::uint32_t e2 = m_cellStart[c], end = m_cellStart[c + 1]; e2 < end; ++e2) {
          // The kept entries name boxes by their place in the home order of the kept search.
          const std::uint32_t s = m_homeOrder[m_sorted[e2] & kEntryBox];
          if (!m_unchanged[s]) continue;
          const LocalBox b = boxOf(p, s);
          if (!boxesOverlap(a, b) || overlapCell(a, b, g) != c) continue;
          if (passesFilter(a, b)) out.push_back(makePairKey(sm, s));
        }
      });
      for (std::uint32_t h : m_keptHuge)
        if (m_unchanged[h] && boxesOverlap(a, boxOf(p, h)) && passesFilter(p, sm, h))
          out.push_back(makePairKey(sm, h));
    }
  });
  // Binned moved proxies among themselves: keys on the kept grid, sorted, runs tested pairwise.
  m_movedKeys.clear();
  for (std::size_t i = 0; i < moved; ++i)
    if (!movedHuge[i])
      forEachCell(cellRange(boxOf(p, m_moved[i]), g), g,
                  [&](std::uint32_t c) { m_movedKeys.push_back((std::uint64_t(c) << 32) | i); });
  tbb::parallel_sort(m_movedKeys.begin(), m_movedKeys.end());
  std::uint64_t candidates = 0;
  const std::size_t runChunk = takeChunks(1);
  auto& runOut = m_chunkPairs[runChunk];
  runOut.clear();
  for (std::size_t i = 0; i < m_movedKeys.size();) {
    std::size_t j = i + 1;
    const std::uint32_t cell = std::uint32_t(m_movedKeys[i] >> 32);
    while (j < m_movedKeys.size() && std::uint32_t(m_movedKeys[j] >> 32) == cell) ++j;
    for (std::size_t x = i; x < j; ++x) {
      const std::uint32_t sa = m_moved[std::uint32_t(m_movedKeys[x])];
      const LocalBox a = boxOf(p, sa);
      for (std::size_t y = x + 1; y < j; ++y) {
        const std::uint32_t sb = m_moved[std::uint32_t(m_movedKeys[y])];
        const LocalBox b = boxOf(p, sb);
        ++candidates;
        if (boxesOverlap(a, b) && overlapCell(a, b, g) == cell && passesFilter(p, sa, sb))
          runOut.push_back(makePairKey(sa, sb));
      }
    }
    i = j;
  }
  m_stats.keys = m_movedKeys.size();
  m_stats.candidates = candidates;
  gather(m_movedKeys);  // the new pairs (m_movedKeys is free again)
  sortPairs(m_movedKeys, m_sortScratch, m_sortOffsets, slotBitsFor(p.count));
  // Pairs of two unchanged proxies are carried over (neither box nor filter changed); a pair is never both
  // carried and new (a new one has a moved proxy).
  const PackedPairs& last = m_callerKeepsPairs ? *p.lastPairs : m_lastPairs;
  mergeCarriedPairs(
      last,
      [&](std::uint64_t key) {
        return m_unchanged[std::uint32_t(key >> 32)] && m_unchanged[std::uint32_t(key)];
      },
      m_movedKeys, pairs);
}

void CpuPairFinder::bruteForce(const ProxyArrays& p, const PairFinderOptions& options,
                               std::vector<std::uint64_t>& pairs) {
  const std::uint64_t n = m_active.size();
  const std::uint64_t total = gpucol_pair_count(n);
  m_stats.candidates = total;
  const std::uint64_t chunk = chunkSize(total);
  const std::uint64_t chunks = (total + chunk - 1) / chunk;
  const std::size_t firstChunk = takeChunks(chunks);
  const bool newton = options.mappingSqrt == MappingSqrt::Newton;
  // The active boxes side by side, copied once (each is tested n - 1 times): read in Bullet's proxies, every
  // test loaded two boxes through their blocks, most of a small scene's search (91 jiggling boxes: about 30
  // of a step's 44 us).
  m_box.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) m_box[i] = boxOf(p, m_active[i]);
  });
  notePeak();
  tbb::parallel_for(std::uint64_t(0), chunks, [&](std::uint64_t c) {
    const std::uint64_t k0 = c * chunk;
    const std::uint64_t k1 = std::min(total, k0 + chunk);
    gpucol_u64 a = 0, b = 0;
    // The mapping function places the chunk's first item; the rest of the chunk steps through the row,
    // which on a CPU is cheaper than a square root per item and visits the same pairs in the same order.
    if (newton)
      gpucol_pair_from_index_newton(n, k0, &a, &b);
    else
      gpucol_pair_from_index(n, k0, &a, &b);
    auto& out = m_chunkPairs[firstChunk + c];
    out.clear();
    for (std::uint64_t k = k0; k < k1; ++k) {
      const LocalBox &boxA = m_box[a], &boxB = m_box[b];
      if (boxesOverlap(boxA, boxB) && passesFilter(boxA, boxB))
        out.push_back((std::uint64_t(boxA.slot) << 32) | boxB.slot);
      if (++b == n) {
        ++a;
        b = a + 1;
      }
    }
  });
  // Row-major order over ascending slots is key order, and chunks are in k order: no sort needed.
  gather(pairs);
}

void CpuPairFinder::binSorted(const ProxyArrays& p, const Grid& g) {
  const std::size_t n = m_binned.size();
  const std::uint64_t cells = g.cells();
  const bool dense = cells <= denseCellLimit(n);
  // Locality: order the binned boxes by the cell of their min corner, and copy them into one
  // array in that order; cell neighbours are then memory neighbours for the candidate tests (stage 8).
  m_box.resize(n);
  auto copyBox = [&](std::size_t to, std::uint32_t s) { m_box[to] = boxOf(p, s); };
  // The home order only serves locality (any order gives the same pairs), and boxes move little from one
  // search to the next: the last order is reused while it covers the same binned proxies, and renewed
  // every kHomeOrderSteps searches.
  bool reuse = homeOrderFits(n);
  if (reuse) {
    reuse = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, kGrain), true,
        [&](const tbb::blocked_range<std::size_t>& r, bool ok) {
          for (std::size_t i = r.begin(); ok && i != r.end(); ++i)
            ok = m_homeOrder[i] < p.count && m_isBinned[m_homeOrder[i]];
          return ok;
        },
        [](bool a, bool b) { return a && b; });
  }
  if (reuse) {
    ++m_homeOrderAge;
  } else if (dense) {
    // Counting sort of the slots by home cell. (Scattering each box straight to its place instead was
    // slower at 1M boxes: 28-byte writes at random.)
    m_homeOrder.resize(n);
    countingSort(
        n, cells, m_cellStart, [&](std::size_t i, auto&& f) { f(homeCell(p, m_binned[i], g)); },
        [&](std::size_t i, std::uint32_t to, std::uint32_t) { m_homeOrder[to] = m_binned[i]; });
    m_homeOrderAge = 0;
  } else {
    m_homeKeys.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      m_homeKeys[i] = (std::uint64_t(homeCell(p, m_binned[i], g)) << 32) | m_binned[i];
    });
    tbb::parallel_sort(m_homeKeys.begin(), m_homeKeys.end());
    m_homeOrder.resize(n);
    tbb::parallel_for(std::size_t(0), n,
                      [&](std::size_t i) { m_homeOrder[i] = std::uint32_t(m_homeKeys[i]); });
    std::vector<std::uint64_t>().swap(m_homeKeys);  // scratch of a rare path: not kept
    m_homeOrderAge = 0;
  }
  if (m_homeOrderAge == 0 || m_homePos.empty()) {
    m_homePos.resize(p.count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          m_homePos[m_homeOrder[i]] = std::uint32_t(i);
                      });
  }
  // Copy in slot order (sequential reads of the nine SoA arrays) to the home positions (one scattered write
  // of a 40-byte box): gathering in home order instead read nine arrays at random, about three times slower
  // at 1M uniform boxes.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        copyBox(m_homePos[m_binned[i]], m_binned[i]);
                    });
  // Stage 4: count cells per box; the total decides whether the keys fit (count, then allocate). On a dense
  // grid each box's cells are also kept as its first cell and its spans (PackedCells), so the two passes of
  // the counting sort step through them with integer arithmetic instead of computing the range again.
  m_packed.resize(dense ? n : 0);
  const std::uint64_t keys = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 4096), std::uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t sum) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const CellRange range = cellRange(m_box[i], g);
          sum += range.count();
          if (dense) m_packed[i] = PackedCells::of(range, g.dims);
        }
        return sum;
      },
      std::plus<std::uint64_t>());
  m_stats.keys = keys;
  if (keys > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("gpucol::GridBroadphase: " + std::to_string(keys) +
                             " (cell, proxy) entries exceed the 2^32 entry limit of one grid");
  if (n > kEntryBox)
    throw std::runtime_error("gpucol::GridBroadphase: " + std::to_string(n) +
                             " binned proxies exceed the 2^31 - 1 limit of one grid");
  m_runCell.clear();
  m_runStart.clear();
  m_runLength.clear();
  if (dense) {
    // Stage 5, dense grid: parallel counting sort by cell.
    m_denseBuilt = true;
    m_sorted.resize(keys);
    countingSort(
        n, cells, m_cellStart,
        [&](std::size_t i, auto&& f) {
          if (m_packed[i].fits())
            m_packed[i].forEach(g.dims, [&](std::uint32_t c, std::uint32_t) { f(c); });
          else
            forEachCell(cellRange(m_box[i], g), g, f);
        },
        [&](std::size_t i, std::uint32_t to, std::uint32_t c) {
          m_sorted[to] = std::uint32_t(i) | (c == m_packed[i].first ? kHomeEntry : 0u);
        });
    // Stage 6: runs of two or more proxies, compacted in parallel over blocks of cells (count, scan, fill).
    const std::size_t blocks = std::size_t((cells + kGrain - 1) / kGrain);
    m_blockRuns.assign(blocks + 1, 0);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t blk) {
      std::uint32_t runs = 0;
      for (std::uint64_t c = blk * kGrain, e = std::min<std::uint64_t>(cells, (blk + 1) * kGrain); c < e; ++c)
        runs += m_cellStart[c + 1] - m_cellStart[c] >= 2;
      m_blockRuns[blk + 1] = runs;
    });
    const std::uint32_t runs = inclusiveScan(m_blockRuns.data(), blocks + 1);
    m_runCell.resize(runs);
    m_runStart.resize(runs);
    m_runLength.resize(runs);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t blk) {
      std::uint32_t r = m_blockRuns[blk];
      for (std::uint64_t c = blk * kGrain, e = std::min<std::uint64_t>(cells, (blk + 1) * kGrain); c < e;
           ++c) {
        const std::uint32_t m = m_cellStart[c + 1] - m_cellStart[c];
        if (m >= 2) {
          m_runCell[r] = std::uint32_t(c);
          m_runStart[r] = m_cellStart[c];
          m_runLength[r] = m;
          ++r;
        }
      }
    });
  } else {
    // Stage 5, sparse grid (far-apart clusters, thin scenes): sort explicit keys.
    m_cellStart.clear();
    m_offsets.resize(n + 1);
    m_offsets[0] = 0;
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
      m_offsets[i + 1] = std::uint32_t(cellRange(m_box[i], g).count());
    });
    inclusiveScan(m_offsets.data(), n + 1);
    m_keys.resize(keys);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          std::uint64_t o = m_offsets[i];
                          forEachCell(cellRange(m_box[i], g), g,
                                      [&](std::uint32_t c) { m_keys[o++] = (std::uint64_t(c) << 32) | i; });
                        }
                      });
    tbb::parallel_sort(m_keys.begin(), m_keys.end());
    for (std::uint64_t i = 0; i < keys;) {
      std::uint64_t j = i + 1;
      const std::uint64_t cell = m_keys[i] >> 32;
      while (j < keys && (m_keys[j] >> 32) == cell) ++j;
      if (j - i >= 2) {
        m_runCell.push_back(std::uint32_t(cell));
        m_runStart.push_back(std::uint32_t(i));
        m_runLength.push_back(std::uint32_t(j - i));
      }
      i = j;
    }
    m_sorted.resize(keys);
    for (std::uint64_t i = 0; i < keys; ++i) m_sorted[i] = std::uint32_t(m_keys[i]);
  }
  // Stage 6: exclusive prefix sum of the per-run pair counts.
  const std::size_t runs = m_runCell.size();
  m_runPrefix.resize(runs + 1);
  m_runPrefix[0] = 0;
  tbb::parallel_for(std::size_t(0), runs,
                    [&](std::size_t r) { m_runPrefix[r + 1] = gpucol_pair_count(m_runLength[r]); });
  inclusiveScan(m_runPrefix.data(), runs + 1);
}

void CpuPairFinder::testRuns(const PairFinderOptions& options, const Grid& g) {
  const std::uint64_t total = m_runPrefix.back();
  m_stats.candidates += total;
  const std::uint64_t chunk = chunkSize(total);
  const std::uint64_t chunks = total == 0 ? 0 : (total + chunk - 1) / chunk;
  const bool bitMask = options.output == PairOutput::BitMask;
  const bool newton = options.mappingSqrt == MappingSqrt::Newton;
  if (bitMask) m_bits.assign((total + 63) / 64, 0);
  const std::size_t firstChunk = takeChunks(chunks);

  // Stage 7: run and (i, j) of candidate k.
  auto locate = [&](std::uint64_t k, std::size_t& run, gpucol_u64& i, gpucol_u64& j) {
    run = std::size_t(std::upper_bound(m_runPrefix.begin(), m_runPrefix.end(), k) - m_runPrefix.begin()) - 1;
    const std::uint64_t local = k - m_runPrefix[run];
    if (newton)
      gpucol_pair_from_index_newton(m_runLength[run], local, &i, &j);
    else
      gpucol_pair_from_index(m_runLength[run], local, &i, &j);
  };
  // Stages 8–9 for one candidate.
  auto accept = [&](std::size_t run, const LocalBox& a, const LocalBox& b) {
    // Same touching-counts test as aabbOverlap, on the local copies; without short-circuit branches, which
    // a CPU mispredicts on most candidates (perf showed the short-circuit form bound by those branches).
    const int overlap = int(a.lo[0] <= b.hi[0]) & int(b.lo[0] <= a.hi[0]) & int(a.lo[1] <= b.hi[1]) &
                        int(b.lo[1] <= a.hi[1]) & int(a.lo[2] <= b.hi[2]) & int(b.lo[2] <= a.hi[2]);
    if (!overlap) return false;
    const std::uint32_t cx = cellOf(std::max(a.lo[0], b.lo[0]), g.origin[0], g.invCell, g.dims[0]);
    const std::uint32_t cy = cellOf(std::max(a.lo[1], b.lo[1]), g.origin[1], g.invCell, g.dims[1]);
    const std::uint32_t cz = cellOf(std::max(a.lo[2], b.lo[2]), g.origin[2], g.invCell, g.dims[2]);
    return (std::uint64_t(cz) * g.dims[1] + cy) * g.dims[0] + cx == m_runCell[run] && passesFilter(a, b);
  };

  // Stages 8-9 for a whole run of kLocalRunMin to kLocalRunMax boxes, four candidates at a time.
  auto testWholeRun = [&](std::size_t run, std::vector<std::uint64_t>& out) {
    const std::uint32_t* local = m_sorted.data() + m_runStart[run];
    auto boxAt = [&](std::uint32_t e) -> const LocalBox& { return m_box[local[e] & kEntryBox]; };
    forEachOverlapInRun(m_runLength[run], boxAt, [&](std::uint32_t i, std::uint32_t j) {
      if (accept(run, boxAt(i), boxAt(j))) out.push_back(makePairKey(boxAt(i).slot, boxAt(j).slot));
    });
  };

  tbb::parallel_for(std::uint64_t(0), chunks, [&](std::uint64_t c) {
    const std::uint64_t k0 = c * chunk;
    const std::uint64_t k1 = std::min(total, k0 + chunk);
    std::size_t run = 0;
    gpucol_u64 i = 0, j = 0;
    locate(k0, run, i, j);
    auto& out = m_chunkPairs[firstChunk + c];
    out.clear();
    // Candidates k0..k1 walk the runs row by row: (i, j) with j > i, box i held while j runs along the row.
    for (std::uint64_t k = k0; k < k1;) {
      const std::uint32_t m = m_runLength[run];
      const std::uint32_t* local = m_sorted.data() + m_runStart[run];
      if (!bitMask && j == 1 && m >= kLocalRunMin && m <= kLocalRunMax && m_runPrefix[run + 1] <= k1) {
        testWholeRun(run, out);
        k = m_runPrefix[run + 1];
        ++run;
        continue;
      }
      while (i + 1 < m && k < k1) {
        const LocalBox ba = m_box[local[i] & kEntryBox];
        const std::uint64_t row =
            std::min<std::uint64_t>(m - j, k1 - k);  // this row's candidates in the chunk
        for (std::uint64_t t = 0; t < row; ++t) {
          const LocalBox& bb = m_box[local[j + t] & kEntryBox];
          if (!accept(run, ba, bb)) continue;
          if (bitMask)
            m_bits[(k + t) >> 6] |= std::uint64_t(1) << ((k + t) & 63);  // 64-aligned chunks: no shared word
          else
            out.push_back(makePairKey(ba.slot, bb.slot));
        }
        k += row;
        j += row;
        if (j == m) {
          ++i;
          j = i + 1;
        }
      }
      if (i + 1 >= m) {
        ++run;
        i = 0;
        j = 1;
      }
    }
    if (bitMask) {
      // Stage 10, bit mask: decode the set bits of this chunk back to pairs through the mapping function.
      for (std::uint64_t w = k0 >> 6; w < (k1 + 63) >> 6; ++w) {
        std::uint64_t bits = m_bits[w];
        while (bits) {
          const std::uint64_t k = (w << 6) + std::uint64_t(__builtin_ctzll(bits));
          bits &= bits - 1;
          std::size_t r = 0;
          gpucol_u64 a = 0, b = 0;
          locate(k, r, a, b);
          const std::uint32_t* local = m_sorted.data() + m_runStart[r];
          out.push_back(makePairKey(m_box[local[a] & kEntryBox].slot, m_box[local[b] & kEntryBox].slot));
        }
      }
    }
  });
}

void CpuPairFinder::testHuge(const ProxyArrays& p, const Grid& g) {
  // Stage 3: every huge box against the other huge boxes (each pair once, from the earlier in m_huge) and
  // against the binned boxes: either one by one, or, when it covers few enough cells of a dense grid,
  // through those cells' entries with stage 9's rule (a binned box is in every cell it overlaps, so the
  // cell of the overlap's min corner holds it; the huge box's clamped range covers that cell too); inside
  // the range, by the entries' home bit alone.
  const std::size_t h = m_huge.size();
  if (h == 0) return;
  const std::size_t firstChunk = takeChunks(h);
  const double keysPerCell = m_denseBuilt ? double(m_sorted.size()) / double(m_cellStart.size() - 1) : 0.0;
  std::vector<std::uint64_t> tested(h, 0);
  tbb::parallel_for(std::size_t(0), h, [&](std::size_t hi) {
    const std::uint32_t sh = m_huge[hi];
    const LocalBox a = boxOf(p, sh);
    auto& out = m_chunkPairs[firstChunk + hi];
    out.clear();
    tested[hi] = hugeAgainstLaterHuge(p, m_huge, hi, out);
    const CellRange range = cellRange(a, g);
    if (m_denseBuilt && double(range.count()) * (1.0 + keysPerCell) < double(m_binned.size())) {
      // A cell strictly inside the huge box's cell range on every axis (range.lo < x < range.hi, and so on)
      // needs no test: cellOf is monotone, so every box listed there overlaps the huge box, and the overlap's
      // min corner lies in this cell exactly when the listed box's home cell (its min corner's) is this one,
      // which the entry's kHomeEntry bit says without loading the box.
      for (std::uint32_t z = range.lo[2]; z <= range.hi[2]; ++z)
        for (std::uint32_t y = range.lo[1]; y <= range.hi[1]; ++y) {
          const std::uint64_t row = (std::uint64_t(z) * g.dims[1] + y) * g.dims[0];
          const bool innerRow = z > range.lo[2] && z < range.hi[2] && y > range.lo[1] && y < range.hi[1];
          for (std::uint32_t x = range.lo[0]; x <= range.hi[0]; ++x) {
            const std::uint32_t c = std::uint32_t(row + x);
            const std::uint32_t begin = m_cellStart[c], end = m_cellStart[c + 1];
            tested[hi] += end - begin;
            if (innerRow && x > range.lo[0] && x < range.hi[0]) {
              for (std::uint32_t e = begin; e < end; ++e) {
                if (!(m_sorted[e] & kHomeEntry)) continue;
                const LocalBox& b = m_box[m_sorted[e] & kEntryBox];
                if (passesFilter(a, b)) out.push_back(makePairKey(sh, b.slot));
              }
              continue;
            }
            for (std::uint32_t e = begin; e < end; ++e) {
              const LocalBox& b = m_box[m_sorted[e] & kEntryBox];
              if (boxesOverlap(a, b) && overlapCell(a, b, g) == c && passesFilter(a, b))
                out.push_back(makePairKey(sh, b.slot));
            }
          }
        }
    } else {
      for (std::uint32_t s : m_binned)
        if (boxesOverlap(a, boxOf(p, s)) && passesFilter(p, sh, s)) out.push_back(makePairKey(sh, s));
      tested[hi] += m_binned.size();
    }
  });
  for (std::uint64_t t : tested) m_stats.candidates += t;
}

void CpuPairFinder::gather(std::vector<std::uint64_t>& pairs) {
  std::vector<std::size_t> offset(m_chunksUsed + 1, 0);
  for (std::size_t c = 0; c < m_chunksUsed; ++c) offset[c + 1] = offset[c] + m_chunkPairs[c].size();
  pairs.resize(offset.back());
  tbb::parallel_for(std::size_t(0), m_chunksUsed, [&](std::size_t c) {
    std::copy(m_chunkPairs[c].begin(), m_chunkPairs[c].end(), pairs.begin() + std::ptrdiff_t(offset[c]));
  });
}

/// Whether the options let a search be done in slabs before its grid is known (searchSlabs has the rest).
bool slabsMayServe(const PairFinderOptions& options) {
  return options.slabTiling != SlabTiling::Off && options.output == PairOutput::Compacted;
}

bool CpuPairFinder::surveyWanted(const PairFinderOptions& options, float& cell, int& axis) const {
  // A kept grid serves the next search when few proxies move (stage 11), which reads no box but the moved.
  if (!(m_lastSizedCell > 0.0f) || m_kept || options.cellSizeRule != CellSizeRule::Size) return false;
  cell = m_lastSizedCell;
  axis = slabsMayServe(options) ? m_slabs.axis() : -1;
  return true;
}

void CpuPairFinder::grid(const ProxyArrays& p, const PairFinderOptions& options, bool keepGrid,
                         std::vector<std::uint64_t>& pairs) {
  m_stats.usedGrid = true;
  m_denseBuilt = false;
  StageClock clock;
  // Read in place, every pass over the boxes walks Bullet's proxies: the grid choice keeps their extents
  // along the slab axis of the last plan (axes rarely change between steps) for this step's plan.
  m_keptExtents.axis = p.minX == nullptr && slabsMayServe(options) ? m_slabs.axis() : -1;
  m_keptExtents.bySlot = false;
  // The binned and huge lists hold every active slot: the binned list is written over the active list.
  m_binned.swap(m_active), std::vector<std::uint32_t>().swap(m_active);
  bool surveyTaken = false;
  Grid home;  // the grid of a search by home cell, when chooseGrid finds one (home.cell > 0)
  const Grid g = chooseGrid(p, m_binned, options, m_extent, m_binned, m_huge, &m_keptExtents, p.survey,
                            &surveyTaken, slabsMayServe(options) ? &home : nullptr);
  m_stats.surveyTaken = surveyTaken;
  // The survey's extents are by slot; the plan takes them as it takes the grid choice's own.
  if (surveyTaken && m_keptExtents.axis >= 0 && p.survey->extents.axis == m_keptExtents.axis)
    std::swap(m_keptExtents, p.survey->extents);
  m_lastSizedCell = options.cellSizeRule == CellSizeRule::Size ? g.sizedCell : 0.0f;
  notePeak();
  std::vector<float>().swap(m_extent);  // chooseGrid's scratch
  m_stats.hugeProxies = std::uint32_t(m_huge.size());
  const std::size_t binnedCount = m_binned.size();
  m_keptGrid = g;
  m_stats.cellSize = g.cell;
  for (int a = 0; a < 3; ++a) m_stats.dims[a] = g.dims[a];
  m_stats.chooseMs = clock.lap();
  const bool slabs = searchSlabs(p, options, g, home);
  // Unused when the plan did not take them.
  std::vector<std::uint32_t>().swap(m_keptExtents.lo), std::vector<std::uint32_t>().swap(m_keptExtents.hi);
  if (!slabs) {
    m_isBinned.assign(p.count, 0);
    for (std::uint32_t s : m_binned) m_isBinned[s] = 1;
    if (!m_binned.empty()) {
      binSorted(p, g);
      m_stats.binMs = clock.lap();
      testRuns(options, g);
      m_stats.testMs = clock.lap();
    }
    testHuge(p, g);
    m_stats.hugeMs = clock.lap();
  } else {
    clock.lap();  // the slab search timed its own parts
  }
  if (m_coded) {
    // Stage 10 by bucket: sorted and coded straight from the slabs' buckets.
    m_buckets.packInto(*m_codedOutput, !PackedPairs::worthCoding(m_buckets.size(), p.count));
    notePeak();
    m_buckets.release();
  } else {
    gather(pairs);
    notePeak();
    std::vector<std::vector<std::uint64_t>>().swap(m_chunkPairs);  // gathered into `pairs`
    m_chunksUsed = 0;
    // Stage 10: one order whatever the chunking, threads or device.
    sortPairs(pairs, m_sortScratch, m_sortOffsets, slotBitsFor(p.count));
  }
  m_stats.sortMs = clock.lap();
  if (slabs && keepGrid) {
    notePeak();
    std::vector<std::uint64_t>().swap(m_sortScratch), std::vector<std::size_t>().swap(m_sortOffsets);
    binKeptGrid(p, g, binnedCount);
    m_stats.binMs += clock.lap();
  }
}

bool CpuPairFinder::searchSlabs(const ProxyArrays& p, const PairFinderOptions& options, const Grid& g,
                                const Grid& home) {
  // The whole-grid search serves what slabs cannot: the bit mask (indexed by global candidate numbers) and
  // sparse grids (a slab of a sparse grid would have mostly empty cells). A home grid is dense enough by
  // chooseGrid's choice, and its slabs copy each box once, so the limit on binned boxes is not for them.
  const bool always = options.slabTiling == SlabTiling::Always;
  const bool byHome = home.cell > 0.0f && (always || m_binned.size() >= kHomeCellsFrom);
  const bool gridServes = g.cells() <= denseCellLimit(m_binned.size()) &&
                          !(options.slabTiling == SlabTiling::Auto && m_binned.size() > kMaxSlabBoxes);
  if (!slabsMayServe(options) || m_binned.empty() || !(byHome || gridServes)) return false;
  StageClock clock;
  // A home order that the whole-grid search would not reuse (binSorted) is not held beside the slabs.
  const auto releaseHomeOrder = [&] {
    for (auto* v : {&m_homeOrder, &m_homePos}) std::vector<std::uint32_t>().swap(*v);
  };
  if (!homeOrderFits(m_binned.size())) releaseHomeOrder();
  const bool small = m_binned.size() < kAnySlabsBelow;
  const std::uint32_t minSlabs = always || small ? 1 : kMinSlabs;
  // By home cell where the boxes are of about one size (the plan's own grid), else in every cell they overlap.
  const bool planned =
      (byHome && m_slabs.plan(p, m_binned, home, options.slabBoxes, minSlabs, options.slabBoxReading,
                              &m_keptExtents, true)) ||
      (gridServes &&
       m_slabs.plan(p, m_binned, g, options.slabBoxes, minSlabs, options.slabBoxReading, &m_keptExtents));
  if (!planned) return false;
  const Grid& searched = m_slabs.byHomeCell() ? home : g;
  // The home order serves the whole-grid search's locality only; a slab search does not keep it up to date.
  releaseHomeOrder();
  notePeak();
  std::vector<std::uint32_t>().swap(m_binned);  // the slab lists hold every binned box
  m_stats.binMs = clock.lap();
  // Coded output: each slab's pairs go into the buckets as the slab is done, not into a list of its own.
  m_coded = m_codedOutput != nullptr && PairBuckets::fits(p.count);
  if (m_coded) m_buckets.reset(p.count, m_slabs.outputs(m_huge.size()));
  const std::size_t first = m_coded ? 0 : takeChunks(m_slabs.outputs(m_huge.size()));
  const SlabSearchCounts counts =
      m_slabs.search(p, m_huge, searched, m_chunkPairs, first, m_coded ? &m_buckets : nullptr);
  m_stats.testMs = clock.lap();
  m_stats.slabs = std::uint32_t(m_slabs.slabs());
  m_stats.slabAxisKept = m_slabs.tookKeptExtents();
  m_stats.slabBoxesInPlace = m_slabs.readsInPlace();
  m_stats.homeCells = m_slabs.byHomeCell();
  m_stats.wideBoxes = std::uint32_t(std::min<std::uint64_t>(counts.wide, UINT32_MAX));
  if (m_stats.homeCells) {
    m_stats.cellSize = home.cell;
    for (int a = 0; a < 3; ++a) m_stats.dims[a] = home.dims[a];
  }
  m_stats.keys = counts.keys;
  m_stats.candidates += counts.candidates;
  notePeak();
  m_slabs.release();  // only the per-slab pair lists are left to gather
  return true;
}

void CpuPairFinder::binKeptGrid(const ProxyArrays& p, const Grid& g, std::size_t binnedCount) {
  // Stage 11 after a slab search, whose cells are gone: the kept grid's cells and entries alone (no box
  // copies, runs or packed ranges: the incremental search reads boxes where they are), by a counting sort of
  // the binned boxes. Its entries name them by their place in the binned list, listed again here (the
  // active slots less the huge ones: the slab lists held them during the search), which becomes the home
  // order; that order is by slot, not by home cell, so the next whole-grid search renews it. A grid of more
  // entries than 32-bit positions reach, or a sparse one (after a search by home cell on a grid of its own),
  // is not kept (the slabs found its pairs; the next search is a full one).
  if (binnedCount > kEntryBox || g.cells() > denseCellLimit(binnedCount)) return;
  std::vector<std::uint32_t> huge = m_huge;
  std::sort(huge.begin(), huge.end());
  m_homeOrder.clear();
  m_homeOrder.reserve(binnedCount);
  for (std::uint32_t s = 0; s < p.count; ++s)
    if ((p.flags[s] & kProxyActive) && !std::binary_search(huge.begin(), huge.end(), s))
      m_homeOrder.push_back(s);
  if (m_stats.homeCells) {
    // The slabs counted one entry per box on their own grid: the kept grid's entries are counted here.
    m_stats.keys = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, m_homeOrder.size(), kGrain), std::uint64_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t sum) {
          for (std::size_t i = r.begin(); i != r.end(); ++i)
            sum += cellRange(boxOf(p, m_homeOrder[i]), g).count();
          return sum;
        },
        std::plus<std::uint64_t>());
  }
  if (m_stats.keys > std::numeric_limits<std::uint32_t>::max()) {
    std::vector<std::uint32_t>().swap(m_homeOrder);
    return;
  }
  m_homeOrderAge = kHomeOrderSteps;
  m_sorted.resize(m_stats.keys);  // counted by the slab holding each entry's cell, or above
  countingSort(
      m_homeOrder.size(), g.cells(), m_cellStart,
      [&](std::size_t i, auto&& f) { forEachCell(cellRange(boxOf(p, m_homeOrder[i]), g), g, f); },
      [&](std::size_t i, std::uint32_t to, std::uint32_t) { m_sorted[to] = std::uint32_t(i); });
  m_denseBuilt = true;
  notePeak();
}

std::size_t CpuPairFinder::scratchBytes() const {
  std::size_t bytes = 0;
  bytes +=
      m_active.capacity() * 4 + m_binned.capacity() * 4 + m_huge.capacity() * 4 + m_extent.capacity() * 4;
  bytes += m_cellStart.capacity() * 4 + m_keys.capacity() * 8 + m_sorted.capacity() * 4;
  bytes += m_box.capacity() * sizeof(LocalBox) + m_homeKeys.capacity() * 8 + m_homeOrder.capacity() * 4 +
           m_homePos.capacity() * 4 + m_isBinned.capacity() + m_packed.capacity() * sizeof(PackedCells);
  bytes += m_unchanged.capacity() + m_keptHuge.capacity() * 4 + m_lastPairs.bytes() + m_moved.capacity() * 4 +
           m_movedKeys.capacity() * 8 + m_sortScratch.capacity() * 8 +
           m_sortOffsets.capacity() * sizeof(std::size_t);
  bytes += m_runCell.capacity() * 4 + m_runStart.capacity() * 4 + m_runLength.capacity() * 4;
  bytes += m_runPrefix.capacity() * 8 + m_bits.capacity() * 8 + m_blockRuns.capacity() * 4 +
           m_offsets.capacity() * 4;
  for (const auto& c : m_chunkPairs) bytes += c.capacity() * 8;
  bytes += m_buckets.bytes();
  return bytes + (m_keptExtents.lo.capacity() + m_keptExtents.hi.capacity()) * 4 + m_slabs.bytes();
}

}  // namespace

void PairFinder::findCodedPairs(const ProxyArrays& proxies, const PairFinderOptions& options,
                                PackedPairs& pairs) {
  std::vector<std::uint64_t> keys;
  findPairs(proxies, options, keys);
  if (PackedPairs::worthCoding(keys.size(), proxies.count))
    pairs.assign(keys);
  else
    pairs.adopt(std::move(keys));
}

std::unique_ptr<PairFinder> makeCpuPairFinder() {
  return std::make_unique<CpuPairFinder>();
}



namespace detail {
namespace {
std::atomic<int>& injectedOpenClFailures() {
  static std::atomic<int> count{0};
  return count;
}
}  // namespace

void failNextOpenClSearches(int count) { injectedOpenClFailures() = count; }

bool takeInjectedOpenClFailure() {
  int left = injectedOpenClFailures().load();
  while (left > 0 && !injectedOpenClFailures().compare_exchange_weak(left, left - 1)) {
  }
  return left > 0;
}
}  // namespace detail

}  // namespace gpucol
