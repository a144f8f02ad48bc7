#include "broadphase/query_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gpucol {
namespace {

/// The index's cells are at most this many per filed box (plus kCellsSlack): the cell array stays dense and
/// small, a coarser grid only costs query time.
constexpr std::uint64_t kCellsPerBox = 2;
constexpr std::uint64_t kCellsSlack = 1024;

/// Relative allowance for the float rounding of the caller's exact sweep test (Bullet's btRayAabb2 rounds
/// each of its three or four float operations by at most 2^-24 of the magnitudes involved): about eight
/// times what they can add up to.
constexpr double kSweepSlack = 2e-6;

/// Share of the largest corner-filed box that the reach adds, so that boxes that move and turn (their
/// bounds grow and shrink, and round differently) can still be refiled.
constexpr double kReachSlack = 0.125;

/// x as a float no greater (Down) or no less (Up) than x, clamped to the finite floats; cellOf clamps too.
float floatDown(double x) {
  x = std::clamp(x, -double(std::numeric_limits<float>::max()), double(std::numeric_limits<float>::max()));
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float floatUp(double x) {
  x = std::clamp(x, -double(std::numeric_limits<float>::max()), double(std::numeric_limits<float>::max()));
  float f = float(x);
  if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

/// Cell ranges per axis: [lo, hi] for x, y and z.
struct CellBox {
  std::uint32_t lo[3];
  std::uint32_t hi[3];
};

}  // namespace

void QueryGrid::build(const ProxyArrays& p, const std::vector<std::uint32_t>& slots,
                      std::uint32_t hugeCellLimit) {
  clear();
  m_built = true;
  m_buildPeak = 0;
  PairFinderOptions options;
  options.hugeCellLimit = hugeCellLimit;
  std::vector<float> extents;
  std::vector<std::uint32_t> binned;
  m_grid = chooseGrid(p, slots, options, extents, binned, m_huge);
  if (binned.empty()) {
    m_cellStart.assign(2, 0);
    for (int a = 0; a < 3; ++a) m_hi[a] = m_grid.origin[a];
    return;
  }
  const BoxCorners first = p.box(binned[0]);
  for (int a = 0; a < 3; ++a) m_hi[a] = first.hi[a], m_lo[a] = m_grid.origin[a];
  for (std::uint32_t s : binned) {
    const BoxCorners b = p.box(s);
    for (int a = 0; a < 3; ++a) m_hi[a] = std::max(m_hi[a], b.hi[a]);
  }
  // The search's cell size, coarsened until the cell array is dense (cells at most twice the boxes).
  const std::uint64_t maxCells = kCellsPerBox * binned.size() + kCellsSlack;
  while (m_grid.cells() > maxCells) {
    m_grid.cell *= 2.0f;
    m_grid.invCell = 1.0f / m_grid.cell;
    for (int a = 0; a < 3; ++a)
      m_grid.dims[a] =
          std::uint32_t(std::floor((double(m_hi[a]) - double(m_grid.origin[a])) / double(m_grid.cell)) + 1.0);
  }
  auto rangeOf = [&](std::uint32_t s) {
    const BoxCorners b = p.box(s);
    CellBox r;
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = cellOf(b.lo[a], m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
      r.hi[a] = cellOf(b.hi[a], m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
    }
    return r;
  };
  // A box no larger than `reach` on every axis is filed once, in the cell of its min corner, and queries
  // reach back by the largest such box (m_homeReach): a box overlapping the region has its min corner
  // within that much below it. Larger boxes are filed in every cell they overlap. `reach` (at most a cell)
  // is chosen for the fewest entries a query reads, counted for a region two cells wide on each axis: a box
  // of extent e cells filed in every cell is read about (2 (1 + e))^3 times, one filed by its corner
  // (2 + reach)^3 times, so a reach far above most boxes' extents costs the small ones more than it saves.
  constexpr int kReachBins = 32;
  double homeCost[kReachBins + 1] = {};  // per bin of extent (in 1/kReachBins of a cell): boxes in it
  double spanCost[kReachBins + 1] = {};  // and what filing them in every cell costs
  std::vector<std::uint8_t> extentBin(binned.size(), kReachBins + 1);
  for (std::size_t i = 0; i < binned.size(); ++i) {
    const BoxCorners b = p.box(binned[i]);
    double e = 0, span = 1;
    for (int a = 0; a < 3; ++a) {
      const double cells = (double(b.hi[a]) - double(b.lo[a])) / double(m_grid.cell);
      e = std::max(e, cells);
      span *= 2.0 * (1.0 + cells);
    }
    if (!(e <= 1.0)) continue;
    const int bin = std::min(kReachBins, int(std::ceil(e * kReachBins)));
    extentBin[i] = std::uint8_t(bin);
    homeCost[bin] += 1;
    spanCost[bin] += span;
  }
  double all = 0;
  for (double c : spanCost) all += c;
  int reachBin = -1;  // -1: every box filed in every cell it overlaps
  double best = all, homes = 0, spans = 0;
  for (int bin = 0; bin <= kReachBins; ++bin) {
    homes += homeCost[bin], spans += spanCost[bin];
    const double reach = 2.0 + double(bin) / kReachBins;
    const double cost = all - spans + homes * reach * reach * reach;
    if (cost < best) best = cost, reachBin = bin;
  }
  std::vector<std::uint8_t> homeFiled(binned.size(), 0);
  m_homeCell.assign(p.count, kNone);
  for (std::size_t i = 0; i < binned.size(); ++i) {
    if (int(extentBin[i]) > reachBin) continue;
    const BoxCorners b = p.box(binned[i]);
    homeFiled[i] = 1;
    m_homeCell[binned[i]] = 0;  // the cell is set once the grid's size is final
    for (int a = 0; a < 3; ++a) m_homeReach[a] = std::max(m_homeReach[a], double(b.hi[a]) - double(b.lo[a]));
  }
  for (double& r : m_homeReach) r *= 1.0 + kReachSlack;
  auto filedRange = [&](std::size_t i) {
    CellBox r = rangeOf(binned[i]);
    if (homeFiled[i])
      for (int a = 0; a < 3; ++a) r.hi[a] = r.lo[a];
    return r;
  };
  auto forCells = [&](const CellBox& r, auto&& f) {
    for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
      for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
        const std::uint64_t row = rowStart(y, z);
        for (std::uint32_t x = r.lo[0]; x <= r.hi[0]; ++x) f(row + x);
      }
  };
  // Counting sort by cell (count, then allocate: nothing to overflow): m_cellStart[c] counts, becomes the
  // start by an exclusive prefix sum, serves as the write cursor (ending as the next cell's start), and
  // is shifted back.
  const std::uint64_t cells = m_grid.cells();
  m_cellStart.assign(cells + 1, 0);
  std::uint64_t entries = 0;
  for (std::size_t i = 0; i < binned.size(); ++i)
    forCells(filedRange(i), [&](std::uint64_t c) { ++m_cellStart[c], ++entries; });
  if (entries > std::numeric_limits<std::uint32_t>::max()) {
    // More entries than 32-bit starts can number: no index (built() is false), so every query scans.
    clear();
    return;
  }
  std::uint32_t sum = 0;
  for (std::uint64_t c = 0; c < cells; ++c) {
    const std::uint32_t count = m_cellStart[c];
    m_cellStart[c] = sum;
    sum += count;
  }
  m_entries.resize(entries);
  m_place.assign(p.count, kNone);
  for (std::size_t i = 0; i < binned.size(); ++i)
    forCells(filedRange(i), [&](std::uint64_t c) {
      if (homeFiled[i]) m_homeCell[binned[i]] = std::uint32_t(c), m_place[binned[i]] = m_cellStart[c];
      m_entries[m_cellStart[c]++] = binned[i];
    });
  for (std::uint64_t c = cells; c > 0; --c) m_cellStart[c] = m_cellStart[c - 1];
  m_cellStart[0] = 0;
  m_cellCount.resize(cells);
  for (std::uint64_t c = 0; c < cells; ++c) m_cellCount[c] = m_cellStart[c + 1] - m_cellStart[c];
  m_buildPeak = memoryBytes() + extents.capacity() * sizeof(float) + binned.capacity() * sizeof(std::uint32_t) +
                extentBin.capacity() + homeFiled.capacity();
}

bool QueryGrid::refile(std::uint32_t id, const float lo[3], const float hi[3]) {
  if (!m_built || id >= m_homeCell.size() || m_homeCell[id] == kNone) return false;
  for (int a = 0; a < 3; ++a)
    if (!(lo[a] <= hi[a]) || !(double(hi[a]) - double(lo[a]) <= m_homeReach[a])) return false;
  const std::uint32_t cell = std::uint32_t(cellAt(lo));
  if (cell == m_homeCell[id]) return true;
  const bool full = m_cellCount[cell] == m_cellStart[cell + 1] - m_cellStart[cell];
  if (full && m_place[id] != kNone && m_overflowed >= std::max<std::size_t>(m_entries.size(), kCellsSlack))
    return false;
  for (int a = 0; a < 3; ++a) m_lo[a] = std::min(m_lo[a], lo[a]), m_hi[a] = std::max(m_hi[a], hi[a]);
  unfile(id);
  fileHome(id, cell);
  return true;
}

void QueryGrid::unfile(std::uint32_t id) {
  const std::uint32_t cell = m_homeCell[id], place = m_place[id];
  if (place != kNone) {
    // The cell's last entry in use takes the place, so the entries in use stay first.
    const std::uint32_t last = m_cellStart[cell] + --m_cellCount[cell];
    const std::uint32_t moved = m_entries[last];
    m_entries[place] = moved;
    if (moved != id) m_place[moved] = place;
    m_entries[last] = kNone;
    // A box on the cell's overflow list takes the freed place: queries read the lists only where cells
    // hold more boxes than at the build.
    if (m_overflowed != 0 && m_overflowHead[cell] != kNone) {
      const std::uint32_t promoted = m_overflowHead[cell];
      m_homeCell[id] = kNone;
      unfile(promoted);
      fileHome(promoted, cell);
      return;
    }
  } else {
    const std::uint32_t next = m_overflowNext[id], prev = m_overflowPrev[id];
    (prev == kNone ? m_overflowHead[cell] : m_overflowNext[prev]) = next;
    if (next != kNone) m_overflowPrev[next] = prev;
    --m_overflowed;
  }
  m_homeCell[id] = kNone;
}

void QueryGrid::fileHome(std::uint32_t id, std::uint32_t cell) {
  m_homeCell[id] = cell;
  const std::uint32_t room = m_cellStart[cell + 1] - m_cellStart[cell];
  if (m_cellCount[cell] < room) {
    const std::uint32_t place = m_cellStart[cell] + m_cellCount[cell]++;
    m_entries[place] = id;
    m_place[id] = place;
    return;
  }
  if (m_overflowHead.empty()) {
    m_overflowHead.assign(m_cellCount.size(), kNone);
    m_overflowNext.assign(m_homeCell.size(), kNone);
    m_overflowPrev.assign(m_homeCell.size(), kNone);
  }
  const std::uint32_t first = m_overflowHead[cell];
  m_overflowNext[id] = first, m_overflowPrev[id] = kNone;
  if (first != kNone) m_overflowPrev[first] = id;
  m_overflowHead[cell] = id;
  m_place[id] = kNone;
  ++m_overflowed;
}

std::uint64_t QueryGrid::cellAt(const float x[3]) const {
  std::uint32_t c[3];
  for (int a = 0; a < 3; ++a) c[a] = cellOf(x[a], m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
  return rowStart(c[1], c[2]) + c[0];
}

void QueryGrid::clear() {
  m_built = false;
  m_grid = Grid{};
  for (double& r : m_homeReach) r = 0;
  m_overflowed = 0;
  for (std::vector<std::uint32_t>* v : {&m_homeCell, &m_place, &m_overflowHead, &m_overflowNext,
                                        &m_overflowPrev, &m_cellStart, &m_cellCount})
    std::vector<std::uint32_t>().swap(*v);
  std::vector<std::uint32_t>().swap(m_entries);
  std::vector<std::uint32_t>().swap(m_huge);
}

std::size_t QueryGrid::memoryBytes() const {
  std::size_t words = 0;
  for (const std::vector<std::uint32_t>* v : {&m_cellStart, &m_cellCount, &m_entries, &m_huge, &m_homeCell,
                                              &m_place, &m_overflowHead, &m_overflowNext, &m_overflowPrev})
    words += v->capacity();
  return words * sizeof(std::uint32_t);
}

std::uint64_t QueryGrid::rowStart(std::uint32_t y, std::uint32_t z) const {
  return std::uint64_t(m_grid.dims[0]) * (y + std::uint64_t(m_grid.dims[1]) * z);
}

std::size_t QueryGrid::rowEntries(std::uint32_t x0, std::uint32_t x1, std::uint32_t y,
                                  std::uint32_t z) const {
  const std::uint64_t row = rowStart(y, z);
  return m_cellStart[row + x1 + 1] - m_cellStart[row + x0];
}

std::size_t QueryGrid::appendRow(std::uint32_t x0, std::uint32_t x1, std::uint32_t y, std::uint32_t z,
                                 std::vector<std::uint32_t>& out, const CandidateTest& keep) const {
  const std::uint64_t row = rowStart(y, z);
  const std::uint32_t begin = m_cellStart[row + x0], end = m_cellStart[row + x1 + 1];
  for (std::uint32_t e = begin; e < end; ++e) {
    const std::uint32_t id = m_entries[e];
    if (id != kNone && keep(id)) out.push_back(id);
  }
  std::size_t read = end - begin;
  if (m_overflowed != 0)
    for (std::uint64_t c = row + x0; c <= row + x1; ++c)
      for (std::uint32_t id = m_overflowHead[c]; id != kNone; id = m_overflowNext[id], ++read)
        if (keep(id)) out.push_back(id);
  return read;
}

namespace {

/// The huge boxes that pass `keep`.
void appendHuge(const std::vector<std::uint32_t>& huge, std::vector<std::uint32_t>& out,
                const CandidateTest& keep) {
  for (std::uint32_t id : huge)
    if (keep(id)) out.push_back(id);
}

}  // namespace

bool QueryGrid::boxCandidates(const float lo[3], const float hi[3], std::size_t maxCandidates,
                              std::vector<std::uint32_t>& out, const CandidateTest& keep) const {
  if (!m_built) return false;
  // A box that overlaps the region contains the point max(its min, the region's min) on each axis, which
  // lies in the region too; cellOf is monotone, so that point's cell is visited and a box filed in every
  // cell it overlaps is filed there; a box filed by its min corner has that corner at most m_homeReach below
  // the region, and the visited cells start that far down. (An inverted region, min > max, is overlapped
  // only by boxes spanning [max, min]: the same cells.)
  CellBox r;
  for (int a = 0; a < 3; ++a) {
    const float rlo = std::min(lo[a], hi[a]), rhi = std::max(lo[a], hi[a]);
    if (!(rlo <= rhi)) return false;  // NaN
    r.lo[a] = cellOf(floatDown(double(rlo) - m_homeReach[a]), m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
    r.hi[a] = cellOf(rhi, m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
    if (rhi < m_lo[a] || rlo > m_hi[a])
      r.lo[a] = 1, r.hi[a] = 0;  // every filed box lies in [m_lo, m_hi]
  }
  double cells = 1;
  for (int a = 0; a < 3; ++a) cells *= r.hi[a] >= r.lo[a] ? double(r.hi[a] - r.lo[a] + 1) : 0.0;
  if (cells > double(m_entries.size()) + double(kCellsSlack)) return false;
  std::size_t count = m_huge.size();
  if (!m_entries.empty() && cells > 0)
    for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
      for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) count += rowEntries(r.lo[0], r.hi[0], y, z);
  if (count > maxCandidates) return false;
  appendHuge(m_huge, out, keep);
  if (m_entries.empty() || cells == 0) return true;
  for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) appendRow(r.lo[0], r.hi[0], y, z, out, keep);
  return true;
}

bool QueryGrid::sweepCandidates(const QuerySweep& sweep, std::size_t maxCandidates,
                                std::vector<std::uint32_t>& out, const CandidateTest& keep) const {
  if (!m_built) return false;
  const std::size_t before = out.size();
  // The region at point q is [q + lowOff, q + highOff] per axis: the cast box, widened by the rounding
  // allowance. Points q(t) for t between 0 and tMax (either sign: btRayAabb2 with a negative lambda still
  // reports boxes holding the segment from q(tMax) to q(0)).
  double lowOff[3], highOff[3];
  double t0 = std::min(0.0, sweep.tMax), t1 = std::max(0.0, sweep.tMax);
  if (!std::isfinite(t0) || !std::isfinite(t1)) return false;
  for (int a = 0; a < 3; ++a) {
    const double from = sweep.from[a], dir = sweep.dir[a];
    if (!std::isfinite(from) || !std::isfinite(dir) || !std::isfinite(sweep.castLo[a]) ||
        !std::isfinite(sweep.castHi[a]))
      return false;
    const double gridMagnitude =
        std::max({std::fabs(double(m_grid.origin[a])), std::fabs(double(m_lo[a])), std::fabs(double(m_hi[a]))});
    const double pad =
        kSweepSlack * (std::fabs(from) + std::fabs(dir) * std::max(-t0, t1) + std::fabs(sweep.castLo[a]) +
                       std::fabs(sweep.castHi[a]) + gridMagnitude) +
        std::numeric_limits<float>::min();
    lowOff[a] = std::min(sweep.castLo[a], sweep.castHi[a]) - pad - m_homeReach[a];
    highOff[a] = std::max(sweep.castLo[a], sweep.castHi[a]) + pad;
  }
  std::size_t read = m_huge.size();  // entries read: what maxCandidates bounds
  appendHuge(m_huge, out, keep);
  if (m_entries.empty()) return true;
  // Clip t to where the region can meet a filed box, all of which lie in [m_lo, m_hi].
  for (int a = 0; a < 3; ++a) {
    const double enter = double(m_lo[a]) - highOff[a] - sweep.from[a];  // q - from must reach this
    const double leave = double(m_hi[a]) - lowOff[a] - sweep.from[a];
    const double dir = sweep.dir[a];
    if (dir == 0.0) {
      if (enter > 0.0 || leave < 0.0) return true;
      continue;
    }
    double ta = enter / dir, tb = leave / dir;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  if (t0 > t1) return true;
  // Pieces one cell long along the axis the sweep crosses fastest; each visits the cells of its own region
  // that the previous piece's did not (both ends of a piece's cell range move one way along each axis, so
  // a cell left behind is never reached again). The caller removes repeats of boxes filed in several cells.
  double span = 0;
  for (int a = 0; a < 3; ++a)
    span = std::max(span, std::fabs(sweep.dir[a]) * (t1 - t0) * double(m_grid.invCell));
  const double budget = double(m_entries.size()) + double(kCellsSlack);
  if (!(span < budget)) {
    out.resize(before);
    return false;
  }
  const std::uint32_t pieces = std::uint32_t(std::ceil(span)) + 1;
  std::uint64_t visited = 0;
  CellBox prev{};
  for (std::uint32_t i = 0; i < pieces; ++i) {
    const double ta = t0 + (t1 - t0) * double(i) / double(pieces);
    const double tb = i + 1 == pieces ? t1 : t0 + (t1 - t0) * double(i + 1) / double(pieces);
    CellBox r;
    for (int a = 0; a < 3; ++a) {
      const double qa = sweep.from[a] + ta * sweep.dir[a], qb = sweep.from[a] + tb * sweep.dir[a];
      r.lo[a] =
          cellOf(floatDown(std::min(qa, qb) + lowOff[a]), m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
      r.hi[a] =
          cellOf(floatUp(std::max(qa, qb) + highOff[a]), m_grid.origin[a], m_grid.invCell, m_grid.dims[a]);
    }
    for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z)
      for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
        const bool seen = i > 0 && z >= prev.lo[2] && z <= prev.hi[2] && y >= prev.lo[1] && y <= prev.hi[1];
        if (!seen) {
          read += appendRow(r.lo[0], r.hi[0], y, z, out, keep);
          visited += r.hi[0] - r.lo[0] + 1;
        } else {
          if (r.lo[0] < prev.lo[0]) {
            const std::uint32_t x1 = std::min(r.hi[0], prev.lo[0] - 1);
            read += appendRow(r.lo[0], x1, y, z, out, keep);
            visited += x1 - r.lo[0] + 1;
          }
          if (r.hi[0] > prev.hi[0]) {
            const std::uint32_t x0 = std::max(r.lo[0], prev.hi[0] + 1);
            read += appendRow(x0, r.hi[0], y, z, out, keep);
            visited += r.hi[0] - x0 + 1;
          }
        }
        if (double(visited) > budget || read > maxCandidates) {
          out.resize(before);
          return false;
        }
      }
    prev = r;
  }
  return true;
}

}  // namespace gpucol
