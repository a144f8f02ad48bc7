// gpucol::GridBroadphase: Bullet's side of the grid broad phase. Proxies live in fixed blocks (stable
// addresses) and are the one place a box is kept between steps; the finders read the boxes in the proxies
// (the OpenCL one as it uploads them); where they cannot (a double-precision Bullet), each search copies the
// live boxes as floats into a structure-of-arrays view (broadphase/grid_pair_finder.h) and drops it
// afterwards. Each step's sorted pair list is diffed against the last one so the pair cache only sees
// additions and removals (DESIGN.md, data flow): the diff lists them, then the cache gets them. That list is
// also the pair finder's previous result, which it carries resting pairs over from (no second copy is kept).
#include "gpucol/grid_broadphase.h"

#include "bullet/grid_broadphase_options.h"

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
namespace {

/// True when `cache` accepts a pair exactly when Bullet's group/mask test does (no overlap filter callback, and
/// one of Bullet's own caches, whose needsBroadphaseCollision is that test): the pair finder then applies the
/// test itself. Otherwise (a user's callback, which may accept pairs the masks reject, or another cache) the
/// finder reports every overlapping pair and the cache decides each.
bool cacheFiltersByGroupAndMask(btOverlappingPairCache& cache) {
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
/// What building a larger scene's quiet boxes takes at its peak per box beyond the boxes it keeps, a little
/// more than measured (19-25 bytes, QueryGrid::buildPeakBytes): the query grid's cells, entries and places,
/// its build's lists, and the list of boxes.
constexpr std::size_t kQuietBuildBytesPerBox = 32;
/// A query's candidates cost about this many proxies of a scan each (gathered, sorted, tested at random).
constexpr std::uint32_t kScanPerCandidate = 4;
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
float floatToward(btScalar x, bool down) {
  float f = float(x);
  if (down ? btScalar(f) > x : btScalar(f) < x)
    f = std::nextafter(f, down ? -std::numeric_limits<float>::infinity() : std::numeric_limits<float>::infinity());
  return f;
}

/// A float box holding the proxy's (the proxy's own when Bullet's scalars are floats).
BoxCorners floatBoxHolding(const btBroadphaseProxy& p) {
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

}  // namespace

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
  // every box stays inside its grown box; a large scene its boxes with their slacks (QuietBoxes): while
  // every box stays within its slack, no pair changed and the step searches nothing. What did not last one
  // step makes the next ones wait (grownWait searches, doubling up to kGrownWaitMax), so scenes that keep
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

  static std::uint8_t flagsOf(int filterGroup) {
    // Bullet gives static and kinematic objects the StaticFilter group (btCollisionWorld::addCollisionObject)
    // and a mask without it, so that the group/mask test refuses their pairs; they rest between steps.
    return std::uint8_t(kProxyActive | ((filterGroup & btBroadphaseProxy::StaticFilter) ? kProxyStatic : 0));
  }

  /// Asks the CPU finder whether it would take a survey of the boxes (BoxSurvey) when they are read in place:
  /// the scan then makes it, reading each box in the proxy whose filter it reads anyway, and the finder's
  /// grid choice reads no proxy (at 100K and 1M boxes that walk cost about as much as the scan itself).
  void prepareSurvey() {
    surveying = false;
    float cell = 0.0f;
    int axis = -1;
    if (!kProxyBoxesAreFloats || liveCount < options().bruteForceBelow ||
        !cpuFinder->surveyWanted(options(), cell, axis))
      return;
    survey.cell = cell;
    survey.hugeCellLimit = internalOptions.hugeCellLimit;
    survey.huge.clear();
    survey.extents.axis = axis;
    survey.extents.bySlot = true;
    if (axis >= 0) survey.extents.lo.resize(slotCount), survey.extents.hi.resize(slotCount);
    surveying = true;
  }

  /// Takes each live proxy's filter from the proxy (Bullet code may edit it after creation); with `fill`,
  /// also writes the finder's view of every slot (its boxes too when the view has their arrays: this pass
  /// reads every proxy anyway), makes the survey when one was prepared, and clears the kMoved bits (the view
  /// carries them). In parallel: each slot is written by one task only. Returns true when a filter changed.
  bool scan(bool fill) {
    // Proxies whose static bit flips here (rare: a filter edited on the proxy).
    std::atomic<std::int64_t> staticDelta{0};
    const bool boxes = fill && view.axes;
    float* const lo[3] = {boxes ? view.axis(0) : nullptr, boxes ? view.axis(1) : nullptr,
                          boxes ? view.axis(2) : nullptr};
    float* const hi[3] = {boxes ? view.axis(3) : nullptr, boxes ? view.axis(4) : nullptr,
                          boxes ? view.axis(5) : nullptr};
    std::uint8_t* const flags = view.flags();
    std::uint8_t* const moved = view.moved();
    // The survey: each task's huge slots and the bounds of its other visible boxes, merged below.
    struct SurveyPart {
      std::vector<std::uint32_t> huge;
      float lo[3] = {kFloatMax, kFloatMax, kFloatMax};
      float hi[3] = {-kFloatMax, -kFloatMax, -kFloatMax};
    };
    const bool surveyed = fill && surveying;
    // Made only for a survey: a small scene's step scans for filter changes alone, and its cost shows.
    std::optional<tbb::enumerable_thread_specific<SurveyPart>> parts;
    if (surveyed) parts.emplace();
    std::uint32_t* const extentLo = surveyed ? survey.extents.lo.data() : nullptr;
    std::uint32_t* const extentHi = surveyed ? survey.extents.hi.data() : nullptr;
    const int extentAxis = survey.extents.axis;
    const auto scanRange = [&](const tbb::blocked_range<std::uint32_t>& r, bool changed) {
          SurveyPart* const part = surveyed ? &parts->local() : nullptr;
          for (std::uint32_t s = r.begin(); s != r.end(); ++s) {
            std::uint8_t st = state[s];
            if (st & kLive) {
              const GridProxy& p = proxy(s);
              if (group[s] != p.m_collisionFilterGroup || mask[s] != p.m_collisionFilterMask) {
                const bool wasStatic = flagsOf(group[s]) & kProxyStatic;
                if (wasStatic != bool(flagsOf(p.m_collisionFilterGroup) & kProxyStatic))
                  staticDelta += wasStatic ? -1 : 1;
                group[s] = p.m_collisionFilterGroup;
                mask[s] = p.m_collisionFilterMask;
                st |= kMoved | kFilterChanged;
                filtersChanged = true;
                changed = true;
              }
              if (fill) flags[s] = (st & (kNonFinite | kInverted)) ? 0 : flagsOf(group[s]);
              if (boxes)
                for (int a = 0; a < 3; ++a)
                  lo[a][s] = float(p.m_aabbMin[a]), hi[a][s] = float(p.m_aabbMax[a]);
              if (part && !(st & kNonFinite)) {
                const BoxCorners c{{float(p.m_aabbMin[0]), float(p.m_aabbMin[1]), float(p.m_aabbMin[2])},
                                   {float(p.m_aabbMax[0]), float(p.m_aabbMax[1]), float(p.m_aabbMax[2])}};
                if (extentLo)
                  extentLo[s] = floatBits(c.lo[extentAxis]), extentHi[s] = floatBits(c.hi[extentAxis]);
                if (isHuge(c, survey.cell, survey.hugeCellLimit)) {
                  part->huge.push_back(s);
                } else {
                  for (int a = 0; a < 3; ++a)
                    part->lo[a] = std::min(part->lo[a], c.lo[a]),
                    part->hi[a] = std::max(part->hi[a], c.hi[a]);
                }
              }
            } else if (fill) {
              flags[s] = 0;
              if (boxes)
                for (int a = 0; a < 3; ++a) lo[a][s] = 0.0f, hi[a][s] = 0.0f;
            }
            if (fill) {
              moved[s] = std::uint8_t((st & kMoved) != 0);
              st = std::uint8_t(st & ~kMoved);
            }
            state[s] = st;
          }
          return changed;
    };
    // A small scene's scan on the calling thread: handing one range to the task scheduler costs more.
    const tbb::blocked_range<std::uint32_t> all(0, slotCount, kScanGrain);
    const bool changed = slotCount <= kScanGrain
                             ? scanRange(all, false)
                             : tbb::parallel_reduce(all, false, scanRange, [](bool a, bool b) { return a || b; });
    staticCount = std::uint32_t(std::int64_t(staticCount) + staticDelta.load());
    if (surveyed) {
      survey.huge.clear();
      for (int a = 0; a < 3; ++a) survey.lo[a] = kFloatMax, survey.hi[a] = -kFloatMax;
      for (const SurveyPart& part : *parts) {
        survey.huge.insert(survey.huge.end(), part.huge.begin(), part.huge.end());
        for (int a = 0; a < 3; ++a)
          survey.lo[a] = std::min(survey.lo[a], part.lo[a]),
          survey.hi[a] = std::max(survey.hi[a], part.hi[a]);
      }
      std::sort(survey.huge.begin(), survey.huge.end());
    }
    return changed;
  }

  /// Frees the survey (the finder took its extents when it used them).
  void releaseSurvey() {
    survey = BoxSurvey{};
    surveying = false;
  }

  /// Where each slot's box lies in its proxy (the caller checks kProxyBoxesAreFloats).
  BoxRecords boxRecords() const {
    const GridProxy probe;
    auto bytesOf = [](const void* p) { return static_cast<const unsigned char*>(p); };
    BoxRecords r;
    r.blocks = blocks ? blocks->table() : nullptr;
    r.blockBits = kBlockBits;
    r.stride = sizeof(GridProxy);
    r.minOffset = std::uint32_t(bytesOf(static_cast<const btScalar*>(probe.m_aabbMin)) - bytesOf(&probe));
    r.maxOffset = std::uint32_t(bytesOf(static_cast<const btScalar*>(probe.m_aabbMax)) - bytesOf(&probe));
    // The scan has copied each proxy's filter into group and mask by the time a finder reads the records.
    r.groupOffset = std::uint32_t(bytesOf(&probe.m_collisionFilterGroup) - bytesOf(&probe));
    r.maskOffset = std::uint32_t(bytesOf(&probe.m_collisionFilterMask) - bytesOf(&probe));
    r.contiguousBytes = blocks ? blocks->contiguousBytes() : 0;
    return r;
  }

  /// Float copies of every slot's box into six arrays of slotCount (zero for slots without a live proxy), in
  /// parallel.
  void copyBoxes(float* const axis[6]) const {
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, slotCount, kScanGrain),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                        for (std::uint32_t s = r.begin(); s != r.end(); ++s) {
                          const bool live = state[s] & kLive;
                          const GridProxy& p = proxy(s);
                          for (int a = 0; a < 3; ++a) {
                            axis[a][s] = live ? float(p.m_aabbMin[a]) : 0.0f;
                            axis[3 + a][s] = live ? float(p.m_aabbMax[a]) : 0.0f;
                          }
                        }
                      });
  }


  /// The finder's view of the filled buffer (consumes nonFiniteChanged): the boxes in the proxies when
  /// `readsRecords`, else in the view's arrays (a copy less than half the proxies' size, which took 24 more
  /// bytes per proxy at the peak and no less time: measurement history), which the scan filled for a
  /// double-precision Bullet.
  ProxyArrays finderView(bool readsRecords) {
    ProxyArrays v;
    v.count = slotCount;
    if (readsRecords) {
      v.records = boxRecords();
    } else {
      const bool filled = view.axes != nullptr;
      view.allocateAxes();
      float* const axis[6] = {view.axis(0), view.axis(1), view.axis(2),
                              view.axis(3), view.axis(4), view.axis(5)};
      if (!filled) copyBoxes(axis);
      v.minX = axis[0], v.minY = axis[1], v.minZ = axis[2], v.maxX = axis[3], v.maxY = axis[4],
      v.maxZ = axis[5];
    }
    v.group = group.data(), v.mask = mask.data(), v.flags = view.flags();
    if (!finderFilters) {
      // The cache's own filter (a user's callback) has the only word: the finder reports every overlapping
      // pair, and the diff offers each new one to the cache (needsBroadphaseCollision).
      acceptAll.resize(slotCount, -1);  // every entry is -1: only new slots are written
      v.group = v.mask = acceptAll.data();
      v.records.groupOffset = v.records.maskOffset = kNoRecordField;
    } else {
      std::vector<std::int32_t>().swap(acceptAll);
    }
    v.moved = view.moved();
    if (finderFilters != lastFinderFilters) v.moved = nullptr;
    lastFinderFilters = finderFilters;
    if (readsRecords && surveying) v.survey = &survey;
    // The finder carries resting pairs over from our copy of its last result instead of keeping its own.
    v.lastPairs = &current;
    // A proxy hidden or shown again is a life change the finder's incremental path does not see in `moved`.
    if (nonFiniteChanged) v.moved = nullptr;
    nonFiniteChanged = false;
    return v;
  }

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

  void dropQueryIndex() {
    for (std::uint32_t s : offIndex)
      if (s < slotCount) state[s] = std::uint8_t(state[s] & ~kOffIndex);
    std::vector<std::uint32_t>().swap(offIndex);
    std::vector<BoxCorners>().swap(indexBoxes);
    if (indexReady.load(std::memory_order_relaxed))
      lastIndexQueries = queryIndexed.load(std::memory_order_relaxed) - indexedAtBuild;
    queryGrid.clear();
    indexReady.store(false, std::memory_order_relaxed);
    scansSinceChange.store(0, std::memory_order_relaxed);
  }

  /// The query index when a query should use it, building it when it is due; nullptr: test every proxy.
  const QueryGrid* queryIndex() {
    if (indexReady.load(std::memory_order_acquire)) return &queryGrid;
    if (liveCount < kQueryIndexMinProxies || !internalOptions.queryIndex) return nullptr;
    if (scansSinceChange.fetch_add(1, std::memory_order_relaxed) < kScansBeforeIndex &&
        lastIndexQueries < kQueriesOfABusyIndex)
      return nullptr;
    std::lock_guard<std::mutex> lock(indexBuild);
    if (!indexReady.load(std::memory_order_relaxed)) buildQueryIndex();
    return &queryGrid;
  }

  void buildQueryIndex() {
    // The visible proxies as the index's input, from float copies of their boxes, kept by slot while the
    // index lives.
    std::vector<std::uint32_t> slots;
    slots.reserve(liveCount);
    for (std::uint32_t s = 0; s < slotCount; ++s)
      if (visible(s)) slots.push_back(s);
    constexpr float kMax = std::numeric_limits<float>::max();
    indexBoxes.assign(slotCount, BoxCorners{{kMax, kMax, kMax}, {-kMax, -kMax, -kMax}});
    std::vector<float> copies(std::size_t(slotCount) * 6, 0.0f);
    float* const axis[6] = {&copies[0],
                            &copies[std::size_t(slotCount)],
                            &copies[std::size_t(slotCount) * 2],
                            &copies[std::size_t(slotCount) * 3],
                            &copies[std::size_t(slotCount) * 4],
                            &copies[std::size_t(slotCount) * 5]};
    for (std::uint32_t s : slots) {
      const BoxCorners b = floatBoxHolding(proxy(s));
      indexBoxes[s] = b;
      for (int a = 0; a < 3; ++a) axis[a][s] = b.lo[a], axis[3 + a][s] = b.hi[a];
    }
    ProxyArrays p;
    p.count = slotCount;
    p.minX = axis[0], p.minY = axis[1], p.minZ = axis[2], p.maxX = axis[3], p.maxY = axis[4], p.maxZ = axis[5];
    if (slots.empty())
      queryGrid.clear();
    else
      queryGrid.build(p, slots, internalOptions.hugeCellLimit);
    indexedProxies = std::uint32_t(slots.size());
    ++indexBuilds;
    indexedAtBuild = queryIndexed.load(std::memory_order_relaxed);
    indexReady.store(true, std::memory_order_release);
  }

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

  void store(std::uint32_t s, const btVector3& lo, const btVector3& hi) {
    // The common case first: min <= max within float's range on every axis (so finite: NaN fails every
    // comparison), on a slot that was so before.
    const btScalar big = btScalar(std::numeric_limits<float>::max());
    if (-big <= lo.x() && lo.x() <= hi.x() && hi.x() <= big && -big <= lo.y() && lo.y() <= hi.y() &&
        hi.y() <= big && -big <= lo.z() && lo.z() <= hi.z() && hi.z() <= big &&
        !(state[s] & (kInverted | kNonFinite)))
      return;
    bool finite = true;
    for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(lo[a]) && std::isfinite(hi[a]);
    if (!finite) {
      warnOnce("grid broadphase non-finite box",
               "GridBroadphase: a proxy's AABB has a NaN or infinite component (min " + toString(lo) +
                   ", max " + toString(hi) +
                   "); such a proxy gets no pairs until its AABB is finite (said once)");
    }
    const bool inverted = finite && !(lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z());
    setInverted(s, inverted);
    if (inverted) {
      warnOnce("grid broadphase inverted box",
               "GridBroadphase: a proxy's AABB has min > max on some axis (min " + toString(lo) + ", max " +
                   toString(hi) +
                   "); its pairs and queries follow the overlap test min <= other max on every axis, as "
                   "btDbvtBroadphase's do (said once)");
    }
    setNonFinite(s, !finite);
  }

  void setInverted(std::uint32_t s, bool value) {
    if (bool(state[s] & kInverted) == value) return;
    dropKeptSearch();
    state[s] = std::uint8_t(value ? state[s] | kInverted : state[s] & ~kInverted);
    invertedCount += value ? 1 : -1;
    nonFiniteChanged = true;  // a life change for the finder, as a box turning non-finite
  }

  /// The pairs of the boxes with min > max (kInverted, hidden from the finder: the grid files a box by its
  /// corners' cells), by Bullet's overlap test against every other visible box, as btDbvtBroadphase finds
  /// them, merged into `foundCoded`. Such boxes are a user's bug, said once by store(); they cost a pass over
  /// every proxy each.
  void addInvertedPairs() {
    std::vector<std::uint32_t> inverted;
    for (std::uint32_t s = 0; s < slotCount; ++s)
      if (visible(s) && (state[s] & kInverted)) inverted.push_back(s);
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> lists;
    tbb::parallel_for(std::size_t(0), inverted.size(), [&](std::size_t i) {
      const std::uint32_t a = inverted[i];
      const GridProxy& pa = proxy(a);
      std::vector<std::uint64_t>& out = lists.local();
      for (std::uint32_t b = 0; b < slotCount; ++b) {
        if (b == a || !visible(b) || ((state[b] & kInverted) && b < a)) continue;  // two inverted: once
        const GridProxy& pb = proxy(b);
        if (!TestAabbAgainstAabb2(pa.m_aabbMin, pa.m_aabbMax, pb.m_aabbMin, pb.m_aabbMax)) continue;
        if (finderFilters && !((group[a] & mask[b]) && (group[b] & mask[a]))) continue;
        out.push_back(makePairKey(a, b));
      }
    });
    std::vector<std::uint64_t> extra;
    for (const std::vector<std::uint64_t>& l : lists) extra.insert(extra.end(), l.begin(), l.end());
    if (extra.empty()) return;
    std::sort(extra.begin(), extra.end());
    std::vector<std::uint64_t> found;
    found.reserve(foundCoded.size());
    foundCoded.forEach([&](std::uint64_t key) { found.push_back(key); });
    std::vector<std::uint64_t> merged(found.size() + extra.size());
    merged.erase(std::merge(found.begin(), found.end(), extra.begin(), extra.end(), merged.begin()), merged.end());
    foundCoded.assign(merged, !PackedPairs::worthCoding(merged.size(), slotCount));
  }

  /// What the last search kept (grown pairs or quiet boxes) no longer answers for the scene.
  void dropKeptSearch() {
    if (!grown.kept() && !quiet.kept()) return;
    grown.clear();
    quiet.clear();
    grownWait = grownReuses > 0 ? 0 : std::min(kGrownWaitMax, 2 * grownWait + 1);
    grownWaitLeft = grownWait;
  }

  /// After a full CPU search, what answers the next steps while boxes move little (`view` is the
  /// search's): a small scene's grown pairs; for a larger one, true when its quiet boxes are due, built
  /// by keepQuietBoxes once the step is done.
  bool keepSearch(const ProxyArrays& view) {
    if (grownWaitLeft > 0) {
      --grownWaitLeft;
      return false;
    }
    if (liveCount < options().bruteForceBelow) {
      grown.build(view);
      grownReuses = 0;
      return false;
    }
    return kProxyBoxesAreFloats;
  }

  /// At the end of a larger scene's step whose search changed no pair (a pile at rest, its boxes nudged by
  /// the solver), its boxes and their slacks for the next steps; built from the proxies once the step's
  /// scratch is gone, so that its peak stays below the search's. Returns the build's peak beyond what it
  /// keeps.
  std::size_t keepQuietBoxes(std::size_t pairs) {
    // Only where the memory bound leaves room (100 bytes per proxy and 8 per pair at a step's peak;
    // measured-results, "Broad phase"): the boxes with their slacks, and the query grid's build.
    const std::size_t room = 100 * std::size_t(liveCount) + 8 * pairs;
    const std::size_t need = heldBytes() + std::size_t(slotCount) * (sizeof(BoxCorners) + sizeof(float)) +
                             std::size_t(liveCount) * kQuietBuildBytesPerBox;
    if (need > room) return 0;
    std::vector<std::uint32_t> slots;
    slots.reserve(liveCount);
    for (std::uint32_t s = 0; s < slotCount; ++s)
      if (visible(s)) slots.push_back(s);
    quiet.build(
        slotCount, slots, [&](std::uint32_t s) { return floatBoxHolding(proxy(s)); }, group.data(), mask.data(),
        internalOptions.hugeCellLimit);
    grownReuses = 0;
    return quiet.buildScratchBytes() + slots.capacity() * sizeof(std::uint32_t);
  }

  /// A step of a large scene whose boxes all stayed within their slacks: no pair changed, so nothing is
  /// searched and the cache keeps its pairs (but those its filter refused, offered again as a search would).
  /// Returns false, having done nothing but drop the quiet boxes, when a filter changed (a full search
  /// follows).
  bool answerQuietly(btDispatcher* dispatcher, GridBroadphaseStats& st) {
    if (cacheFiltersByGroupAndMask(*pairCache) != finderFilters) {
      dropKeptSearch();
      return false;
    }
    const auto start = std::chrono::steady_clock::now();
    // A filter edited on a proxy is found here, as the scan would find it.
    for (std::uint32_t s = 0; s < slotCount; ++s) {
      if (!(state[s] & kLive)) continue;
      const GridProxy& p = proxy(s);
      if (group[s] != p.m_collisionFilterGroup || mask[s] != p.m_collisionFilterMask) {
        dropKeptSearch();
        return false;
      }
    }
    const auto cacheStart = std::chrono::steady_clock::now();
    ++grownReuses;
    st.boxesQuiet = true;
    st.overlappingPairs = current.size();
    st.searchMs = std::chrono::duration<double, std::milli>(cacheStart - start).count();
    if (!refused.empty()) {
      foundCoded.assign(current.toVector());
      diffAndUpdateCache(dispatcher, st);
      for (auto* v : {&addedKeys, &removedKeys}) std::vector<std::uint64_t>().swap(*v);
    }
    dirty = false;
    st.memoryBytes = st.peakBytes = heldBytes();
    st.cacheMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cacheStart).count();
    stats = st;
    return true;
  }

  /// A step of a small scene whose boxes all stayed inside their grown boxes: the kept pairs are tested on
  /// the boxes as they are, and the cache is told the difference. Returns false, having done nothing but
  /// drop the list, when a filter changed since (a full search follows).
  bool answerFromGrownPairs(btDispatcher* dispatcher, GridBroadphaseStats& st) {
    if (cacheFiltersByGroupAndMask(*pairCache) != finderFilters) {
      dropKeptSearch();
      return false;
    }
    const auto start = std::chrono::steady_clock::now();
    // The list holds every visible proxy (it is kept only while none is inverted, and a proxy that comes,
    // goes or turns finite drops it), so a filter edited on a proxy is seen here, as the scan would see it;
    // the full search that follows then scans.
    bool filterEdited = false;
    const bool changed = grown.retest(
        [&](std::uint32_t s) {
          const GridProxy& p = proxy(s);
          filterEdited |= group[s] != p.m_collisionFilterGroup || mask[s] != p.m_collisionFilterMask;
          return BoxCorners{{float(p.m_aabbMin[0]), float(p.m_aabbMin[1]), float(p.m_aabbMin[2])},
                            {float(p.m_aabbMax[0]), float(p.m_aabbMax[1]), float(p.m_aabbMax[2])}};
        },
        grownFound);
    if (filterEdited) {
      dropKeptSearch();
      return false;
    }
    const auto cacheStart = std::chrono::steady_clock::now();
    ++grownReuses;
    st.searched = true;
    st.grownPairsTested = true;
    st.overlappingPairs = changed ? grownFound.size() : current.size();
    st.searchMs = std::chrono::duration<double, std::milli>(cacheStart - start).count();
    // Nothing for the cache when no pair changed and none was refused (a refused pair found again is offered
    // again, diffAndUpdateCache); the kept pairs' overlaps were those of `current` after its search.
    if (changed || !refused.empty()) {
      if (changed)
        foundCoded.assign(grownFound);
      else
        foundCoded.assign(current.toVector());
      diffAndUpdateCache(dispatcher, st);
      for (auto* v : {&addedKeys, &removedKeys}) std::vector<std::uint64_t>().swap(*v);
    }
    dirty = false;
    // The list and its test's scratch are held between steps; the diff's lists of changes are small.
    st.memoryBytes = st.peakBytes = heldBytes();
    st.cacheMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cacheStart).count();
    stats = st;
    return true;
  }

  void setNonFinite(std::uint32_t s, bool value) {
    if (bool(state[s] & kNonFinite) == value) return;
    dropKeptSearch();
    state[s] = std::uint8_t(value ? state[s] | kNonFinite : state[s] & ~kNonFinite);
    nonFiniteCount += value ? 1 : -1;
    nonFiniteChanged = true;
  }

  static std::string toString(const btVector3& v) {
    char text[96];
    std::snprintf(text, sizeof text, "(%g, %g, %g)", double(v.x()), double(v.y()), double(v.z()));
    return text;
  }

  PairFinder& chooseFinder(GridBroadphaseStats& st) {
    const Backend b = config.broadphaseBackend;
    bool wantOpenCl = b == Backend::OpenCL;
    autoMeasuring = false;
    if (b == Backend::Auto) {
      wantOpenCl = autoChoice.choose(liveCount) == MeasuredBackendChoice::Path::Device;
      // The device lists are asked only once a size class wants the device (its CPU searches took
      // MeasuredBackendChoice::kDeviceWorthMs or more), so that a world of short searches never touches
      // OpenCL, and a machine whose only OpenCL device is a CPU one never sets OpenCL up for it.
      if (wantOpenCl && !detail::autoUsesCpuDevice() && !opencl::chosenDeviceIsGpu(config.openclDevice)) {
        autoChoice.deviceFailed();
        wantOpenCl = false;
      }
      autoMeasuring = !autoChoice.decided(liveCount).has_value();
    }
    if (wantOpenCl && !openClTried) {
      openClTried = true;
      openClFinder = makeOpenClPairFinder(config);
      if (!openClFinder && b == Backend::OpenCL)
        std::cerr << "gpucol::GridBroadphase: no OpenCL pair finder available; using the CPU path\n";
    }
    if (wantOpenCl && openClFinder &&
        (b == Backend::OpenCL || openClFinder->runsOnGpu() || detail::autoUsesCpuDevice())) {
      st.usedOpenCl = true;
      return *openClFinder;
    }
    if (wantOpenCl && b == Backend::Auto) {
      autoChoice.deviceFailed();  // no finder, or its device is not a GPU after all
      autoMeasuring = false;
    }
    return *cpuFinder;
  }

  /// The OpenCL finder failed: warned about once, dropped, and never made again for this broad phase (Auto
  /// takes the CPU from now on, as the mesh path does).
  void dropOpenCl(const std::string& why) {
    warnOnce("GridBroadphase OpenCL failure", "the OpenCL pair search failed (" + why +
                                                  "); the broad phase continues on the CPU path");
    openClFinder.reset();
    openClTried = true;
    autoChoice.deviceFailed();
    autoMeasuring = false;
  }

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

  void diffAndUpdateCache(btDispatcher* dispatcher, GridBroadphaseStats& st);
  void removeDeferred(btDispatcher* dispatcher);

  /// Bytes held between steps (GridBroadphaseStats::memoryBytes): proxy blocks, block table, filters, state,
  /// free-slot lists, the last pair list and its refused part, and the finder's kept memory.
  std::size_t heldBytes() const {
    std::size_t bytes = blockCount() * kBlockSize * sizeof(GridProxy) + (blocks ? blocks->tableBytes() : 0);
    bytes += (group.capacity() + mask.capacity() + acceptAll.capacity()) * sizeof(std::int32_t) + state.capacity();
    bytes += (freeSlots.capacity() + pendingFree.capacity()) * sizeof(std::uint32_t);
    bytes += current.bytes() + refused.capacity() * sizeof(std::uint64_t) + grown.bytes() + quiet.bytes() +
             grownFound.capacity() * sizeof(std::uint64_t);
    for (const PairFinder* f : {cpuFinder.get(), openClFinder.get()})
      if (f) bytes += f->stats().scratchBytes;
    return bytes;
  }
};

GridBroadphase::GridBroadphase(const Config& config, btOverlappingPairCache* pairCache) : m_impl(new Impl) {
  m_impl->config = config;
  if (config.bruteForceBelow < 0)
    throw std::invalid_argument("gpucol::GridBroadphase: Config::bruteForceBelow must be >= 0, got " +
                                std::to_string(config.bruteForceBelow));
  if (pairCache) {
    m_impl->pairCache = pairCache;
  } else {
    m_impl->ownedCache.reset(new btHashedOverlappingPairCache());
    m_impl->pairCache = m_impl->ownedCache.get();
  }
}

GridBroadphase::~GridBroadphase() = default;

btBroadphaseProxy* GridBroadphase::createProxy(const btVector3& aabbMin, const btVector3& aabbMax,
                                               int shapeType, void* userPtr, int collisionFilterGroup,
                                               int collisionFilterMask, btDispatcher* /*dispatcher*/) {
  Impl& d = *m_impl;
  std::uint32_t slot;
  if (!d.freeSlots.empty()) {
    slot = d.freeSlots.back();
    d.freeSlots.pop_back();
  } else {
    if (d.slotCount >= 0xffffffffu)
      throw std::length_error("gpucol::GridBroadphase: more than 2^32 - 1 proxies");
    slot = d.slotCount++;
    if ((slot >> kBlockBits) >= d.blockCount()) {
      if (!d.blocks) d.blocks = std::make_unique<ReservedBlocks>(kBlockSize * sizeof(GridProxy), kMaxBlocks);
      auto* block = static_cast<GridProxy*>(d.blocks->add());
      for (std::uint32_t i = 0; i < kBlockSize; ++i) new (block + i) GridProxy();
    }
    d.growSlots();
    d.group.push_back(0), d.mask.push_back(0), d.state.push_back(0);
  }
  d.dropKeptSearch();
  GridProxy& p = d.proxy(slot);
  static_cast<btBroadphaseProxy&>(p) =
      btBroadphaseProxy(aabbMin, aabbMax, userPtr, collisionFilterGroup, collisionFilterMask);
  (void)shapeType;  // Bullet 3 proxies no longer store the shape type
  p.m_uniqueId = ++d.nextUniqueId;
  p.slot = slot;
  d.state[slot] = std::uint8_t(kLive | kMoved | (d.state[slot] & kOffIndex));
  d.store(slot, aabbMin, aabbMax);
  d.boxChanged(slot);
  d.group[slot] = collisionFilterGroup;
  d.mask[slot] = collisionFilterMask;
  if (Impl::flagsOf(collisionFilterGroup) & kProxyStatic) ++d.staticCount;
  ++d.liveCount;
  d.dirty = true;
  return &p;
}

void GridBroadphase::destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) {
  Impl& d = *m_impl;
  GridProxy* p = static_cast<GridProxy*>(proxy);
  const std::uint32_t slot = p->slot;
  if (slot >= d.slotCount || &d.proxy(slot) != p || !(d.state[slot] & kLive))
    throw std::invalid_argument(
        "gpucol::GridBroadphase::destroyProxy: proxy does not belong to this broad phase");
  // Its pairs leave the cache now (algorithms and manifolds freed through the dispatcher); the keys in
  // `current` are dropped at the next search, and the slot is reused only after that search.
  d.pairCache->removeOverlappingPairsContainingProxy(proxy, dispatcher);
  d.dropKeptSearch();
  if (Impl::flagsOf(d.group[slot]) & kProxyStatic) --d.staticCount;
  d.setNonFinite(slot, false);
  d.setInverted(slot, false);
  d.state[slot] = std::uint8_t(kFreed | kMoved | (d.state[slot] & kOffIndex));
  d.pendingFree.push_back(slot);
  --d.liveCount;
  d.dirty = true;
}

void GridBroadphase::setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                             btDispatcher* /*dispatcher*/) {
  Impl& d = *m_impl;
  // Unchanged boxes (Bullet re-sends every AABB by default, m_forceUpdateAllAabbs) leave the step clean,
  // so a scene at rest costs no search.
  // x, y, z only: btVector3's operator== also compares the unused fourth component.
  const btVector3 &lo = proxy->m_aabbMin, &hi = proxy->m_aabbMax;
  if (lo.x() == aabbMin.x() && lo.y() == aabbMin.y() && lo.z() == aabbMin.z() && hi.x() == aabbMax.x() &&
      hi.y() == aabbMax.y() && hi.z() == aabbMax.z())
    return;
  const std::uint32_t s = static_cast<GridProxy*>(proxy)->slot;
  proxy->m_aabbMin = aabbMin;
  proxy->m_aabbMax = aabbMax;
  d.state[s] |= kMoved;
  d.store(s, aabbMin, aabbMax);
  d.boxChanged(s);
  d.dirty = true;
  if (d.grown.kept() || d.quiet.kept()) {
    const float lo[3] = {float(aabbMin.x()), float(aabbMin.y()), float(aabbMin.z())};
    const float hi[3] = {float(aabbMax.x()), float(aabbMax.y()), float(aabbMax.z())};
    if (d.grown.kept() ? !d.grown.holds(s, lo, hi) : !d.quiet.holds(s, lo, hi)) d.dropKeptSearch();
  }
}

void GridBroadphase::getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const {
  aabbMin = proxy->m_aabbMin;
  aabbMax = proxy->m_aabbMax;
}

void GridBroadphase::rayTest(const btVector3& rayFrom, const btVector3& /*rayTo*/,
                             btBroadphaseRayCallback& rayCallback, const btVector3& aabbMin,
                             const btVector3& aabbMax) {
  Impl& d = *m_impl;
  // btDbvtBroadphase reads m_lambda_max once, before its traversal, and tests boxes grown by the ray's own
  // box (bounds = [min - aabbMax, max - aabbMin]) with btRayAabb2 from t = 0; so do we, in slot order.
  const btScalar lambdaMax = rayCallback.m_lambda_max;
  auto hits = [&](std::uint32_t s) {
    GridProxy& p = d.proxy(s);
    const btVector3 bounds[2] = {p.m_aabbMin - aabbMax, p.m_aabbMax - aabbMin};
    btScalar tmin = 0;
    return btRayAabb2(rayFrom, rayCallback.m_rayDirectionInverse, rayCallback.m_signs, bounds, tmin, 0,
                      lambdaMax);
  };
  auto process = [&](btBroadphaseProxy* p) { rayCallback.process(p); };
  if (const QueryGrid* index = d.queryIndex()) {
    // The sweep's direction is the one btRayAabb2 tests along, 1 / m_rayDirectionInverse; signs that do
    // not match it make btRayAabb2 test something else, which only a scan reproduces.
    QuerySweep sweep;
    bool usable = true;
    for (int a = 0; a < 3; ++a) {
      const double inverse = rayCallback.m_rayDirectionInverse[a];
      usable = usable && rayCallback.m_signs[a] == unsigned(inverse < 0.0);
      sweep.from[a] = rayFrom[a];
      sweep.dir[a] = 1.0 / inverse;
      sweep.castLo[a] = aabbMin[a], sweep.castHi[a] = aabbMax[a];
    }
    sweep.tMax = lambdaMax;
    std::vector<std::uint32_t> candidates;
    candidates.reserve(kQueryCandidatesReserved);
    // The exact test on the box filed for a candidate (which holds its box; btRayAabb2 is monotone in the
    // bounds, rounding included): most of a cell's candidates are dropped before they are sorted and read.
    auto rayHitsFiled = [&](const BoxCorners& b) {
      const btVector3 bounds[2] = {btVector3(b.lo[0], b.lo[1], b.lo[2]) - aabbMax,
                                   btVector3(b.hi[0], b.hi[1], b.hi[2]) - aabbMin};
      btScalar tmin = 0;
      return btRayAabb2(rayFrom, rayCallback.m_rayDirectionInverse, rayCallback.m_signs, bounds, tmin, 0,
                        lambdaMax);
    };
    const Impl::FiledTests<decltype(rayHitsFiled)> keep(d, rayHitsFiled);
    if (usable && index->sweepCandidates(sweep, d.maxCandidates(), candidates, keep.bySlot()))
      return d.answerFromIndex(candidates, hits, process);
  }
  d.answerByScan(hits, process);
}

void GridBroadphase::aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                              btBroadphaseAabbCallback& callback) {
  Impl& d = *m_impl;
  auto overlaps = [&](std::uint32_t s) {
    const GridProxy& p = d.proxy(s);
    const btVector3& lo = p.m_aabbMin;
    const btVector3& hi = p.m_aabbMax;
    // Touching counts, as in btDbvtAabbMm's Intersect.
    return lo.x() <= aabbMax.x() && hi.x() >= aabbMin.x() && lo.y() <= aabbMax.y() && hi.y() >= aabbMin.y() &&
           lo.z() <= aabbMax.z() && hi.z() >= aabbMin.z();
  };
  auto process = [&](btBroadphaseProxy* p) { callback.process(p); };
  if (const QueryGrid* index = d.queryIndex()) {
    const float lo[3] = {aabbMin.x(), aabbMin.y(), aabbMin.z()};
    const float hi[3] = {aabbMax.x(), aabbMax.y(), aabbMax.z()};
    std::vector<std::uint32_t> candidates;
    candidates.reserve(kQueryCandidatesReserved);
    // The exact test on the box filed for a candidate, which holds its box.
    auto overlapsFiled = [&](const BoxCorners& b) {
      return btScalar(b.lo[0]) <= aabbMax.x() && btScalar(b.hi[0]) >= aabbMin.x() &&
             btScalar(b.lo[1]) <= aabbMax.y() && btScalar(b.hi[1]) >= aabbMin.y() &&
             btScalar(b.lo[2]) <= aabbMax.z() && btScalar(b.hi[2]) >= aabbMin.z();
    };
    const Impl::FiledTests<decltype(overlapsFiled)> keep(d, overlapsFiled);
    if (index->boxCandidates(lo, hi, d.maxCandidates(), candidates, keep.bySlot()))
      return d.answerFromIndex(candidates, overlaps, process);
  }
  d.answerByScan(overlaps, process);
}

void GridBroadphase::calculateOverlappingPairs(btDispatcher* dispatcher) {
  Impl& d = *m_impl;
  GridBroadphaseStats st;
  st.proxies = d.liveCount;
  st.staticProxies = d.staticCount;
  if (d.dirty && d.grown.kept() && d.answerFromGrownPairs(dispatcher, st)) return;
  if (d.dirty && d.quiet.kept() && d.answerQuietly(dispatcher, st)) return;
  // When a box already changed, the scan fills the finder's view as it goes (a filter it finds changed is
  // marked moved there); otherwise it only looks for filter changes, and the view is filled when it found
  // one. A second filling scan would find the moved marks cleared by the first.
  const bool filling = d.dirty;
  if (filling) d.view.allocate(d.slotCount, !kProxyBoxesAreFloats), d.prepareSurvey();
  if (d.scan(filling) && !filling) {
    d.dirty = true;
    d.view.allocate(d.slotCount, !kProxyBoxesAreFloats);
    d.prepareSurvey();
    d.scan(true);
  }
  st.staticProxies = d.staticCount;
  if (!d.dirty) {
    d.releaseSurvey();
    st.overlappingPairs = d.stats.overlappingPairs;
    st.memoryBytes = d.stats.memoryBytes;
    st.peakBytes = d.stats.memoryBytes;
    d.stats = st;
    return;
  }
  st.searched = true;
  d.finderFilters = cacheFiltersByGroupAndMask(*d.pairCache);
  PairFinder* chosen = &d.chooseFinder(st);
  ProxyArrays view = d.finderView(kProxyBoxesAreFloats && chosen->readsBoxRecords());
  // kMoved is relative to the previous search of the same finder; after a switch of finder, all moved.
  if (chosen != d.lastFinder) view.moved = nullptr;
  // Nothing is freed before the search: the step holds at least what was held before it, and the view (a
  // search that starts by dropping a kept grid may never come back up to that).
  const std::size_t startBytes = d.heldBytes() + d.view.bytes() + d.survey.bytes();
  const auto searchStart = std::chrono::steady_clock::now();
  auto search = [&](PairFinder& f, const ProxyArrays& v) {
    if (f.codesPairs())
      f.findCodedPairs(v, d.options(), d.foundCoded);
    else
      f.findPairs(v, d.options(), d.found);
  };
  try {
    search(*chosen, view);
  } catch (const std::exception& e) {
    if (chosen == d.cpuFinder.get()) throw;
    // The OpenCL search failed (a build, an allocation, a launch): said once, and the CPU path takes over for
    // good with a full search of its own, so the step loses no pair.
    d.dropOpenCl(e.what());
    st.usedOpenCl = false;
    chosen = d.cpuFinder.get();
    view = d.finderView(kProxyBoxesAreFloats && chosen->readsBoxRecords());
    view.moved = nullptr;
    search(*chosen, view);
  }
  PairFinder& finder = *chosen;
  const auto cacheStart = std::chrono::steady_clock::now();
  bool quietDue = false;
  if (&finder == d.cpuFinder.get() && d.invertedCount == 0)
    quietDue = d.keepSearch(view);
  else
    d.dropKeptSearch();
  st.searchMs = std::chrono::duration<double, std::milli>(cacheStart - searchStart).count();
  if (d.autoMeasuring) {
    d.autoChoice.record(
        d.liveCount, st.usedOpenCl ? MeasuredBackendChoice::Path::Device : MeasuredBackendChoice::Path::Cpu,
        st.searchMs);
  }
  const PairFinderStats& fs = finder.stats();
  st.chooseMs = fs.chooseMs, st.binMs = fs.binMs, st.testMs = fs.testMs, st.hugeMs = fs.hugeMs;
  st.sortMs = fs.sortMs;
  d.lastFinder = &finder;
  st.usedGrid = fs.usedGrid;
  st.restingProxies = fs.restingProxies;
  st.rebinnedProxies = fs.rebinnedProxies;
  st.cellSize = fs.cellSize;
  st.boxesSurveyed = fs.surveyTaken;
  // The search's extra: the view and the finder's high-water mark above what it keeps and its output as it
  // stands now (a mark that counts its output, peakIncludesOutput, says how much of it was there: the slab
  // search's working memory is gone before the list is gathered).
  const std::size_t outputBytes = finder.codesPairs() ? d.foundCoded.bytes() : d.found.capacity() * 8;
  const std::size_t finderMark = std::max(fs.peakScratchBytes, fs.scratchBytes);
  const std::size_t heldOfMark =
      fs.scratchBytes + (fs.peakIncludesOutput ? std::min(finderMark - fs.scratchBytes, outputBytes) : 0);
  const std::size_t stepBytes = d.view.bytes() + d.survey.bytes() + finderMark - heldOfMark;
  d.view.release();
  d.releaseSurvey();
  // This step's list as found beside its coded copy (none when it is kept plain: taken over).
  std::size_t foundBytes = 0;
  if (!finder.codesPairs()) {
    if (PackedPairs::worthCoding(d.found.size(), d.slotCount)) {
      foundBytes = d.found.capacity() * 8;
      d.foundCoded.assign(d.found);
    } else {
      d.foundCoded.adopt(std::move(d.found));
    }
    std::vector<std::uint64_t>().swap(d.found);
  }
  if (d.invertedCount > 0) d.addInvertedPairs();
  st.overlappingPairs = d.foundCoded.size();
  const std::size_t lastListBytes = d.current.bytes(), listBytes = d.foundCoded.bytes();
  d.diffAndUpdateCache(dispatcher, st);
  for (std::uint32_t s : d.pendingFree) {
    d.state[s] = std::uint8_t(d.state[s] & ~kFreed);
    d.freeSlots.push_back(s);
  }
  d.pendingFree.clear();
  d.dirty = false;
  st.memoryBytes = d.heldBytes();
  // The peak: what is held after the step but its pair list, with the last step's list and either the
  // search's extra and output, or (a finder that does not code) this step's list as found and coded, or
  // both coded lists and the diff's lists of changes.
  const std::size_t changeBytes = (d.addedKeys.capacity() + d.removedKeys.capacity()) * 8;
  const std::size_t before = st.memoryBytes - listBytes + lastListBytes;
  st.peakBytes = std::max({startBytes, before + outputBytes + stepBytes, before + foundBytes + listBytes,
                           before + listBytes + changeBytes});
  for (auto* v : {&d.addedKeys, &d.removedKeys}) std::vector<std::uint64_t>().swap(*v);
  if (quietDue && st.added == 0 && st.removed == 0) {
    const std::size_t scratch = d.keepQuietBoxes(st.overlappingPairs);
    st.memoryBytes = d.heldBytes();
    st.peakBytes = std::max(st.peakBytes, st.memoryBytes + scratch);
  }
  st.cacheMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cacheStart).count();
  d.stats = st;
}

/// The diff of the last pair list (`current`) with this step's (`foundCoded`) in one merge walk that only
/// lists the changes, then the cache's calls, removals first and additions after, each in key order (the
/// cache's pair array then never holds both). Listing first keeps the walk over the two pair lists apart from
/// the cache's hash-table work: handing each change to the cache as the walk found it was about half as
/// slow again at 1M uniform boxes. Pairs only in `current` that the cache holds are removed (those of
/// destroyed proxies went with destroyProxy already); pairs only in `foundCoded`, and refused ones found
/// again (the cache's filter callback may change its mind), are offered to the cache. Then `foundCoded`
/// becomes `current`, and the last list is freed.
void GridBroadphase::Impl::diffAndUpdateCache(btDispatcher* dispatcher, GridBroadphaseStats& st) {
  btOverlappingPairCache* cache = pairCache;
  auto proxy0 = [&](std::uint64_t key) { return &proxy(std::uint32_t(key >> 32)); };
  auto proxy1 = [&](std::uint64_t key) { return &proxy(std::uint32_t(key)); };
  refusedNow.clear();
  removedKeys.clear();
  addedKeys.clear();
  // The changes of each part of the key range (the found list's segments), walked in parallel twice: counted,
  // then listed into lists allocated at their size (grown by push_back a list held up to twice its keys,
  // and half as much again while it grew: tests/memory).
  const std::size_t parts = diffParts(foundCoded);
  std::vector<std::size_t> addedAt(parts + 1, 0), removedAt(parts + 1, 0);
  // Where the cache's own filter decides (a user's callback: the finder reports every overlapping pair), a
  // kept pair one of whose proxies changed its filter is asked again, as the finder's masks are otherwise.
  const bool recheck = !finderFilters && filtersChanged.load();
  std::vector<std::uint64_t> recheckKeys;
  std::mutex recheckMutex;
  auto walk = [&](bool list) {
    diffCodedInParts(current, foundCoded, [&](std::size_t part, std::uint64_t begin, auto before, auto now) {
      std::uint64_t* const added = list ? addedKeys.data() + addedAt[part] : nullptr;
      std::uint64_t* const removed = list ? removedKeys.data() + removedAt[part] : nullptr;
      std::size_t addedCount = 0, removedCount = 0;
      // `refused` is walked along with the merge: both callbacks that consult it see keys in ascending
      // order.
      std::size_t r = std::size_t(std::lower_bound(refused.begin(), refused.end(), begin) - refused.begin());
      auto isRefused = [&](std::uint64_t key) {
        while (r < refused.size() && refused[r] < key) ++r;
        return r < refused.size() && refused[r] == key;
      };
      auto add = [&](std::uint64_t key) {
        if (list) added[addedCount] = key;
        ++addedCount;
      };
      auto remove = [&](std::uint64_t key) {
        if (isRefused(key)) return;  // never in the cache
        if ((state[std::uint32_t(key >> 32)] & kFreed) || (state[std::uint32_t(key)] & kFreed)) return;
        if (list) removed[removedCount] = key;
        ++removedCount;
      };
      if (refused.empty() && !recheck) {
        diffSortedReaders(before, now, add, remove, IgnoreKept{});  // kept keys skipped in runs
      } else {
        diffSortedReaders(before, now, add, remove, [&](std::uint64_t key) {
          if (isRefused(key)) {
            add(key);  // asked again
          } else if (list && recheck &&
                     ((state[std::uint32_t(key >> 32)] | state[std::uint32_t(key)]) & kFilterChanged)) {
            std::lock_guard<std::mutex> lock(recheckMutex);
            recheckKeys.push_back(key);
          }
        });
      }
      if (!list) addedAt[part + 1] = addedCount, removedAt[part + 1] = removedCount;
    });
  };
  walk(false);
  for (std::size_t p = 0; p < parts; ++p) addedAt[p + 1] += addedAt[p], removedAt[p + 1] += removedAt[p];
  addedKeys.resize(addedAt[parts]);
  removedKeys.resize(removedAt[parts]);
  walk(true);
  if (!recheckKeys.empty()) {
    // Those the cache now refuses leave it and join the refused; the lists stay sorted.
    for (const std::uint64_t key : recheckKeys) {
      if (cache->needsBroadphaseCollision(proxy0(key), proxy1(key))) continue;
      removedKeys.push_back(key);
      refusedNow.push_back(key);
    }
    std::sort(removedKeys.begin(), removedKeys.end());
  }
  if (filtersChanged.exchange(false)) {
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, slotCount, kScanGrain),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                        for (std::uint32_t s = r.begin(); s != r.end(); ++s) state[s] &= ~kFilterChanged;
                      });
  }
  st.removed = removedKeys.size();
  const bool deferred = cache->hasDeferredRemoval();
  if (!deferred)
    for (const std::uint64_t key : removedKeys)
      cache->removeOverlappingPair(proxy0(key), proxy1(key), dispatcher);
  for (const std::uint64_t key : addedKeys) {
    // The cache's own filter (overlap filter callback) has the last word.
    if (!cache->needsBroadphaseCollision(proxy0(key), proxy1(key))) {
      refusedNow.push_back(key);
      continue;
    }
    cache->addOverlappingPair(proxy0(key), proxy1(key));
    ++st.added;
  }
  if (deferred && !removedKeys.empty()) removeDeferred(dispatcher);  // handled in one pass over the cache
  if (!recheckKeys.empty()) std::sort(refusedNow.begin(), refusedNow.end());
  current.swap(foundCoded);
  foundCoded.clear();
  refused.swap(refusedNow);
  if (refusedNow.capacity() > 2 * refused.size() + 16) std::vector<std::uint64_t>().swap(refusedNow);
}

/// Caches with deferred removal (btSortedOverlappingPairCache by default) ignore removeOverlappingPair and
/// expect the broad phase to drop pairs itself, as btDbvtBroadphase and btAxisSweep3 do: clean the pair
/// (frees its algorithm through the dispatcher), null its proxies, sort the nulls to the end and shrink.
void GridBroadphase::Impl::removeDeferred(btDispatcher* dispatcher) {
  Impl& d = *this;
  btOverlappingPairCache* cache = d.pairCache;
  btBroadphasePairArray& pairs = cache->getOverlappingPairArray();
  int invalid = 0;
  for (int i = 0; i < pairs.size(); ++i) {
    btBroadphasePair& pair = pairs[i];
    if (!pair.m_pProxy0 || !pair.m_pProxy1) continue;
    const std::uint64_t key = makePairKey(static_cast<GridProxy*>(pair.m_pProxy0)->slot,
                                          static_cast<GridProxy*>(pair.m_pProxy1)->slot);
    if (std::binary_search(d.removedKeys.begin(), d.removedKeys.end(), key)) {
      cache->cleanOverlappingPair(pair, dispatcher);
      pair.m_pProxy0 = nullptr;
      pair.m_pProxy1 = nullptr;
      ++invalid;
    }
  }
  pairs.quickSort(btBroadphasePairSortPredicate());
  pairs.resize(pairs.size() - invalid);
}

btOverlappingPairCache* GridBroadphase::getOverlappingPairCache() {
  return m_impl->pairCache;
}

const btOverlappingPairCache* GridBroadphase::getOverlappingPairCache() const {
  return m_impl->pairCache;
}

void GridBroadphase::getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const {
  const Impl& d = *m_impl;
  bool any = false;
  for (std::uint32_t s = 0; s < d.slotCount; ++s) {
    if (!d.visible(s)) continue;
    const GridProxy& p = d.proxy(s);
    if (!any) {
      aabbMin = p.m_aabbMin, aabbMax = p.m_aabbMax, any = true;
    } else {
      aabbMin.setMin(p.m_aabbMin);
      aabbMax.setMax(p.m_aabbMax);
    }
  }
  if (!any) aabbMin = aabbMax = btVector3(0, 0, 0);
}

void GridBroadphase::resetPool(btDispatcher* /*dispatcher*/) {
  Impl& d = *m_impl;
  if (d.liveCount != 0) return;
  d.blocks.reset();
  d.slotCount = 0;
  std::vector<std::int32_t>().swap(d.group);
  std::vector<std::int32_t>().swap(d.mask);
  std::vector<std::uint8_t>().swap(d.state);
  d.nonFiniteCount = 0;
  d.invertedCount = 0;
  d.staticCount = 0;
  d.lastFinder = nullptr;
  d.freeSlots.clear(), d.pendingFree.clear(), d.current.clear(), d.refused.clear();
  d.grown.clear();
  d.dropQueryIndex();
  d.nextUniqueId = 0;
  d.dirty = true;
}

void GridBroadphase::printStats() {
  const GridBroadphaseStats& st = m_impl->stats;
  std::printf(
      "gpucol::GridBroadphase: %u proxies, %llu overlapping pairs (+%llu -%llu), %s%s, cell %g, %zu bytes\n",
      st.proxies, static_cast<unsigned long long>(st.overlappingPairs),
      static_cast<unsigned long long>(st.added), static_cast<unsigned long long>(st.removed),
      st.usedGrid ? "grid" : "brute force", st.usedOpenCl ? " (OpenCL)" : "", double(st.cellSize),
      st.memoryBytes);
}

void detail::GridBroadphaseAccess::setOptions(GridBroadphase& broadphase,
                                              const GridBroadphaseOptions& options) {
  GridBroadphase::Impl& d = *broadphase.m_impl;
  d.internalOptions = options;
  d.dirty = true;
  d.lastFinder = nullptr;  // a full search with the new options
  d.dropQueryIndex();      // and an index (if any) with them
}

const GridBroadphaseStats& GridBroadphase::stats() const {
  return m_impl->stats;
}

GridBroadphaseQueryStats GridBroadphase::queryStats() const {
  const Impl& d = *m_impl;
  GridBroadphaseQueryStats q;
  q.scans = d.queryScans.load(std::memory_order_relaxed);
  q.indexed = d.queryIndexed.load(std::memory_order_relaxed);
  q.indexBuilds = d.indexBuilds;
  q.indexBytes = d.indexReady.load(std::memory_order_acquire)
                     ? d.queryGrid.memoryBytes() + d.offIndex.capacity() * sizeof(std::uint32_t) +
                           d.indexBoxes.capacity() * sizeof(BoxCorners)
                     : 0;
  return q;
}

}  // namespace gpucol
