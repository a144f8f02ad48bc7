// GridBroadphase's queries (rayTest, aabbTest): a scan of every proxy or, once the queries since the boxes last
// changed have cost about as much as building it, the query index (broadphase/query_grid.h), which follows
// moved boxes and is dropped when too many could not be refiled.
#include "bullet/grid_broadphase_impl.h"

namespace gpucol {

void GridBroadphase::Impl::dropQueryIndex() {
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

const QueryGrid* GridBroadphase::Impl::queryIndex() {
  if (indexReady.load(std::memory_order_acquire)) return &queryGrid;
  if (liveCount < kQueryIndexMinProxies || !internalOptions.queryIndex) return nullptr;
  if (scansSinceChange.fetch_add(1, std::memory_order_relaxed) < kScansBeforeIndex &&
      lastIndexQueries < kQueriesOfABusyIndex)
    return nullptr;
  std::lock_guard<std::mutex> lock(indexBuild);
  if (!indexReady.load(std::memory_order_relaxed)) buildQueryIndex();
  return &queryGrid;
}

void GridBroadphase::Impl::buildQueryIndex() {
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
