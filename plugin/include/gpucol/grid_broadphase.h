#pragma once

#include <BulletCollision/BroadphaseCollision/btBroadphaseInterface.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>

#include <cstddef>
#include <cstdint>
#include <memory>

#include "gpucol/config.h"

namespace gpucol {

namespace detail {
struct GridBroadphaseAccess;  // tests and gpucol-bench: bullet/grid_broadphase_options.h
}  // namespace detail

/// What the last calculateOverlappingPairs did.
struct GridBroadphaseStats {
  /// Live proxies.
  std::uint32_t proxies = 0;
  /// Pairs found overlapping (before the pair cache's own filter callback).
  std::uint64_t overlappingPairs = 0;
  /// Pairs added to the pair cache by the last step.
  std::uint64_t added = 0;
  /// Pairs removed from the pair cache by the last step.
  std::uint64_t removed = 0;
  /// True when the search ran at all (false when no proxy moved, appeared or vanished).
  bool searched = false;
  /// True when the grid was used (false: brute force through the mapping function).
  bool usedGrid = false;
  /// True when the OpenCL pair finder ran.
  bool usedOpenCl = false;
  /// True when a small scene's step (under Config::bruteForceBelow, CPU path) tested only the pairs of the
  /// boxes grown at its last search: every box stayed inside its grown box (an eighth of its largest side
  /// on every side), so its pairs are among those.
  bool grownPairsTested = false;
  /// True when a larger scene's step (CPU path) searched nothing: after a search that changed no pair, every
  /// box stayed within its slack of its box at that search (half the smallest margin by which it overlapped or
  /// missed a box near it, at most a sixteenth of its largest side), so no pair can have changed.
  bool boxesQuiet = false;
  /// Live proxies that were neither re-binned nor tested against each other this step: static or sleeping
  /// ones whose box and filter did not change since the grid was last built (their pairs carry over).
  std::uint32_t restingProxies = 0;
  /// Live proxies with Bullet's static filter group: two of them pair only where their masks accept each
  /// other, as in Bullet (its static objects' mask refuses the static group), and while they rest they are
  /// neither re-binned nor tested (`restingProxies`).
  std::uint32_t staticProxies = 0;
  /// Live proxies binned (or tested against all) this step: every one on a full search, else the moved.
  std::uint32_t rebinnedProxies = 0;
  /// Edge of the grid's cubic cells (0 without grid).
  float cellSize = 0.0f;
  /// True when the boxes, read in place (single-precision Bullet), were surveyed for the grid
  /// choice by the step's scan of the proxies, which then read no box itself.
  bool boxesSurveyed = false;
  /// Bytes the broad phase holds between steps: the proxies Bullet holds (56 bytes each, in blocks of 256),
  /// the filter and state per slot (9 bytes), free-slot lists, the last step's sorted pair keys (8 bytes
  /// per pair, plus the few the cache's filter refused; the CPU finder carries resting pairs over from
  /// them), and what the pair finder keeps between searches (the CPU finder, after a whole-grid search: the
  /// home-cell order of the binned boxes, 8 bytes per proxy; while few proxies move, the kept grid of
  /// stage 11), and what the last search kept for the steps after it (`grownPairsTested`, `boxesQuiet`: for a
  /// larger scene its boxes and their slacks, 28 bytes per slot). Allocated capacities are counted, not
  /// sizes. Bullet's pair cache (btHashedOverlappingPairCache or the user's) is not counted: it belongs to
  /// Bullet.
  std::size_t memoryBytes = 0;
  /// Bytes at the peak of the last step: memoryBytes plus the scratch of the step that is released at its
  /// end (the boxes' structure-of-arrays view, the finder's working arrays at their high-water mark, the last
  /// step's pair list and the diff's lists of changes until the cache has them); the same exclusions. This
  /// step's pair list is counted beside the finder's arrays as far as it was there at that mark (the CPU
  /// finder's slab search is done before its pairs are gathered), in full for a finder that does not say.
  /// Never less than what was held when the search began. tests/memory checks it against the heap.
  std::size_t peakBytes = 0;
  /// Wall-clock milliseconds of the pair search, and of the diff with the last step plus the pair cache's
  /// additions and removals.
  double searchMs = 0, cacheMs = 0;
  /// Wall-clock milliseconds of the stages of a full grid search on the CPU (0 otherwise): cell size and
  /// huge split, binning and sort by cell, candidate tests, huge boxes, gather and sort of the pairs.
  double chooseMs = 0, binMs = 0, testMs = 0, hugeMs = 0, sortMs = 0;
};

/// How rayTest and aabbTest have been answered since the broad phase was made.
struct GridBroadphaseQueryStats {
  /// Queries answered by testing every proxy (few proxies, few queries since the boxes changed, or a
  /// region so large that the index would visit more cells than there are boxes).
  std::uint64_t scans = 0;
  /// Queries answered through the query index (the proxies in the cells the query reaches).
  std::uint64_t indexed = 0;
  /// Times the query index was built.
  std::uint64_t indexBuilds = 0;
  /// Bytes the query index holds now (0 while there is none); not part of GridBroadphaseStats::memoryBytes.
  std::size_t indexBytes = 0;
};

/// A btBroadphaseInterface that finds exactly the pairs whose AABBs overlap (touching counts) with a uniform
/// grid and the pair-index mapping function of Avril et al. 2012, on the CPU (oneTBB) or through OpenCL,
/// and keeps the pair cache in sync incrementally. Put it where btDbvtBroadphase was.
class GridBroadphase : public btBroadphaseInterface {
 public:
  /// A broad phase with `config`'s backend and thresholds; `pairCache` is used if given (not owned),
  /// else a btHashedOverlappingPairCache is created and owned.
  explicit GridBroadphase(const Config& config = Config{}, btOverlappingPairCache* pairCache = nullptr);
  /// Destroys the broad phase (and the pair cache when it owns it).
  ~GridBroadphase() override;
  GridBroadphase(const GridBroadphase&) = delete;
  GridBroadphase& operator=(const GridBroadphase&) = delete;

  /// Creates a proxy owned by the broad phase (its address stays valid until destroyProxy).
  btBroadphaseProxy* createProxy(const btVector3& aabbMin, const btVector3& aabbMax, int shapeType,
                                 void* userPtr, int collisionFilterGroup, int collisionFilterMask,
                                 btDispatcher* dispatcher) override;
  /// Removes the proxy's pairs from the pair cache (through `dispatcher`) and frees the proxy.
  void destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) override;
  /// Stores the proxy's new AABB; pairs follow at the next calculateOverlappingPairs.
  void setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
               btDispatcher* dispatcher) override;
  /// The AABB last given to createProxy or setAabb.
  void getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const override;
  /// Reports every proxy whose AABB (grown by -aabbMax/-aabbMin, as btDbvtBroadphase does) the ray hits
  /// within [0, rayCallback.m_lambda_max], with Bullet's btRayAabb2 test, in slot order. Once the queries
  /// since the boxes last changed have cost about as much as building it, a query index (the boxes filed
  /// by grid cell) names the candidates; the answer is the same either way. Concurrent queries are safe;
  /// a query concurrent with setAabb, createProxy or destroyProxy is not (as with Bullet's broad phases).
  void rayTest(const btVector3& rayFrom, const btVector3& rayTo, btBroadphaseRayCallback& rayCallback,
               const btVector3& aabbMin = btVector3(0, 0, 0),
               const btVector3& aabbMax = btVector3(0, 0, 0)) override;
  /// Reports every proxy whose AABB overlaps [aabbMin, aabbMax] (touching counts), in slot order; through
  /// the query index as rayTest.
  void aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                btBroadphaseAabbCallback& callback) override;
  /// Finds the overlapping pairs and adds/removes the difference to the last step in the pair cache.
  void calculateOverlappingPairs(btDispatcher* dispatcher) override;
  /// The pair cache (owned or user-supplied).
  btOverlappingPairCache* getOverlappingPairCache() override;
  /// The pair cache (owned or user-supplied).
  const btOverlappingPairCache* getOverlappingPairCache() const override;
  /// The union of all proxies' AABBs (a zero box when there is none), as btDbvtBroadphase reports it.
  void getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const override;
  /// Releases the internal storage when no proxy is left (ensures reproducible runs, like btDbvtBroadphase).
  void resetPool(btDispatcher* dispatcher) override;
  /// Prints proxy and pair counts and the last step's path to stdout.
  void printStats() override;

  /// Statistics of the last calculateOverlappingPairs.
  const GridBroadphaseStats& stats() const;
  /// How the queries (rayTest, aabbTest) were answered so far.
  GridBroadphaseQueryStats queryStats() const;

 private:
  friend struct detail::GridBroadphaseAccess;
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace gpucol
