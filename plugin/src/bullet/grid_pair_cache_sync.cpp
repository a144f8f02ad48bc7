// Bullet's pair cache kept in sync with the pair finder's sorted list: the diff with the last step's list, and
// the cache's calls for the changes only (DESIGN.md, data flow).
#include "bullet/grid_broadphase_impl.h"

namespace gpucol {

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

}  // namespace gpucol
