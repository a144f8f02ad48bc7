// gpucol::GridBroadphase: Bullet's side of the grid broad phase. Proxies live in fixed blocks (stable
// addresses) and are the one place a box is kept between steps; the finders read the boxes in the proxies
// (the OpenCL one as it uploads them); where they cannot (a double-precision Bullet), each search copies the
// live boxes as floats into a structure-of-arrays view (broadphase/grid_pair_finder.h) and drops it
// afterwards. Each step's sorted pair list is diffed against the last one so the pair cache only sees
// additions and removals (DESIGN.md, data flow): the diff lists them, then the cache gets them. That list is
// also the pair finder's previous result, which it carries resting pairs over from (no second copy is kept).
#include "gpucol/grid_broadphase.h"

#include "bullet/grid_broadphase_impl.h"

namespace gpucol {

void GridBroadphase::Impl::addInvertedPairs() {
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

void GridBroadphase::Impl::dropKeptSearch() {
  if (!grown.kept() && !quiet.kept()) return;
  grown.clear();
  quiet.clear();
  grownWait = grownReuses > 0 ? 0 : std::min(kGrownWaitMax, 2 * grownWait + 1);
  grownWaitLeft = grownWait;
}

bool GridBroadphase::Impl::keepSearch(const ProxyArrays& view) {
  if (grownWaitLeft > 0) {
    --grownWaitLeft;
    return false;
  }
  if (liveCount < options().bruteForceBelow) {
    grown.build(view);
    grownReuses = 0;
    return false;
  }
  return kProxyBoxesAreFloats;  // the slacks are taken on the boxes the finder reads
}

std::size_t GridBroadphase::Impl::keepQuietBoxes(std::size_t pairs) {
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

bool GridBroadphase::Impl::answerQuietly(btDispatcher* dispatcher, GridBroadphaseStats& st) {
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
  st.boxesQuiet = true;
  st.overlappingPairs = current.size();
  finishKeptStep(dispatcher, st, nullptr, start);
  return true;
}

void GridBroadphase::Impl::finishKeptStep(btDispatcher* dispatcher, GridBroadphaseStats& st,
                                          const std::vector<std::uint64_t>* changed,
                                          std::chrono::steady_clock::time_point start) {
  const auto cacheStart = std::chrono::steady_clock::now();
  ++grownReuses;
  st.searchMs = std::chrono::duration<double, std::milli>(cacheStart - start).count();
  // Nothing for the cache when no pair changed and none was refused (a refused pair found again is offered
  // again, diffAndUpdateCache); the kept pairs' overlaps were those of `current` after its search.
  if (changed || !refused.empty()) {
    if (changed)
      foundCoded.assign(*changed);
    else
      foundCoded.assign(current.toVector());
    diffAndUpdateCache(dispatcher, st);
    for (auto* v : {&addedKeys, &removedKeys}) std::vector<std::uint64_t>().swap(*v);
  }
  dirty = false;
  // What was kept is held between steps; the diff's lists of changes are small.
  st.memoryBytes = st.peakBytes = heldBytes();
  st.cacheMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cacheStart).count();
  stats = st;
}

bool GridBroadphase::Impl::answerFromGrownPairs(btDispatcher* dispatcher, GridBroadphaseStats& st) {
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
  st.searched = true;
  st.grownPairsTested = true;
  st.overlappingPairs = changed ? grownFound.size() : current.size();
  finishKeptStep(dispatcher, st, changed ? &grownFound : nullptr, start);
  return true;
}

PairFinder& GridBroadphase::Impl::chooseFinder(GridBroadphaseStats& st) {
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

void GridBroadphase::Impl::dropOpenCl(const std::string& why) {
  warnOnce("GridBroadphase OpenCL failure", "the OpenCL pair search failed (" + why +
                                                "); the broad phase continues on the CPU path");
  openClFinder.reset();
  openClTried = true;
  autoChoice.deviceFailed();
  autoMeasuring = false;
}

std::size_t GridBroadphase::Impl::heldBytes() const {
  std::size_t bytes = blockCount() * kBlockSize * sizeof(GridProxy) + (blocks ? blocks->tableBytes() : 0);
  bytes += (group.capacity() + mask.capacity() + acceptAll.capacity()) * sizeof(std::int32_t) + state.capacity();
  bytes += (freeSlots.capacity() + pendingFree.capacity()) * sizeof(std::uint32_t);
  bytes += current.bytes() + refused.capacity() * sizeof(std::uint64_t) + grown.bytes() + quiet.bytes() +
           grownFound.capacity() * sizeof(std::uint64_t);
  for (const PairFinder* f : {cpuFinder.get(), openClFinder.get()})
    if (f) bytes += f->stats().scratchBytes;
  return bytes;
}

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

btOverlappingPairCache* GridBroadphase::getOverlappingPairCache() {
  return m_impl->pairCache;
}

const btOverlappingPairCache* GridBroadphase::getOverlappingPairCache() const {
  return m_impl->pairCache;
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

}  // namespace gpucol
