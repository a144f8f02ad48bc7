#pragma once
// GridBroadphase's state (GridBroadphase::Impl), shared by the files of its concepts: the proxies
// (grid_proxy_storage.cpp), the scan that gives the pair finders their view of them (grid_proxy_scan.cpp), the
// step and its backend choice (grid_broadphase.cpp), the pair cache kept in sync (grid_pair_cache_sync.cpp),
// and the queries with their index (grid_broadphase_queries.cpp).
#include <LinearMath/btAabbUtil2.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "gpucol/grid_broadphase.h"
#include "bullet/grid_broadphase_options.h"
#include "broadphase/grid_choice.h"
#include "broadphase/grid_pair_finder.h"
#include "broadphase/grown_box_pairs.h"
#include "broadphase/quiet_boxes.h"
#include "broadphase/packed_pairs.h"
#include "broadphase/pair_diff.h"
#include "broadphase/query_grid.h"
#include "bullet/measured_backend_choice.h"
#include "bullet/warn_once.h"
#include "memory/reserved_blocks.h"
#include "opencl/host/opencl_started.h"

namespace gpucol {

/// True when `cache` accepts a pair exactly when Bullet's group/mask test does (no overlap filter callback, and
/// one of Bullet's own caches, whose needsBroadphaseCollision is that test): the pair finder then applies the
/// test itself. Otherwise (a user's callback, which may accept pairs the masks reject, or another cache) the
/// finder reports every overlapping pair and the cache decides each.
inline bool cacheFiltersByGroupAndMask(btOverlappingPairCache& cache) {
  if (cache.getOverlapFilterCallback() != nullptr) return false;
  return dynamic_cast<btHashedOverlappingPairCache*>(&cache) != nullptr ||
         dynamic_cast<btSortedOverlappingPairCache*>(&cache) != nullptr;
}

/// Proxies per parallel task of the per-step scan of the proxies' filters.
constexpr std::uint32_t kScanGrain = 16384;

/// Proxies per storage block: 2^8 proxies of 56 bytes, 14 KiB (small scenes do not pay for a large last
/// block: 4096 per block held 229 bytes per proxy at 1,000 proxies); a slot's proxy is found by a shift and a
/// mask, and blocks never move, so the addresses Bullet holds stay valid. The blocks lie end to end in one
/// reserved range (memory/reserved_blocks.h) with room for every slot number, so that an OpenCL device
/// sharing the host's memory reads all the boxes in place through one buffer.
constexpr std::uint32_t kBlockBits = 8;
constexpr std::uint32_t kBlockSize = 1u << kBlockBits;
constexpr std::size_t kMaxBlocks = (std::size_t(1) << 32) >> kBlockBits;

/// Bits of Impl::state, per slot.
constexpr std::uint8_t kLive = 1;       // holds a live proxy
constexpr std::uint8_t kMoved = 2;      // box, filter or life changed since the last search
constexpr std::uint8_t kNonFinite = 4;  // box has a NaN or infinite component: hidden from the finder
constexpr std::uint8_t kFreed = 8;      // destroyed since the last search: its pairs already left the cache
constexpr std::uint8_t kOffIndex = 16;  // set or reused since the query index was built (in offIndex)
constexpr std::uint8_t kInverted = 64;  // box has min > max on an axis: hidden from the finder, paired apart
constexpr std::uint8_t kFilterChanged = 32;  // filter changed since the last diff (asked again when a cache's
                                             // own filter decides: diffAndUpdateCache)

/// Queries (rayTest, aabbTest) test every proxy below this many live proxies: the index's cells and the
/// sort of its candidates cost more than a scan of so few boxes.
constexpr std::uint32_t kQueryIndexMinProxies = 512;
/// The query index is built by the query that follows this many scans since the boxes last changed, about
/// what building it costs in scans (gpucol-bench queries prints the ratio): a scene that queries less pays
/// only scans, and one that queries more never pays more than about twice the cheaper of the two (the
/// ski-rental rule).
constexpr std::uint32_t kScansBeforeIndex = 10;
/// The index is dropped once more than this share of its boxes moved since it was built (the moved ones are
/// tested one by one by every query).
constexpr std::uint32_t kOffIndexShare = 8;  // 1/8
/// A query's candidates cost about this many proxies of a scan each (gathered, sorted, tested at random).
constexpr std::uint32_t kScanPerCandidate = 4;
/// What building a larger scene's quiet boxes takes at its peak per box beyond the boxes it keeps, a little
/// more than measured (19-25 bytes, QueryGrid::buildPeakBytes): the query grid's cells, entries and places,
/// its build's lists, and the list of boxes.
constexpr std::size_t kQuietBuildBytesPerBox = 32;
/// An index that answered this many queries before the boxes moved it away marks a world that queries every
/// frame: the next index is built by the first query after a change instead of after kScansBeforeIndex scans.
constexpr std::uint64_t kQueriesOfABusyIndex = 64;
/// A query's candidate list starts with room for this many: a short ray names about 50 in a uniform cloud,
/// and growing the list from empty copied it several times.
constexpr std::size_t kQueryCandidatesReserved = 256;

/// A proxy with its slot in the per-slot arrays (the slot fits the base class's tail padding: 56 bytes).
struct GridProxy : btBroadphaseProxy {
  std::uint32_t slot = 0;
};
static_assert(std::is_trivially_destructible<GridProxy>::value, "proxy blocks are freed without destructors");

/// x as a float no greater (down) or no less than x: a float box that holds a double-precision Bullet's box.
inline float floatToward(btScalar x, bool down) {
  float f = float(x);
  if (down ? btScalar(f) > x : btScalar(f) < x)
    f = std::nextafter(f, down ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity());
  return f;
}

/// A float box holding the proxy's (the proxy's own when Bullet's scalars are floats).
inline BoxCorners floatBoxHolding(const btBroadphaseProxy& p) {
  BoxCorners b;
  for (int a = 0; a < 3; ++a) b.lo[a] = floatToward(p.m_aabbMin[a], true), b.hi[a] = floatToward(p.m_aabbMax[a], false);
  return b;
}

/// The finders read the proxies' boxes in place as floats (BoxRecords), so only where Bullet is built in single
/// precision; otherwise every finder gets float copies.
constexpr bool kProxyBoxesAreFloats = std::is_same<btScalar, float>::value;
/// The bounds of no box, for the survey's running min and max.
constexpr float kFloatMax = std::numeric_limits<float>::max();

/// The finder's view of the slots, filled before each search and released after it: a flags byte and a
/// moved byte per slot and, for a finder that does not read the boxes from the proxies
/// (PairFinder::readsBoxRecords), a copy of every box as six float arrays (24 more bytes per slot). Not
/// initialised: the fills write every slot.
struct ViewBuffer {
  std::unique_ptr<std::uint8_t[]> marks;  // flags of every slot, then moved
  std::unique_ptr<float[]> axes;          // min x, y, z, then max x, y, z of every slot
  std::size_t slots = 0;
  float* axis(int a) { return axes.get() + std::size_t(a) * slots; }
  std::uint8_t* flags() { return marks.get(); }
  std::uint8_t* moved() { return marks.get() + slots; }
  void allocate(std::size_t n, bool withAxes) {
    if (n != slots || !marks) marks.reset(new std::uint8_t[2 * n]), axes.reset();
    slots = n;
    if (withAxes) allocateAxes();
  }
  void allocateAxes() {
    if (!axes) axes.reset(new float[6 * slots]);
  }
  std::size_t bytes() const { return (marks ? 2 * slots : 0) + (axes ? 6 * sizeof(float) * slots : 0); }
  void release() {
    marks.reset(), axes.reset();
    slots = 0;
  }
};

struct GridBroadphase::Impl {
  Config config;
  GridBroadphaseOptions internalOptions;  // tests and gpucol-bench (grid_broadphase_options.h)
  GridBroadphaseStats stats;
  btOverlappingPairCache* pairCache = nullptr;
  std::unique_ptr<btHashedOverlappingPairCache> ownedCache;

  // Held between steps: the proxies (the only copy of each box), the filters as of the last scan (a change
  // is a move), a state byte per slot, the free slots and the last step's pairs.
  std::unique_ptr<ReservedBlocks> blocks;  // made with the first proxy
  std::uint32_t slotCount = 0;
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> state;
  const PairFinder* lastFinder = nullptr;  // the finder of the last search (kMoved is relative to it)
  std::vector<std::uint32_t> freeSlots;    // reusable now
  std::vector<std::uint32_t> pendingFree;  // freed since the last search: reused only after it
  // A box with a NaN or infinite component gets no pairs, as Bullet's own updateAabbs drops an overflowing
  // box: the finder's cell size, grid bounds and cell indices would turn NaN (or a float-to-int conversion of
  // NaN) and spread to every proxy. Such a proxy is hidden from the finder until its box is finite again.
  std::uint32_t nonFiniteCount = 0;
  std::uint32_t invertedCount = 0;  // live proxies with kInverted
  bool nonFiniteChanged = false;  // a proxy entered or left that state: the next search is a full one
  // Whether the finder applies Bullet's group/mask test itself (cacheFiltersByGroupAndMask), and what the last
  // search did: a change makes the next search a full one.
  bool finderFilters = true, lastFinderFilters = true;
  // A live proxy's filter changed since the last diff (its slots carry kFilterChanged).
  std::atomic<bool> filtersChanged{false};
  // Every slot's "accept all" filter (-1), the finder's group and mask while the cache's own filter decides.
  std::vector<std::int32_t> acceptAll;
  std::uint32_t liveCount = 0;
  std::uint32_t staticCount = 0;  // live proxies with the static flag (GridBroadphaseStats::staticProxies)
  int nextUniqueId = 0;
  bool dirty = true;

  std::unique_ptr<PairFinder> cpuFinder = makeCpuPairFinder();
  std::unique_ptr<PairFinder> openClFinder;
  bool openClTried = false;
  // Backend::Auto's choice by the number of live proxies, from this broad phase's own search times. Auto
  // measures only when the chosen OpenCL device is a GPU: on PoCL's CPU device the CPU path was faster at
  // every size measured, 1K to 1M boxes (docs/measured-results.md, "Broad phase"), and Auto never starts OpenCL for it.
  MeasuredBackendChoice autoChoice;
  bool autoMeasuring = false;  // the last search was one of autoChoice's measured calls
  // The finder's result of the last search (sorted keys, coded: a pile holds several per proxy) and, of
  // those, the ones the cache's filter refused (sorted): the cache holds `current` less `refused`.
  PackedPairs current;
  std::vector<std::uint64_t> refused;

  // What the last CPU search keeps for the steps after it, while no proxy comes or goes and no filter
  // changes: a small scene the pairs of its grown boxes (GrownBoxPairs), tested instead of a search while
  // every box stays inside its grown box; a larger scene at rest its boxes with their slacks (QuietBoxes):
  // while every box stays within its slack, no pair changed and the step searches nothing. What did not last
  // one step makes the next ones wait (grownWait searches, doubling up to kGrownWaitMax), so scenes that keep
  // moving do not pay for building them.
  GrownBoxPairs grown;
  QuietBoxes quiet;
  std::uint32_t grownReuses = 0;  // steps answered from what was kept since it was built
  std::uint32_t grownWait = 0, grownWaitLeft = 0;
  static constexpr std::uint32_t kGrownWaitMax = 64;
  std::vector<std::uint64_t> grownFound;  // scratch of a step answered from the list

  // The query index (broadphase/query_grid.h), built by a query when due and dropped when too many boxes
  // changed; the proxies changed since it was built are tested by every query. indexReady is set with
  // release order once the index is complete, so concurrent queries read it without the lock.
  QueryGrid queryGrid;
  std::vector<std::uint32_t> offIndex;
  std::uint32_t indexedProxies = 0;
  // A box that moves is filed again where it now is (QueryGrid::refile) when the index can; otherwise it is
  // tested by every query (offIndex). indexBoxes holds the filed boxes by slot (slots not filed hold a box
  // that holds nothing).
  std::vector<BoxCorners> indexBoxes;
  std::uint64_t indexedAtBuild = 0;   // queryIndexed when the index was built
  std::uint64_t lastIndexQueries = 0;  // queries the last dropped index answered
  std::atomic<bool> indexReady{false};
  std::atomic<std::uint32_t> scansSinceChange{0};
  std::atomic<std::uint64_t> queryScans{0}, queryIndexed{0};
  std::uint64_t indexBuilds = 0;
  std::mutex indexBuild;

  // Scratch of one step, released at its end.
  ViewBuffer view;
  BoxSurvey survey;                  // made by the scan for the CPU finder when the boxes are read in place
  bool surveying = false;            // the scan of this step makes it
  std::vector<std::uint64_t> found;  // this step's keys from a finder that does not code them
  PackedPairs foundCoded;            // this step's keys, coded
  std::vector<std::uint64_t> refusedNow;
  std::vector<std::uint64_t> removedKeys;  // pairs to remove from the cache (sorted)
  std::vector<std::uint64_t> addedKeys;    // pairs to offer to the cache (sorted)

  // The proxies (grid_proxy_storage.cpp).
  GridProxy& proxy(std::uint32_t s) {
    return static_cast<GridProxy*>(blocks->block(s >> kBlockBits))[s & (kBlockSize - 1)];
  }

  const GridProxy& proxy(std::uint32_t s) const {
    return static_cast<const GridProxy*>(blocks->block(s >> kBlockBits))[s & (kBlockSize - 1)];
  }

  /// Blocks of proxies (none before the first proxy).
  std::size_t blockCount() const { return blocks ? blocks->size() : 0; }

  /// Before a slot is appended: the per-slot arrays grow by a quarter, in whole blocks, rather than double
  /// (what push_back does): their spare capacity is held between steps, and doubling left 6,384 empty slots
  /// of 9 bytes at 10,000 proxies (5.7 bytes per proxy). Growing by a quarter still copies each slot a
  /// bounded number of times (about 5) while proxies are created.
  void growSlots() {
    if (state.size() < state.capacity()) return;
    const std::size_t grown = std::max<std::size_t>(1, state.capacity() + state.capacity() / 4);
    const std::size_t slots = (grown + kBlockSize - 1) / kBlockSize * kBlockSize;
    group.reserve(slots), mask.reserve(slots), state.reserve(slots);
  }

  /// A live proxy with a finite box (the ones queries and the finder see).
  bool visible(std::uint32_t s) const { return (state[s] & (kLive | kNonFinite)) == kLive; }

  /// The finder's flags of a proxy with filter group `filterGroup`.
  static std::uint8_t flagsOf(int filterGroup) {
    // Bullet gives static and kinematic objects the StaticFilter group (btCollisionWorld::addCollisionObject)
    // and a mask without it, so that the group/mask test refuses their pairs; they rest between steps.
    return std::uint8_t(kProxyActive | ((filterGroup & btBroadphaseProxy::StaticFilter) ? kProxyStatic : 0));
  }

  /// Notes, as slot s takes the box [lo, hi], whether it is inverted or not finite (each said once).
  void store(std::uint32_t s, const btVector3& lo, const btVector3& hi);

  /// Marks slot s inverted (min > max on an axis) or not: a life change for the finder.
  void setInverted(std::uint32_t s, bool value);

  /// Marks slot s not finite or finite again: hidden from the finder, a life change for it.
  void setNonFinite(std::uint32_t s, bool value);

  /// A vector as the warnings print it.
  static std::string toString(const btVector3& v);

  // The scan and the finders' view (grid_proxy_scan.cpp).
  /// Asks the CPU finder whether it would take a survey of the boxes (BoxSurvey) when they are read in place:
  /// the scan then makes it, reading each box in the proxy whose filter it reads anyway, and the finder's
  /// grid choice reads no proxy (at 100K and 1M boxes that walk cost about as much as the scan itself).
  void prepareSurvey();

  /// Takes each live proxy's filter from the proxy (Bullet code may edit it after creation); with `fill`,
  /// also writes the finder's view of every slot (its boxes too when the view has their arrays: this pass
  /// reads every proxy anyway), makes the survey when one was prepared, and clears the kMoved bits (the view
  /// carries them). In parallel: each slot is written by one task only. Returns true when a filter changed.
  bool scan(bool fill);

  /// Frees the survey (the finder took its extents when it used them).
  void releaseSurvey();

  /// Where each slot's box lies in its proxy (the caller checks kProxyBoxesAreFloats).
  BoxRecords boxRecords() const;

  /// Float copies of every slot's box into six arrays of slotCount (zero for slots without a live proxy), in
  /// parallel.
  void copyBoxes(float* const axis[6]) const;

  /// The finder's view of the filled buffer (consumes nonFiniteChanged): the boxes in the proxies when
  /// `readsRecords`, else in the view's arrays (a copy less than half the proxies' size, which took 24 more
  /// bytes per proxy at the peak and no less time: measurement history), which the scan filled for a
  /// double-precision Bullet.
  ProxyArrays finderView(bool readsRecords);

  // The queries and their index (grid_broadphase_queries.cpp).
  /// A proxy's box was set, or its slot given to a new proxy: the query index no longer knows where it is.
  void boxChanged(std::uint32_t s) {
    if (!indexReady.load(std::memory_order_relaxed)) {
      // Read first: setAabb runs for every moved proxy of a step, and a store on each would dirty the line.
      if (scansSinceChange.load(std::memory_order_relaxed) != 0)
        scansSinceChange.store(0, std::memory_order_relaxed);
      return;
    }
    if (state[s] & kOffIndex) return;
    // Every filed slot's indexBoxes entry stays the float box holding its proxy's (answerFromIndex relies
    // on it): refiled, even where it did not move, or kept aside.
    const BoxCorners now = floatBoxHolding(proxy(s));
    if (s < indexBoxes.size() && queryGrid.refile(s, now.lo, now.hi)) {
      indexBoxes[s] = now;
      return;
    }
    state[s] |= kOffIndex;
    offIndex.push_back(s);
    if (offIndex.size() > indexedProxies / kOffIndexShare + 16) dropQueryIndex();
  }

  /// Drops the query index and its bookkeeping; a later query builds it again when due.
  void dropQueryIndex();

  /// The query index when a query should use it, building it when it is due; nullptr: test every proxy.
  const QueryGrid* queryIndex();

  /// Files every visible proxy in the index, by the float box that holds its box.
  void buildQueryIndex();

  /// Candidates beyond which a query tests every proxy instead: sorting a candidate costs about as much as
  /// testing kScanPerCandidate proxies in a scan.
  std::size_t maxCandidates() const { return slotCount / kScanPerCandidate; }

  /// A query's test run on the boxes the index filed (indexBoxes, which hold the proxies' boxes).
  template <class Test>
  struct FiledTests {
    FiledTests(const Impl& impl, const Test& test) : d(impl), t(test) {}
    CandidateTest bySlot() const {
      return {[](const void* c, std::uint32_t s) {
                const FiledTests& f = *static_cast<const FiledTests*>(c);
                return f.t(f.d.indexBoxes[s]);
              },
              this};
    }
    const Impl& d;
    const Test& t;
  };

  /// A query through the index: `candidates` (any order, repeats allowed) and the proxies kept aside are
  /// tested with `test`, and the visible ones that pass go to `process`, in slot order, once each.
  template <class Test, class Process>
  void answerFromIndex(std::vector<std::uint32_t>& candidates, Test&& test, Process&& process) {
    queryIndexed.fetch_add(1, std::memory_order_relaxed);
    candidates.insert(candidates.end(), offIndex.begin(), offIndex.end());
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    // The index's candidates passed the test on their filed box; with float scalars that box is the
    // proxy's own (boxChanged keeps it so), so only the slots kept aside are tested again.
    for (std::uint32_t s : candidates)
      if (visible(s) && ((kProxyBoxesAreFloats && !(state[s] & kOffIndex)) || test(s))) process(&proxy(s));
  }

  /// A query without the index: every visible proxy is tested, in slot order.
  template <class Test, class Process>
  void answerByScan(Test&& test, Process&& process) {
    queryScans.fetch_add(1, std::memory_order_relaxed);
    for (std::uint32_t s = 0; s < slotCount; ++s)
      if (visible(s) && test(s)) process(&proxy(s));
  }

  // The step (grid_broadphase.cpp).
  /// The pairs of the boxes with min > max (kInverted, hidden from the finder: the grid files a box by its
  /// corners' cells), by Bullet's overlap test against every other visible box, as btDbvtBroadphase finds
  /// them, merged into `foundCoded`. Such boxes are a user's bug, said once by store(); they cost a pass over
  /// every proxy each.
  void addInvertedPairs();

  /// What the last search kept (grown pairs or quiet boxes) no longer answers for the scene.
  void dropKeptSearch();

  /// After a full CPU search, what answers the next steps while boxes move little (`view` is the search's):
  /// a small scene's grown pairs; for a larger one, true when its quiet boxes are due, built by
  /// keepQuietBoxes once the step is done.
  bool keepSearch(const ProxyArrays& view);

  /// At the end of a larger scene's step whose search changed no pair (`pairs` of them: a pile at rest, its
  /// boxes nudged by the solver), its boxes and their slacks for the next steps, where the memory bound leaves
  /// room; built from the proxies once the step's scratch is gone, so that its peak stays below the
  /// search's. Returns the build's peak beyond what it keeps (0: none built).
  std::size_t keepQuietBoxes(std::size_t pairs);

  /// A step of a larger scene whose boxes all stayed within their slacks: no pair changed, so nothing is
  /// searched and the cache keeps its pairs (those its filter refused are offered again, as a search would).
  /// Returns false, having done nothing but drop the quiet boxes, when a filter changed (a full search
  /// follows).
  bool answerQuietly(btDispatcher* dispatcher, GridBroadphaseStats& st);

  /// The end of a step answered from what the last search kept (begun at `start`): the cache is told the
  /// difference to `changed`, the step's pairs when they changed (nullptr: they did not; refused pairs are
  /// then offered again), and the step's stats are set.
  void finishKeptStep(btDispatcher* dispatcher, GridBroadphaseStats& st,
                      const std::vector<std::uint64_t>* changed, std::chrono::steady_clock::time_point start);

  /// A step of a small scene whose boxes all stayed inside their grown boxes: the kept pairs are tested on
  /// the boxes as they are, and the cache is told the difference. Returns false, having done nothing but
  /// drop the list, when a filter changed since (a full search follows).
  bool answerFromGrownPairs(btDispatcher* dispatcher, GridBroadphaseStats& st);

  /// The finder of this search: the configured backend, Backend::Auto's measured choice, or the CPU without
  /// OpenCL.
  PairFinder& chooseFinder(GridBroadphaseStats& st);

  /// The OpenCL finder failed: warned about once, dropped, and never made again for this broad phase (Auto
  /// takes the CPU from now on, as the mesh path does).
  void dropOpenCl(const std::string& why);

  /// The finders' options from the Config and the internal options.
  PairFinderOptions options() const {
    PairFinderOptions o;
    o.bruteForceBelow = config.bruteForceBelow < 0 ? 0u : std::uint32_t(config.bruteForceBelow);
    o.cellSizeRule = internalOptions.densityCellSize ? CellSizeRule::Density : CellSizeRule::Size;
    o.output = internalOptions.bitMaskOutput ? PairOutput::BitMask : PairOutput::Compacted;
    o.mappingSqrt = internalOptions.newtonSqrt ? MappingSqrt::Newton : MappingSqrt::Double;
    o.hugeCellLimit = internalOptions.hugeCellLimit;
    // Boxes read in place ask for the least memory: slabs at every size (at 1M boxes the whole-grid search's
    // own working memory is larger than the copy of the boxes that reading in place saves).
    o.slabTiling = kProxyBoxesAreFloats ? SlabTiling::AnySize : SlabTiling::Auto;
    return o;
  }

  /// Bytes held between steps (GridBroadphaseStats::memoryBytes): proxy blocks, block table, filters, state,
  /// free-slot lists, the last pair list and its refused part, and the finder's kept memory.
  std::size_t heldBytes() const;

  // The pair cache kept in sync (grid_pair_cache_sync.cpp).
  /// The changes from `current` to `foundCoded`, handed to the pair cache; `foundCoded` becomes `current`.
  void diffAndUpdateCache(btDispatcher* dispatcher, GridBroadphaseStats& st);

  /// The removed pairs dropped from a cache with deferred removal, in one pass over it.
  void removeDeferred(btDispatcher* dispatcher);
};

}  // namespace gpucol
