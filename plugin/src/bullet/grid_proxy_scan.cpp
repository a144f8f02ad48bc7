// The per-step scan of GridBroadphase's proxies: filter changes taken from the proxies, and the pair finder's
// view of every slot (flags, moved marks, boxes in place or copied, the survey for the grid choice).
#include "bullet/grid_broadphase_impl.h"

namespace gpucol {

void GridBroadphase::Impl::prepareSurvey() {
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

bool GridBroadphase::Impl::scan(bool fill) {
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

void GridBroadphase::Impl::releaseSurvey() {
  survey = BoxSurvey{};
  surveying = false;
}

BoxRecords GridBroadphase::Impl::boxRecords() const {
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

void GridBroadphase::Impl::copyBoxes(float* const axis[6]) const {
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

ProxyArrays GridBroadphase::Impl::finderView(bool readsRecords) {
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

}  // namespace gpucol
