// GridBroadphase's proxies: made, moved and destroyed through Bullet's calls, kept in reserved blocks (stable
// addresses) with a state byte per slot; boxes that are not finite or are inverted are noted as they come.
#include "bullet/grid_broadphase_impl.h"

namespace gpucol {

void GridBroadphase::Impl::store(std::uint32_t s, const btVector3& lo, const btVector3& hi) {
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

void GridBroadphase::Impl::setInverted(std::uint32_t s, bool value) {
  if (bool(state[s] & kInverted) == value) return;
  dropKeptSearch();
  state[s] = std::uint8_t(value ? state[s] | kInverted : state[s] & ~kInverted);
  invertedCount += value ? 1 : -1;
  nonFiniteChanged = true;  // a life change for the finder, as a box turning non-finite
}

void GridBroadphase::Impl::setNonFinite(std::uint32_t s, bool value) {
  if (bool(state[s] & kNonFinite) == value) return;
  dropKeptSearch();
  state[s] = std::uint8_t(value ? state[s] | kNonFinite : state[s] & ~kNonFinite);
  nonFiniteCount += value ? 1 : -1;
  nonFiniteChanged = true;
}

std::string GridBroadphase::Impl::toString(const btVector3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%g, %g, %g)", double(v.x()), double(v.y()), double(v.z()));
  return text;
}

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

}  // namespace gpucol
