#include "broadphase/grid_choice.h"

#include <algorithm>
#include <cmath>

namespace gpucol {
namespace {

/// Size rule: cell edge = this × median largest extent. 2 was measured best of {1, 1.5, 2, 3} on the
/// benchmark scenes (gpucol-bench broadphase --cell-factor): smaller cells mean more keys per box,
/// larger ones more candidate pairs per cell.
constexpr float kSizeFactor = 2.0f;
/// Density rule (paper §4.1): the cell volume that holds this many objects on average.
constexpr float kObjectsPerCell = 4.0f;
/// Cell coordinates must fit the 32-bit cell index of a key (dims product < 2^32).
constexpr std::uint64_t kMaxCells = (std::uint64_t(1) << 32) - 1;

}  // namespace

Grid chooseGrid(const ProxyArrays& p, const std::vector<std::uint32_t>& active, const PairFinderOptions& options,
                std::vector<float>& extentScratch, std::vector<std::uint32_t>& binned,
                std::vector<std::uint32_t>& huge) {
  const std::size_t n = active.size();
  // Stage 2: the median of the largest extent, robust to a few huge boxes (a mean would follow them).
  extentScratch.resize(n);
  float lo[3] = {p.minX[active[0]], p.minY[active[0]], p.minZ[active[0]]};
  float hi[3] = {p.maxX[active[0]], p.maxY[active[0]], p.maxZ[active[0]]};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t s = active[i];
    extentScratch[i] = std::max({p.maxX[s] - p.minX[s], p.maxY[s] - p.minY[s], p.maxZ[s] - p.minZ[s]});
  }
  std::nth_element(extentScratch.begin(), extentScratch.begin() + std::ptrdiff_t(n / 2), extentScratch.end());
  const float median = extentScratch[n / 2];
  float cell = kSizeFactor * median;
  if (options.cellSizeRule == CellSizeRule::Density || !(cell > 0.0f)) {
    for (std::uint32_t s : active) {
      lo[0] = std::min(lo[0], p.minX[s]), lo[1] = std::min(lo[1], p.minY[s]),
      lo[2] = std::min(lo[2], p.minZ[s]);
      hi[0] = std::max(hi[0], p.maxX[s]), hi[1] = std::max(hi[1], p.maxY[s]),
      hi[2] = std::max(hi[2], p.maxZ[s]);
    }
    // A flat scene has zero volume; count each axis at least one object thick so the rule stays finite.
    double volume = 1.0;
    for (int a = 0; a < 3; ++a) volume *= std::max(double(hi[a]) - double(lo[a]), double(median));
    const float density = float(std::cbrt(double(kObjectsPerCell) * volume / double(n)));
    if (density > 0.0f && std::isfinite(density)) cell = std::max(density, median);
  }
  if (!(cell > 0.0f) || !std::isfinite(cell)) cell = 1.0f;  // all boxes are points at one spot

  // Stage 3: huge boxes (estimated from extents, independent of the grid's origin).
  binned.clear();
  huge.clear();
  const double inv = 1.0 / double(cell);
  for (std::uint32_t s : active) {
    const double covered = (double(p.maxX[s] - p.minX[s]) * inv + 1.0) *
                           (double(p.maxY[s] - p.minY[s]) * inv + 1.0) *
                           (double(p.maxZ[s] - p.minZ[s]) * inv + 1.0);
    (covered > double(options.hugeCellLimit) ? huge : binned).push_back(s);
  }

  Grid g;
  if (binned.empty()) return g;
  const std::uint32_t f = binned[0];
  float bmin[3] = {p.minX[f], p.minY[f], p.minZ[f]};
  float bmax[3] = {p.maxX[f], p.maxY[f], p.maxZ[f]};
  for (std::uint32_t s : binned) {
    bmin[0] = std::min(bmin[0], p.minX[s]), bmin[1] = std::min(bmin[1], p.minY[s]),
    bmin[2] = std::min(bmin[2], p.minZ[s]);
    bmax[0] = std::max(bmax[0], p.maxX[s]), bmax[1] = std::max(bmax[1], p.maxY[s]),
    bmax[2] = std::max(bmax[2], p.maxZ[s]);
  }
  // Coarsen until the cell index fits 32 bits: exactness never depends on the cell size.
  for (;;) {
    std::uint64_t total = 1;
    bool fits = true;
    for (int a = 0; a < 3 && fits; ++a) {
      const double d = std::floor((double(bmax[a]) - double(bmin[a])) / double(cell)) + 1.0;
      fits = d <= double(kMaxCells);
      if (fits) {
        g.dims[a] = std::uint32_t(d);
        total *= g.dims[a];
        fits = total <= kMaxCells;
      }
    }
    if (fits) break;
    cell *= 2.0f;
  }
  for (int a = 0; a < 3; ++a) g.origin[a] = bmin[a];
  g.cell = cell;
  g.invCell = 1.0f / cell;
  return g;
}

}  // namespace gpucol
