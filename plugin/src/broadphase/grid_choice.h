#pragma once

// Stages 2–3 of the grid search (grid_pair_finder.h): the one grid choice shared by the CPU finder and the
// OpenCL finder, so both bin boxes into the same grid.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "broadphase/grid_pair_finder.h"

namespace gpucol {

/// The uniform grid of one search: origin, cell edge and cells per axis (their product fits 32 bits).
struct Grid {
  float origin[3] = {0, 0, 0};        ///< Lower corner: the min corner of all binned boxes.
  float cell = 1.0f;                  ///< Cell edge length.
  float sizedCell = 1.0f;             ///< Stage 2's cell edge, before any doubling to fit 32 bits.
  float invCell = 1.0f;               ///< 1 / cell.
  std::uint32_t dims[3] = {1, 1, 1};  ///< Cells per axis.
  /// Number of cells.
  std::uint64_t cells() const { return std::uint64_t(dims[0]) * dims[1] * dims[2]; }
};

/// Cell coordinate of x on one axis: floor((x - origin) * invCell) clamped to [0, dim-1]. Monotone in x
/// (float subtraction and multiplication by a positive number round monotonically), which is all the
/// dedupe rule needs: the overlap's min corner lies inside both boxes, so its cell lies in both ranges.
inline std::uint32_t cellOf(float x, float origin, float invCell, std::uint32_t dim) {
  const float t = (x - origin) * invCell;
  if (!(t > 0.0f)) return 0;
  if (t >= float(dim - 1)) return dim - 1;
  return std::min(std::uint32_t(t), dim - 1);
}

/// A grid of at most this many cells for `binned` boxes is dense: both finders sort its entries by a
/// counting sort over its cells (stage 5), since a count per cell then costs about as much as the entries.
inline std::uint64_t denseCellLimit(std::size_t binned) {
  return 8 * std::uint64_t(binned) + 1024;
}

/// Stage 3's test: a box that covers more than `limit` cells of edge `cell` (estimated from its extents,
/// independent of the grid's origin) is tested against all instead of being binned.
inline bool isHuge(const BoxCorners& b, float cell, std::uint32_t limit) {
  // A box with min > max on an axis (a user's bug) lies in no cell: kept aside, so that the query index names
  // it to every query, whose exact test decides (GridBroadphase pairs such boxes itself, apart from the finders).
  if (!(b.lo[0] <= b.hi[0] && b.lo[1] <= b.hi[1] && b.lo[2] <= b.hi[2])) return true;
  const double inv = 1.0 / double(cell);
  const double covered = (double(b.hi[0] - b.lo[0]) * inv + 1.0) * (double(b.hi[1] - b.lo[1]) * inv + 1.0) *
                         (double(b.hi[2] - b.lo[2]) * inv + 1.0);
  return covered > double(limit);
}
/// Stage 3's test on slot s's box.
inline bool isHuge(const ProxyArrays& p, std::uint32_t s, float cell, std::uint32_t limit) {
  return isHuge(p.box(s), cell, limit);
}

/// Each binned box's extent along one axis, kept by chooseGrid for a slab plan when the boxes are read in
/// place: the plan's first pass then reads these 8 bytes per box instead of walking Bullet's proxies again,
/// and writes each box's packed layers over `lo`, which it then takes as its layer list (so the two are
/// never held beside each other). The floats are kept as their bits for that.
struct AxisExtents {
  int axis = -1;                  ///< The axis kept (-1: none); the caller's guess of the slab axis.
  bool bySlot = false;            ///< Indexed by slot (a BoxSurvey's) instead of by binned index.
  std::vector<std::uint32_t> lo;  ///< floatBits of binned[i]'s (or slot i's) min corner on `axis`.
  std::vector<std::uint32_t> hi;  ///< floatBits of binned[i]'s (or slot i's) max corner on `axis`.
};

/// The grid choice's reads of every box, made by the caller's own pass over them (GridBroadphase's per-step
/// scan of its proxies, when the boxes are read in place), so that a step walks Bullet's proxies once: at
/// stage 2's cell edge of the last search (PairFinder::surveyWanted), which active boxes are huge, the bounds
/// of the others, and every slot's extent along the guessed slab axis. chooseGrid takes it when the median
/// of this search's sample gives about the same cell edge; else it reads the boxes itself. The pairs never
/// depend on it: a box listed as huge or not is tested either way, and the bounds only place the grid.
struct BoxSurvey {
  float cell = 0.0f;                ///< The cell edge the huge test used.
  std::uint32_t hugeCellLimit = 0;  ///< The cell count limit it used.
  std::vector<std::uint32_t> huge;  ///< The huge active slots, ascending.
  float lo[3] = {0, 0, 0};          ///< Min corner of the other active boxes.
  float hi[3] = {-1, -1, -1};       ///< Max corner of them (below lo: none).
  AxisExtents extents;              ///< By slot (bySlot), count entries; axis -1: not surveyed.
  /// Bytes held.
  std::size_t bytes() const { return (huge.capacity() + extents.lo.capacity() + extents.hi.capacity()) * 4; }
};

/// The bits of a float, and back (AxisExtents).
inline std::uint32_t floatBits(float x) {
  std::uint32_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}
inline float bitsFloat(std::uint32_t b) {
  float x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

/// Chooses the grid for the `active` proxies (not empty): stage 2, the cell edge from the median largest
/// extent (size rule) or the paper's density (§4.1); stage 3, proxies whose boxes would cover more than
/// `options.hugeCellLimit` cells go to `huge`, the others to `binned` (both in `active` order); then the
/// grid spans the binned boxes, its cells doubled until their count fits 32 bits (the pairs found never
/// depend on the cell size). `binned` may be `active` itself (it is then written over it). `extentScratch`
/// is working memory kept by the caller between searches. With `kept` and kept->axis set, also fills
/// kept->lo and kept->hi for the binned boxes. With `survey` (made for every slot of `p`), stage 3 and the
/// bounds come from it when its cell edge is taken (`*surveyTaken`); `kept` is then left alone.
/// With `home` (CPU finder, under the size rule), also says whether the boxes are of about
/// one size, judged from stage 2's sample: few of them (kHomeLargerShare) larger than kHomeExtentRatio times
/// its median. If so, *home becomes the grid of the search by home cell (SlabSearch): the same origin, cells
/// just larger than the largest of the others, so that nearly every box spans at most two cells per axis,
/// and at most kHomeCellsPerBox cells per binned box; else home->cell is left 0.
Grid chooseGrid(const ProxyArrays& p, const std::vector<std::uint32_t>& active,
                const PairFinderOptions& options, std::vector<float>& extentScratch,
                std::vector<std::uint32_t>& binned, std::vector<std::uint32_t>& huge,
                AxisExtents* kept = nullptr, const BoxSurvey* survey = nullptr, bool* surveyTaken = nullptr,
                Grid* home = nullptr);

}  // namespace gpucol
