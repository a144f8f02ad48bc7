// The broad phase's studies of `gpucol-bench accuracy`: the square root behind the mapping function's first guess
// (paper §3.3) and the grid's cell size (§4.1).
#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <set>
#include <utility>
#include <random>
#include <string>
#include <vector>

#include "accuracy_row.h"
#include "bench_stats.h"
#include "bullet/grid_broadphase_options.h"
#include "gpucol/grid_broadphase.h"
#include "shared_math/pair_mapping.h"

namespace gpucol::bench {
namespace {

// A guess of the row of pair index k: the double square root (-1 steps here) or the magic-constant root with
// `steps` Newton steps.
gpucol_u64 rowGuess(gpucol_u64 n, gpucol_u64 k, int steps) {
  return steps < 0 ? gpucol_pair_row_guess_double(n, k) : gpucol_pair_row_guess_newton_steps(n, k, steps);
}

std::string sqrtName(int steps) {
  return steps < 0 ? std::string("double") : "newton " + std::to_string(steps);
}

void mappingStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  const std::uint64_t mappings = context.quick ? 1000000 : 10000000;
  for (const gpucol_u64 n : {gpucol_u64(100000), gpucol_u64(10000000)}) {
    const gpucol_u64 pairs = gpucol_pair_count(n);
    std::mt19937_64 rng(99);
    std::uniform_int_distribution<gpucol_u64> pick(0, pairs - 1);
    std::vector<gpucol_u64> ks(mappings);
    for (gpucol_u64& k : ks) k = pick(rng);
    for (int steps : {-1, 1, 2, 3}) {
      // How often the guess is not the row: the integer fix-up then moves it (the answer is exact either way).
      std::uint64_t wrong = 0;
      for (gpucol_u64 k : ks) wrong += rowGuess(n, k, steps) != gpucol_pair_fix_row(n, k, rowGuess(n, k, -1));
      // Time of guess + fix-up, one thread; the sum keeps the work from being optimised away. A guess that is
      // mostly wrong leaves the fix-up walking many rows per index, so it is timed on a hundredth of them.
      const std::size_t timed = wrong * 2 > mappings ? ks.size() / 100 : ks.size();
      volatile gpucol_u64 sink = 0;
      std::vector<double> samples;
      for (int run = 0; run < context.runs; ++run) {
        samples.push_back(millisecondsOf([&] {
          gpucol_u64 sum = 0;
          for (std::size_t i = 0; i < timed; ++i) sum += gpucol_pair_fix_row(n, ks[i], rowGuess(n, ks[i], steps));
          sink = sink + sum;
        }));
      }
      AccuracyRow row;
      row.study = "mapping_sqrt";
      row.scene = "n = " + std::to_string(n);
      row.setting = sqrtName(steps);
      row.isDefault = steps < 0;  // PairFinderOptions::mappingSqrt defaults to the double root.
      row.timeMs = median(samples) * (1e7 / double(timed));
      row.guessErrorRate = double(wrong) / double(mappings);
      row.mappingSqrt = row.setting;
      printAccuracyRow(row);
      rows.push_back(std::move(row));
    }
  }
}

// Boxes of a cell size study: unit boxes, or half extents from 0.1 to 2 ("mixed"), one per 8 m^3 on average.
struct BoxSet {
  std::string name;
  std::vector<btVector3> lo, hi;
};

BoxSet makeBoxes(std::size_t n, bool mixed, unsigned seed) {
  BoxSet set;
  set.name = std::string(mixed ? "mixed sizes " : "unit boxes ") + std::to_string(n);
  const float side = std::cbrt(8.0f * float(n));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> position(0.0f, side), size(0.1f, 2.0f);
  for (std::size_t i = 0; i < n; ++i) {
    const btVector3 centre(position(rng), position(rng), position(rng));
    const btVector3 half = mixed ? btVector3(size(rng), size(rng), size(rng)) : btVector3(0.5f, 0.5f, 0.5f);
    set.lo.push_back(centre - half);
    set.hi.push_back(centre + half);
  }
  return set;
}

// Every overlapping pair (touching counts) by sweeping along x: an independent reference for the grid.
std::set<std::pair<std::size_t, std::size_t>> sweepPairs(const BoxSet& set) {
  std::vector<std::size_t> order(set.lo.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return set.lo[a].x() < set.lo[b].x(); });
  std::set<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t a = order[i];
    for (std::size_t j = i + 1; j < order.size() && set.lo[order[j]].x() <= set.hi[a].x(); ++j) {
      const std::size_t b = order[j];
      if (set.lo[a].y() <= set.hi[b].y() && set.lo[b].y() <= set.hi[a].y() && set.lo[a].z() <= set.hi[b].z() &&
          set.lo[b].z() <= set.hi[a].z()) {
        pairs.insert({std::min(a, b), std::max(a, b)});
      }
    }
  }
  return pairs;
}

void cellSizeStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  const std::size_t n = context.quick ? 10000 : 100000;
  for (const bool mixed : {false, true}) {
    const BoxSet set = makeBoxes(n, mixed, 5);
    const auto reference = sweepPairs(set);
    for (const bool density : {false, true}) {
      GridBroadphase grid;
      GridBroadphaseOptions options;
      options.densityCellSize = density;
      detail::GridBroadphaseAccess::setOptions(grid, options);
      btDefaultCollisionConfiguration configuration;
      btCollisionDispatcher dispatcher(&configuration);
      std::vector<btBroadphaseProxy*> proxies;
      for (std::size_t i = 0; i < n; ++i) {
        proxies.push_back(grid.createProxy(set.lo[i], set.hi[i], BOX_SHAPE_PROXYTYPE, reinterpret_cast<void*>(i),
                                           btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter,
                                           &dispatcher));
      }
      grid.calculateOverlappingPairs(&dispatcher);
      // A step with every box re-sent a hair away and back, so that every proxy is re-binned: the full search.
      std::vector<double> samples;
      for (int run = 0; run < context.runs; ++run) {
        const btVector3 shift((run % 2) ? -1e-3f : 1e-3f, 0, 0);
        samples.push_back(millisecondsOf([&] {
          for (std::size_t i = 0; i < n; ++i) {
            grid.setAabb(proxies[i], set.lo[i] + (run % 2 ? btVector3(0, 0, 0) : shift),
                         set.hi[i] + (run % 2 ? btVector3(0, 0, 0) : shift), &dispatcher);
          }
          grid.calculateOverlappingPairs(&dispatcher);
        }));
      }
      // Errors after a final step at the set's own boxes.
      for (std::size_t i = 0; i < n; ++i) grid.setAabb(proxies[i], set.lo[i], set.hi[i], &dispatcher);
      grid.calculateOverlappingPairs(&dispatcher);
      std::set<std::pair<std::size_t, std::size_t>> found;
      btOverlappingPairCache* cache = grid.getOverlappingPairCache();
      for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        const btBroadphasePair& p = cache->getOverlappingPairArray()[i];
        const auto a = reinterpret_cast<std::size_t>(p.m_pProxy0->m_clientObject);
        const auto b = reinterpret_cast<std::size_t>(p.m_pProxy1->m_clientObject);
        found.insert({std::min(a, b), std::max(a, b)});
      }
      AccuracyRow row;
      row.study = "cell_size";
      row.scene = set.name;
      row.setting = density ? "density rule" : "size rule";
      row.isDefault = !density;
      row.timeMs = median(samples);
      double missed = 0, extra = 0;
      for (const auto& p : reference) missed += !found.count(p);
      for (const auto& p : found) extra += !reference.count(p);
      row.broadphaseMissed = missed;
      row.broadphaseExtra = extra;
      row.cellRule = row.setting + " (cell " + std::to_string(grid.stats().cellSize) + " m)";
      printAccuracyRow(row);
      rows.push_back(std::move(row));
    }
  }
}

}  // namespace

void runBroadphaseAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  std::cout << "mapping_sqrt: share of first guesses off the row (fixed exactly afterwards), ms per 10^7 indices\n";
  mappingStudy(context, rows);
  std::cout << "cell_size: the grid's cell size rule, pairs against a sweep along x, ms per step with every box "
               "re-sent\n";
  cellSizeStudy(context, rows);
}

}  // namespace gpucol::bench
