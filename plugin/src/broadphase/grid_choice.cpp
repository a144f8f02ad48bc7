#include "broadphase/grid_choice.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gpucol {
namespace {

/// Size rule: cell edge = this × median largest extent. Smaller cells mean more keys per box, larger ones
/// more candidate pairs per cell. 2 was measured best of {1, 1.5, 2, 3} on the benchmark scenes when the
/// finder was first written; against 2.5 and 3 on the finder of 87f6dc4, at 100K boxes, the three were alike
/// within the noise (measurement history, "The size rule's factor measured again").
constexpr float kSizeFactor = 2.0f;
/// Density rule (paper §4.1): the cell volume that holds this many objects on average.
constexpr float kObjectsPerCell = 4.0f;
/// Cell coordinates must fit the 32-bit cell index of a key (dims product < 2^32).
constexpr std::uint64_t kMaxCells = (std::uint64_t(1) << 32) - 1;
/// Above this many boxes the median extent is taken over a regular sample of about this many.
constexpr std::size_t kMedianSamples = 4096;
/// Boxes per parallel task of the stage's loops.
constexpr std::size_t kChunk = 16384;
/// A survey's cell edge is taken while it is within this factor of the one this search's sample gives.
constexpr float kSurveyCellRatio = 2.0f;
/// The bounds of no box.
constexpr float kInf = std::numeric_limits<float>::infinity();
/// The search by home cell serves when, in stage 2's sample, at most kHomeLargerShare of the boxes have a
/// largest extent over kHomeExtentRatio times the median: its cells are as large as the largest of the
/// others, so the larger that is beside the median, the more boxes a cell's neighbours hold; and each larger
/// box (a ground, a wall) is searched on its own, as a huge or a wide box.
constexpr float kHomeExtentRatio = 1.5f;
constexpr float kHomeLargerShare = 1.0f / 64.0f;
/// ... and when its grid has at most this many cells per binned box (plus kHomeCellsSlack): each slab's
/// thread holds a start per cell of its slab.
constexpr std::uint64_t kHomeCellsPerBox = 16;
constexpr std::uint64_t kHomeCellsSlack = 1024;
/// The home grid's cell is this much larger than the sample's largest extent, so that rounding in cellOf
/// does not make boxes of that extent span three cells (those that still do are searched as wide boxes).
constexpr float kHomeCellMargin = 1.0f + 1.0f / 1024.0f;

/// Min and max corners of a set of boxes.
struct Bounds {
  float lo[3];
  float hi[3];
};

/// Bounds of the boxes slots[begin, end) (not empty), in parallel (min and max are exact in any order).
Bounds boundsOf(const ProxyArrays& p, const std::vector<std::uint32_t>& slots, std::size_t begin,
                std::size_t end) {
  const BoxCorners f = p.box(slots[begin]);
  const Bounds first{{f.lo[0], f.lo[1], f.lo[2]}, {f.hi[0], f.hi[1], f.hi[2]}};
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(begin, end, kChunk), first,
      [&](const tbb::blocked_range<std::size_t>& r, Bounds b) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const BoxCorners c = p.box(slots[i]);
          for (int a = 0; a < 3; ++a)
            b.lo[a] = std::min(b.lo[a], c.lo[a]), b.hi[a] = std::max(b.hi[a], c.hi[a]);
        }
        return b;
      },
      [](Bounds a, const Bounds& b) {
        for (int k = 0; k < 3; ++k)
          a.lo[k] = std::min(a.lo[k], b.lo[k]), a.hi[k] = std::max(a.hi[k], b.hi[k]);
        return a;
      });
}

/// Sets g's dims for boxes within [lo, hi] at cell edge `cell` (g.origin = lo); false when their count would
/// not fit 32 bits.
bool fitDims(const float lo[3], const float hi[3], float cell, Grid& g) {
  std::uint64_t total = 1;
  for (int a = 0; a < 3; ++a) {
    const double d = std::floor((double(hi[a]) - double(lo[a])) / double(cell)) + 1.0;
    if (!(d <= double(kMaxCells))) return false;
    g.dims[a] = std::uint32_t(d);
    total *= g.dims[a];
    if (total > kMaxCells) return false;
  }
  for (int a = 0; a < 3; ++a) g.origin[a] = lo[a];
  g.cell = cell;
  g.invCell = 1.0f / cell;
  return true;
}

}  // namespace

Grid chooseGrid(const ProxyArrays& p, const std::vector<std::uint32_t>& active,
                const PairFinderOptions& options, std::vector<float>& extentScratch,
                std::vector<std::uint32_t>& binned, std::vector<std::uint32_t>& huge, AxisExtents* kept,
                const BoxSurvey* survey, bool* surveyTaken, Grid* home) {
  const std::size_t n = active.size();
  // Stage 2: the median of the largest extent, robust to a few huge boxes (a mean would follow them). Above
  // kMedianSamples boxes, the median of every stride-th box: the cell size only sets the speed, never the
  // pairs. nth_element over every box was the larger part of this stage at 1M boxes (serial), and in place
  // (Bullet's proxies read where they are) a pass over every box is a walk over all of them in memory.
  const std::size_t stride = std::max<std::size_t>(1, n / kMedianSamples);
  const std::size_t samples = (n + stride - 1) / stride;
  extentScratch.resize(samples);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, samples, kChunk), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const BoxCorners b = p.box(active[i * stride]);
          extentScratch[i] = std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
        }
      });
  std::nth_element(extentScratch.begin(), extentScratch.begin() + std::ptrdiff_t(samples / 2),
                   extentScratch.end());
  const float median = extentScratch[samples / 2];
  // The home grid's cell: the largest sampled extent up to kHomeExtentRatio times the median (after
  // nth_element those lie above it), and how many sampled boxes are larger.
  const bool homeWanted = home && options.cellSizeRule == CellSizeRule::Size;
  float homeExtent = median;
  std::size_t larger = 0;
  for (std::size_t i = samples / 2; homeWanted && i < samples; ++i) {
    const float e = extentScratch[i];
    if (e <= kHomeExtentRatio * median)
      homeExtent = std::max(homeExtent, e);
    else
      ++larger;
  }
  float cell = kSizeFactor * median;
  if (options.cellSizeRule == CellSizeRule::Density || !(cell > 0.0f)) {
    const Bounds all = boundsOf(p, active, 0, n);
    // A flat scene has zero volume; count each axis at least one object thick so the rule stays finite.
    double volume = 1.0;
    for (int a = 0; a < 3; ++a) volume *= std::max(double(all.hi[a]) - double(all.lo[a]), double(median));
    const float density = float(std::cbrt(double(kObjectsPerCell) * volume / double(n)));
    if (density > 0.0f && std::isfinite(density)) cell = std::max(density, median);
  }
  if (!(cell > 0.0f) || !std::isfinite(cell)) cell = 1.0f;  // all boxes are points at one spot
  // The caller's survey, made at the last search's cell edge, serves while this sample's edge is within a
  // factor of kSurveyCellRatio of it (the cell edge only sets the speed; a scene whose sizes changed more
  // is read again, and the next survey is made at its new edge).
  const bool taken = survey && options.cellSizeRule == CellSizeRule::Size &&
                     survey->hugeCellLimit == options.hugeCellLimit && survey->cell > 0.0f &&
                     survey->cell <= kSurveyCellRatio * cell && cell <= kSurveyCellRatio * survey->cell &&
                     survey->lo[0] <= survey->hi[0] && survey->lo[1] <= survey->hi[1] &&
                     survey->lo[2] <= survey->hi[2];
  if (surveyTaken) *surveyTaken = taken;
  if (taken) cell = survey->cell;
  const float sizedCell = cell;

  // Stage 3 and the bounds of the binned boxes in one pass over fixed chunks of `active` (each box is read
  // once: in place, in Bullet's proxies, every pass is a walk over memory): a chunk's binned slots go to its
  // own stretch of `binned`, closed up afterwards, and its huge ones to a list of its own, so both lists
  // stay in `active` order.
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  binned.resize(n);
  const int keptAxis = kept && !taken ? kept->axis : -1;
  if (keptAxis >= 0) kept->lo.resize(n), kept->hi.resize(n);
  std::uint32_t* keptLo = keptAxis >= 0 ? kept->lo.data() : nullptr;
  std::uint32_t* keptHi = keptAxis >= 0 ? kept->hi.data() : nullptr;
  std::vector<std::vector<std::uint32_t>> chunkHuge(chunks);
  std::vector<Bounds> chunkBounds(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    const std::size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
    std::size_t b = begin;
    Bounds& box = chunkBounds[c];
    box = Bounds{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    if (taken) {  // the survey's huge slots, met in ascending order
      const std::vector<std::uint32_t>& listed = survey->huge;
      auto h = std::lower_bound(listed.begin(), listed.end(), active[begin]);
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t s = active[i];
        while (h != listed.end() && *h < s) ++h;
        if (h != listed.end() && *h == s)
          chunkHuge[c].push_back(s);
        else
          binned[b++] = s;
      }
      return;
    }
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t s = active[i];
      const BoxCorners corners = p.box(s);
      if (isHuge(corners, cell, options.hugeCellLimit)) {
        chunkHuge[c].push_back(s);
        continue;
      }
      if (keptLo) keptLo[b] = floatBits(corners.lo[keptAxis]), keptHi[b] = floatBits(corners.hi[keptAxis]);
      binned[b++] = s;
      for (int a = 0; a < 3; ++a)
        box.lo[a] = std::min(box.lo[a], corners.lo[a]), box.hi[a] = std::max(box.hi[a], corners.hi[a]);
    }
  });
  huge.clear();
  std::size_t closed = 0;
  Bounds box{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  for (std::size_t c = 0; c < chunks; ++c) {
    const std::size_t begin = c * kChunk, count = std::min(n, begin + kChunk) - begin - chunkHuge[c].size();
    if (closed != begin) {  // std::copy forward: the target starts before the source
      std::copy(binned.begin() + std::ptrdiff_t(begin), binned.begin() + std::ptrdiff_t(begin + count),
                binned.begin() + std::ptrdiff_t(closed));
      if (keptLo) {
        std::copy(keptLo + begin, keptLo + begin + count, keptLo + closed);
        std::copy(keptHi + begin, keptHi + begin + count, keptHi + closed);
      }
    }
    closed += count;
    huge.insert(huge.end(), chunkHuge[c].begin(), chunkHuge[c].end());
    for (int a = 0; a < 3; ++a)
      box.lo[a] = std::min(box.lo[a], chunkBounds[c].lo[a]),
      box.hi[a] = std::max(box.hi[a], chunkBounds[c].hi[a]);
  }
  binned.resize(closed);
  if (keptLo) kept->lo.resize(closed), kept->hi.resize(closed);
  if (taken)
    for (int a = 0; a < 3; ++a) box.lo[a] = survey->lo[a], box.hi[a] = survey->hi[a];

  Grid g;
  g.sizedCell = sizedCell;
  if (home) home->cell = 0.0f;
  if (binned.empty()) return g;
  // Coarsen until the cell index fits 32 bits: exactness never depends on the cell size.
  while (!fitDims(box.lo, box.hi, cell, g)) cell *= 2.0f;
  if (homeWanted && homeExtent > 0.0f && float(larger) <= kHomeLargerShare * float(samples)) {
    Grid h;
    h.sizedCell = sizedCell;
    if (fitDims(box.lo, box.hi, homeExtent * kHomeCellMargin, h) &&
        h.cells() <= kHomeCellsPerBox * binned.size() + kHomeCellsSlack)
      *home = h;
  }
  return g;
}

}  // namespace gpucol
