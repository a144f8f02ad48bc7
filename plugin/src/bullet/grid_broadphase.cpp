// gpucol::GridBroadphase: Bullet's side of the grid broad phase. Proxies live in a deque (stable
// addresses), their AABBs and filters in structure-of-arrays form for the pair finder
// (broadphase/grid_pair_finder.h); each step's sorted pair list is diffed against the last one so the pair
// cache only sees additions and removals (DESIGN.md, data flow).
#include "gpucol/grid_broadphase.h"

#include <LinearMath/btAabbUtil2.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "broadphase/grid_pair_finder.h"
#include "broadphase/pair_diff.h"
#include "bullet/warn_once.h"
#include "opencl/host/opencl_started.h"

namespace gpucol {
namespace {

/// Auto backend: at and above this many proxies the OpenCL finder is used, when one is registered and its
/// device is a GPU. On a CPU device (PoCL) Auto never uses it: there the CPU path was faster at every size
/// measured, 1K to 1M boxes (README, "Broad phase"). The GPU crossover has not been measured (no GPU was
/// available), so this value is a guess, not a measurement.
constexpr std::uint32_t kAutoOpenClFrom = 100000;

/// Proxies per parallel task of the per-step scan of the proxies' filters.
constexpr std::uint32_t kScanGrain = 16384;

/// A proxy with its slot in the structure-of-arrays storage.
struct GridProxy : btBroadphaseProxy {
  std::uint32_t slot = 0;
};

}  // namespace

struct GridBroadphase::Impl {
  Config config;
  GridBroadphaseTuning tuning;
  GridBroadphaseStats stats;
  btOverlappingPairCache* pairCache = nullptr;
  std::unique_ptr<btHashedOverlappingPairCache> ownedCache;

  std::deque<GridProxy> proxies;  // index = slot; a deque never moves its elements when it grows
  std::vector<float> minX, minY, minZ, maxX, maxY, maxZ;
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> flags;
  std::vector<std::uint8_t> moved;             // per slot: box, filter or life changed since the last search
  const PairFinder* lastFinder = nullptr;      // the finder of the last search (moved is relative to it)
  std::vector<std::uint32_t> freeSlots;        // reusable now
  std::vector<std::uint32_t> pendingFree;      // freed since the last search: reused only after it
  std::vector<std::uint8_t> freedSinceSearch;  // per slot: its old pairs are already gone from the cache
  // A box with a NaN or infinite component gets no pairs, as Bullet's own updateAabbs drops an overflowing
  // box: the finder's cell size, grid bounds and cell indices would turn NaN (or a float-to-int conversion of
  // NaN) and spread to every proxy. Such a proxy is hidden from the finder until its box is finite again.
  std::vector<std::uint8_t> nonFinite;  // per slot
  std::uint32_t nonFiniteCount = 0;
  bool nonFiniteChanged = false;          // a proxy entered or left that state: the next search is a full one
  std::vector<std::uint8_t> finderFlags;  // flags with the non-finite proxies' active bit cleared
  std::uint32_t liveCount = 0;
  std::uint32_t staticCount = 0;  // live proxies with the static flag (GridBroadphaseStats::staticProxies)
  int nextUniqueId = 0;
  bool dirty = true;

  std::unique_ptr<PairFinder> cpuFinder = makeCpuPairFinder();
  std::unique_ptr<PairFinder> openClFinder;
  bool openClTried = false;
  std::vector<std::uint64_t> accepted;  // sorted keys of the pairs in the cache after the last step
  std::vector<std::uint64_t> found;
  std::vector<std::uint64_t> added;        // pairs new this step (sorted)
  std::vector<std::uint64_t> refused;      // of those, the ones the cache's filter refused (sorted)
  std::vector<std::uint64_t> removedKeys;  // pairs vanished this step (sorted)

  /// The finder's view of the proxies (called once per search: it consumes nonFiniteChanged).
  ProxyArrays view() {
    ProxyArrays v;
    v.count = std::uint32_t(flags.size());
    v.minX = minX.data(), v.minY = minY.data(), v.minZ = minZ.data();
    v.maxX = maxX.data(), v.maxY = maxY.data(), v.maxZ = maxZ.data();
    v.group = group.data(), v.mask = mask.data(), v.flags = flags.data();
    v.moved = moved.data();
    if (nonFiniteCount > 0) {
      finderFlags = flags;
      for (std::size_t s = 0; s < flags.size(); ++s) {
        if (nonFinite[s]) finderFlags[s] = std::uint8_t(finderFlags[s] & ~kProxyActive);
      }
      v.flags = finderFlags.data();
    }
    // A proxy hidden or shown again is a life change the finder's incremental path does not see in `moved`.
    if (nonFiniteChanged) v.moved = nullptr;
    nonFiniteChanged = false;
    return v;
  }

  static std::uint8_t flagsOf(int filterGroup) {
    // Bullet gives static and kinematic objects the StaticFilter group
    // (btCollisionWorld::addCollisionObject); those pairs are never generated.
    return std::uint8_t(kProxyActive | ((filterGroup & btBroadphaseProxy::StaticFilter) ? kProxyStatic : 0));
  }

  void store(std::uint32_t s, const btVector3& lo, const btVector3& hi) {
    minX[s] = lo.x(), minY[s] = lo.y(), minZ[s] = lo.z();
    maxX[s] = hi.x(), maxY[s] = hi.y(), maxZ[s] = hi.z();
    bool finite = true;
    for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(lo[a]) && std::isfinite(hi[a]);
    if (!finite) {
      warnOnce("grid broadphase non-finite box",
               "GridBroadphase: a proxy's AABB has a NaN or infinite component (min " + toString(lo) +
                   ", max " + toString(hi) +
                   "); such a proxy gets no pairs until its AABB is finite (said once)");
    }
    setNonFinite(s, !finite);
  }

  void setNonFinite(std::uint32_t s, bool value) {
    if (bool(nonFinite[s]) == value) return;
    nonFinite[s] = value;
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
    // Auto asks the device lists first, so that a machine whose only OpenCL device is a CPU one never sets
    // OpenCL up for it (the CPU path is faster there at every size measured).
    const bool wantOpenCl = b == Backend::OpenCL || (b == Backend::Auto && liveCount >= kAutoOpenClFrom &&
                                                     opencl::chosenDeviceIsGpu(config.openclDevice));
    if (wantOpenCl && !openClTried) {
      openClTried = true;
      openClFinder = makeOpenClPairFinder(config);
      if (!openClFinder && b == Backend::OpenCL)
        std::cerr << "gpucol::GridBroadphase: no OpenCL pair finder available; using the CPU path\n";
    }
    if (wantOpenCl && openClFinder && (b == Backend::OpenCL || openClFinder->runsOnGpu())) {
      st.usedOpenCl = true;
      return *openClFinder;
    }
    return *cpuFinder;
  }

  PairFinderOptions options() const {
    PairFinderOptions o;
    o.bruteForceBelow = config.bruteForceBelow < 0 ? 0u : std::uint32_t(config.bruteForceBelow);
    o.cellSizeRule = tuning.densityCellSize ? CellSizeRule::Density : CellSizeRule::Size;
    o.output = tuning.bitMaskOutput ? PairOutput::BitMask : PairOutput::Compacted;
    o.mappingSqrt = tuning.newtonSqrt ? MappingSqrt::Newton : MappingSqrt::Double;
    o.hugeCellLimit = tuning.hugeCellLimit;
    return o;
  }

  void removeDeferred(btDispatcher* dispatcher);

  std::size_t memoryBytes(const PairFinder& finder) const {
    return proxies.size() * sizeof(GridProxy) +
           flags.capacity() * (6 * sizeof(float) + 2 * sizeof(std::int32_t) + 3) +
           (freeSlots.capacity() + pendingFree.capacity()) * 4 +
           (accepted.capacity() + found.capacity() + added.capacity() + refused.capacity() +
            removedKeys.capacity()) *
               8 +
           finder.stats().scratchBytes;
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
    if (d.proxies.size() >= std::size_t(0xffffffffu))
      throw std::length_error("gpucol::GridBroadphase: more than 2^32 - 1 proxies");
    slot = std::uint32_t(d.proxies.size());
    d.proxies.emplace_back();
    for (auto* v : {&d.minX, &d.minY, &d.minZ, &d.maxX, &d.maxY, &d.maxZ}) v->push_back(0.0f);
    d.group.push_back(0), d.mask.push_back(0), d.flags.push_back(0), d.freedSinceSearch.push_back(0);
    d.moved.push_back(0);
    d.nonFinite.push_back(0);
  }
  GridProxy& p = d.proxies[slot];
  static_cast<btBroadphaseProxy&>(p) =
      btBroadphaseProxy(aabbMin, aabbMax, userPtr, collisionFilterGroup, collisionFilterMask);
  (void)shapeType;  // Bullet 3 proxies no longer store the shape type
  p.m_uniqueId = ++d.nextUniqueId;
  p.slot = slot;
  d.store(slot, aabbMin, aabbMax);
  d.group[slot] = collisionFilterGroup;
  d.mask[slot] = collisionFilterMask;
  d.flags[slot] = Impl::flagsOf(collisionFilterGroup);
  if (d.flags[slot] & kProxyStatic) ++d.staticCount;
  d.moved[slot] = 1;
  ++d.liveCount;
  d.dirty = true;
  return &p;
}

void GridBroadphase::destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) {
  Impl& d = *m_impl;
  GridProxy* p = static_cast<GridProxy*>(proxy);
  const std::uint32_t slot = p->slot;
  if (slot >= d.proxies.size() || &d.proxies[slot] != p || !(d.flags[slot] & kProxyActive))
    throw std::invalid_argument(
        "gpucol::GridBroadphase::destroyProxy: proxy does not belong to this broad phase");
  // Its pairs leave the cache now (algorithms and manifolds freed through the dispatcher); the keys in
  // `accepted` are dropped at the next search, and the slot is reused only after that search.
  d.pairCache->removeOverlappingPairsContainingProxy(proxy, dispatcher);
  if (d.flags[slot] & kProxyStatic) --d.staticCount;
  d.flags[slot] = 0;
  d.setNonFinite(slot, false);
  d.freedSinceSearch[slot] = 1;
  d.pendingFree.push_back(slot);
  --d.liveCount;
  d.dirty = true;
}

void GridBroadphase::setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                             btDispatcher* /*dispatcher*/) {
  Impl& d = *m_impl;
  const std::uint32_t s = static_cast<GridProxy*>(proxy)->slot;
  proxy->m_aabbMin = aabbMin;
  proxy->m_aabbMax = aabbMax;
  // Unchanged boxes (Bullet re-sends every AABB by default, m_forceUpdateAllAabbs) leave the step clean,
  // so a scene at rest costs no search.
  if (d.minX[s] != aabbMin.x() || d.minY[s] != aabbMin.y() || d.minZ[s] != aabbMin.z() ||
      d.maxX[s] != aabbMax.x() || d.maxY[s] != aabbMax.y() || d.maxZ[s] != aabbMax.z()) {
    d.store(s, aabbMin, aabbMax);
    d.moved[s] = 1;
    d.dirty = true;
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
  for (std::uint32_t s = 0; s < d.flags.size(); ++s) {
    if (!(d.flags[s] & kProxyActive) || d.nonFinite[s]) continue;
    GridProxy& p = d.proxies[s];
    const btVector3 bounds[2] = {p.m_aabbMin - aabbMax, p.m_aabbMax - aabbMin};
    btScalar tmin = 0;
    if (btRayAabb2(rayFrom, rayCallback.m_rayDirectionInverse, rayCallback.m_signs, bounds, tmin, 0,
                   lambdaMax))
      rayCallback.process(&p);
  }
}

void GridBroadphase::aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                              btBroadphaseAabbCallback& callback) {
  Impl& d = *m_impl;
  for (std::uint32_t s = 0; s < d.flags.size(); ++s) {
    if (!(d.flags[s] & kProxyActive) || d.nonFinite[s]) continue;
    // Touching counts, as in btDbvtAabbMm's Intersect.
    if (d.minX[s] <= aabbMax.x() && d.maxX[s] >= aabbMin.x() && d.minY[s] <= aabbMax.y() &&
        d.maxY[s] >= aabbMin.y() && d.minZ[s] <= aabbMax.z() && d.maxZ[s] >= aabbMin.z())
      callback.process(&d.proxies[s]);
  }
}

void GridBroadphase::calculateOverlappingPairs(btDispatcher* dispatcher) {
  Impl& d = *m_impl;
  GridBroadphaseStats st;
  st.proxies = d.liveCount;
  // Proxies whose static bit flips in the scan below (rare: a filter edited on the proxy).
  std::atomic<std::int64_t> staticDelta{0};
  // Filters may be edited on the proxy after creation (Bullet code does so); take them from there. In
  // parallel: each slot is written by one task only (this scan of every proxy was serial work at 1M).
  const bool filterChanged = tbb::parallel_reduce(
      tbb::blocked_range<std::uint32_t>(0, std::uint32_t(d.flags.size()), kScanGrain), false,
      [&](const tbb::blocked_range<std::uint32_t>& r, bool changed) {
        // A deque iterator steps through the proxies; indexing the deque costs a division per proxy.
        auto proxy = d.proxies.cbegin() + std::ptrdiff_t(r.begin());
        for (std::uint32_t s = r.begin(); s != r.end(); ++s, ++proxy) {
          if (!(d.flags[s] & kProxyActive)) continue;
          const GridProxy& p = *proxy;
          if (d.group[s] != p.m_collisionFilterGroup || d.mask[s] != p.m_collisionFilterMask) {
            d.group[s] = p.m_collisionFilterGroup;
            d.mask[s] = p.m_collisionFilterMask;
            const bool wasStatic = d.flags[s] & kProxyStatic;
            d.flags[s] = Impl::flagsOf(p.m_collisionFilterGroup);
            if (wasStatic != bool(d.flags[s] & kProxyStatic)) staticDelta += wasStatic ? -1 : 1;
            d.moved[s] = 1;
            changed = true;
          }
        }
        return changed;
      },
      [](bool a, bool b) { return a || b; });
  d.staticCount = std::uint32_t(std::int64_t(d.staticCount) + staticDelta.load());
  st.staticProxies = d.staticCount;
  if (filterChanged) d.dirty = true;
  if (!d.dirty) {
    st.overlappingPairs = d.stats.overlappingPairs;
    st.memoryBytes = d.stats.memoryBytes;
    d.stats = st;
    return;
  }
  st.searched = true;
  PairFinder& finder = d.chooseFinder(st);
  ProxyArrays view = d.view();
  // `moved` is relative to the previous search of the same finder; after a switch of finder, all moved.
  if (&finder != d.lastFinder) view.moved = nullptr;
  const auto searchStart = std::chrono::steady_clock::now();
  finder.findPairs(view, d.options(), d.found);
  const auto cacheStart = std::chrono::steady_clock::now();
  st.searchMs = std::chrono::duration<double, std::milli>(cacheStart - searchStart).count();
  const PairFinderStats& fs = finder.stats();
  st.chooseMs = fs.chooseMs, st.binMs = fs.binMs, st.testMs = fs.testMs, st.hugeMs = fs.hugeMs;
  st.sortMs = fs.sortMs;
  d.lastFinder = &finder;
  std::fill(d.moved.begin(), d.moved.end(), std::uint8_t(0));
  st.usedGrid = finder.stats().usedGrid;
  st.restingProxies = finder.stats().restingProxies;
  st.rebinnedProxies = finder.stats().rebinnedProxies;
  st.cellSize = finder.stats().cellSize;
  st.overlappingPairs = d.found.size();

  // The pairs in the cache after this step are `found` less the additions the cache refuses: the diff
  // collects the changes, the cache gets the removals then the additions (each in key order), and `found`
  // becomes the new `accepted`, without a third pair-sized list.
  d.added.clear();
  d.removedKeys.clear();
  diffSortedPairs(
      d.accepted, d.found, [&](std::uint64_t key) { d.added.push_back(key); },
      [&](std::uint64_t key) {
        // Pairs of destroyed proxies were removed by destroyProxy already.
        if (!d.freedSinceSearch[std::uint32_t(key >> 32)] && !d.freedSinceSearch[std::uint32_t(key)])
          d.removedKeys.push_back(key);
      },
      [](std::uint64_t) {});
  auto proxy0 = [&](std::uint64_t key) { return &d.proxies[std::uint32_t(key >> 32)]; };
  auto proxy1 = [&](std::uint64_t key) { return &d.proxies[std::uint32_t(key)]; };
  btOverlappingPairCache* cache = d.pairCache;
  st.removed = d.removedKeys.size();
  if (!cache->hasDeferredRemoval()) {
    for (const std::uint64_t key : d.removedKeys)
      cache->removeOverlappingPair(proxy0(key), proxy1(key), dispatcher);
  }
  d.refused.clear();
  for (const std::uint64_t key : d.added) {
    // The cache's own filter (overlap filter callback) has the last word; a refused pair is asked again
    // next step while it still overlaps, since the callback may change its mind.
    if (!cache->needsBroadphaseCollision(proxy0(key), proxy1(key))) {
      d.refused.push_back(key);
      continue;
    }
    cache->addOverlappingPair(proxy0(key), proxy1(key));
    ++st.added;
  }
  if (!d.refused.empty()) {
    // Both lists are sorted: drop the refused keys from `found` in one walk.
    std::size_t r = 0, kept = 0;
    for (const std::uint64_t key : d.found) {
      while (r < d.refused.size() && d.refused[r] < key) ++r;
      if (r == d.refused.size() || d.refused[r] != key) d.found[kept++] = key;
    }
    d.found.resize(kept);
  }
  d.accepted.swap(d.found);
  if (!cache->hasDeferredRemoval()) d.removedKeys.clear();
  if (!d.removedKeys.empty()) d.removeDeferred(dispatcher);  // handled in one pass over the cache
  for (std::uint32_t s : d.pendingFree) {
    d.freedSinceSearch[s] = 0;
    d.freeSlots.push_back(s);
  }
  d.pendingFree.clear();
  d.dirty = false;
  st.memoryBytes = d.memoryBytes(finder);
  st.cacheMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cacheStart).count();
  d.stats = st;
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
  for (std::uint32_t s = 0; s < d.flags.size(); ++s) {
    if (!(d.flags[s] & kProxyActive) || d.nonFinite[s]) continue;
    const btVector3 lo(d.minX[s], d.minY[s], d.minZ[s]), hi(d.maxX[s], d.maxY[s], d.maxZ[s]);
    if (!any) {
      aabbMin = lo, aabbMax = hi, any = true;
    } else {
      aabbMin.setMin(lo);
      aabbMax.setMax(hi);
    }
  }
  if (!any) aabbMin = aabbMax = btVector3(0, 0, 0);
}

void GridBroadphase::resetPool(btDispatcher* /*dispatcher*/) {
  Impl& d = *m_impl;
  if (d.liveCount != 0) return;
  d.proxies.clear();
  for (auto* v : {&d.minX, &d.minY, &d.minZ, &d.maxX, &d.maxY, &d.maxZ}) std::vector<float>().swap(*v);
  std::vector<std::int32_t>().swap(d.group);
  std::vector<std::int32_t>().swap(d.mask);
  std::vector<std::uint8_t>().swap(d.flags);
  std::vector<std::uint8_t>().swap(d.freedSinceSearch);
  std::vector<std::uint8_t>().swap(d.moved);
  std::vector<std::uint8_t>().swap(d.nonFinite);
  d.nonFiniteCount = 0;
  d.lastFinder = nullptr;
  d.freeSlots.clear(), d.pendingFree.clear(), d.accepted.clear();
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

void GridBroadphase::setTuning(const GridBroadphaseTuning& tuning) {
  m_impl->tuning = tuning;
  m_impl->dirty = true;
  m_impl->lastFinder = nullptr;  // a full search with the new options
}

const GridBroadphaseStats& GridBroadphase::stats() const {
  return m_impl->stats;
}

}  // namespace gpucol
