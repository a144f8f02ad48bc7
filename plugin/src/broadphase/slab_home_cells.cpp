// The slab search by home cell (slab_search.h has the rule and why it is exact); stage numbers refer to
// grid_pair_finder.h.
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "broadphase/slab_search.h"

namespace gpucol {
namespace {

/// The cell entry of a box that spans three or more cells on an axis (searched through the cells around it).
constexpr std::uint32_t kWideBox = std::numeric_limits<std::uint32_t>::max();

}  // namespace

template <int A>
SlabSearchCounts SlabSearch::searchSlabByHomeCellOn(std::size_t slab, const ProxyArrays& p,
                                                    const std::vector<std::uint32_t>& huge, const Grid& g,
                                                    Scratch& t, PairBuckets* buckets) {
  t.pairs.clear();
  auto add = [&](std::uint64_t key) { addPair(slab, t, buckets, key); };
  SlabSearchCounts counts;
  const std::size_t begin = m_memberStart[slab], m = m_memberStart[slab + 1] - begin;
  if (m == 0) return counts;
  constexpr int U = A == 0 ? 1 : 0, V = A == 2 ? 1 : 2;
  const std::uint32_t a0 = m_firstLayer[slab], a1 = m_firstLayer[slab + 1];
  // The slab's grid: U fastest, then V, then the layers along A from a0 - 1 (local layer 0: boxes that start
  // below the slab and reach into it, whose pairs among themselves are the slab below's) up to a1 - 1.
  const std::uint32_t du = g.dims[U], dv = g.dims[V], layers = a1 - a0 + 1;
  const std::uint64_t cells = std::uint64_t(du) * dv * layers;
  if (cells + 2 > std::numeric_limits<std::uint32_t>::max() || m >= std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("gpucol::GridBroadphase: a slab of " + std::to_string(cells) + " cells and " +
                             std::to_string(m) + " boxes exceeds the 2^32 limit of the search by home cell");
  const float originU = g.origin[U], originV = g.origin[V], originA = g.origin[A];
  auto cellU = [&](float x) { return cellOf(x, originU, g.invCell, du); };
  auto cellV = [&](float x) { return cellOf(x, originV, g.invCell, dv); };
  auto cellA = [&](float x) { return cellOf(x, originA, g.invCell, g.dims[A]); };
  // A pair is this slab's when the later of the two boxes' first layers (the layer of the overlap's min
  // corner) lies in it: the rule the pairs found through cells meet by the cells searched.
  auto owned = [&](const LocalBox& a, const LocalBox& b) {
    const std::uint32_t layer = cellA(std::max(a.lo[A], b.lo[A]));
    return layer >= a0 && layer < a1;
  };

  // Stages 4-5: each box's home cell, counted; then the boxes copied in cell order (start[c]..start[c + 1]
  // is cell c's once placing has moved each cell's start up to its end).
  resizeExact(t.entries, m);
  resizeExact(t.cellStart, std::size_t(cells) + 2);
  std::fill(t.cellStart.begin(), t.cellStart.end(), 0u);
  std::uint32_t* start = t.cellStart.data();
  const std::uint32_t* member = m_members.data() + begin;
  std::size_t wideCount = 0;
  for (std::size_t j = 0; j < m; ++j) {
    if (j + kBoxPrefetchAhead < m) p.prefetchBox(member[j + kBoxPrefetchAhead]);
    const BoxCorners b = p.box(member[j]);  // the corners alone: the filters are read when placing
    const std::uint32_t u = cellU(b.lo[U]), v = cellV(b.lo[V]), layer = cellA(b.lo[A]);
    // A member reaches the slab, so a box of at most two cells per axis starts in layer a0 - 1 or above.
    if (cellU(b.hi[U]) - u > 1 || cellV(b.hi[V]) - v > 1 || cellA(b.hi[A]) - layer > 1 || layer + 1 < a0) {
      t.entries[j] = kWideBox;
      ++wideCount;
      continue;
    }
    const std::uint32_t c = u + du * (v + dv * (layer + 1 - a0));
    t.entries[j] = c;
    ++start[c + 2];
  }
  for (std::size_t c = 2; c < std::size_t(cells) + 2; ++c) start[c] += start[c - 1];
  // The wide boxes listed at their number (a list grown by push_back would hold its old and new arrays at
  // once, which the thread's byte count does not see).
  resizeExact(t.wide, wideCount);
  for (std::size_t j = 0, w = 0; w < wideCount; ++j)
    if (t.entries[j] == kWideBox) t.wide[w++] = std::uint32_t(j);
  const std::uint32_t placed = std::uint32_t(m - wideCount);
  resizeExact(t.sorted, placed);
  // Read again rather than copied in member order first: that copy was most of a small scene's peak.
  for (std::size_t j = 0; j < m; ++j) {
    if (j + kBoxPrefetchAhead < m) p.prefetchBox(member[j + kBoxPrefetchAhead]);
    if (t.entries[j] != kWideBox) t.sorted[start[t.entries[j] + 1]++] = boxOf(p, member[j]);
  }
  counts.keys = placed;
  counts.wide = t.wide.size();
  const LocalBox* box = t.sorted.data();
  auto testRange = [&](const LocalBox& a, std::uint32_t from, std::uint32_t to) {
    for (std::uint32_t k = from; k < to; ++k)
      if (boxesOverlap(a, box[k]) && passesFilter(a, box[k])) add(makePairKey(a.slot, box[k].slot));
  };

  // Stages 8-9: each cell's boxes against the later ones of the cell and of the next cell of its row (one
  // range), the three cells u-1..u+1 of the next row (v+1) and those of the rows v-1..v+1 of the next layer:
  // 13 neighbours, so each pair of neighbouring cells once. Local layer 0 only reaches up into the slab.
  for (std::uint32_t layer = 0; layer < layers; ++layer)
    for (std::uint32_t v = 0; v < dv; ++v) {
      const std::uint32_t* own = start + (layer * dv + v) * du;
      const std::uint32_t* rows[4];
      std::uint32_t rowCount = 0;
      if (layer > 0 && v + 1 < dv) rows[rowCount++] = own + du;
      if (layer + 1 < layers)
        for (std::uint32_t w = v > 0 ? v - 1 : 0, last = v + 1 < dv ? v + 1 : v; w <= last; ++w)
          rows[rowCount++] = start + ((layer + 1) * dv + w) * du;
      for (std::uint32_t u = 0; u < du; ++u) {
        const std::uint32_t s0 = own[u], s1 = own[u + 1];
        if (s0 == s1) continue;
        const std::uint32_t uLo = u > 0 ? u - 1 : 0, uEnd = u + 1 < du ? u + 2 : u + 1;
        std::uint32_t from[4], to[4], rangeBoxes = 0;
        for (std::uint32_t r = 0; r < rowCount; ++r)
          from[r] = rows[r][uLo], to[r] = rows[r][uEnd], rangeBoxes += to[r] - from[r];
        // The rest of this cell and the next cell of the row are one range (local layer 0: neither).
        const std::uint32_t sameEnd = layer > 0 ? own[uEnd] : 0;
        for (std::uint32_t i = s0; i < s1; ++i) {
          const LocalBox& a = box[i];
          if (layer > 0) testRange(a, i + 1, sameEnd), counts.candidates += sameEnd - i - 1;
          for (std::uint32_t r = 0; r < rowCount; ++r) testRange(a, from[r], to[r]);
          counts.candidates += rangeBoxes;
        }
      }
    }

  // Wide and huge boxes (stage 3), which are in no cell, against the placed boxes: a placed box that
  // overlaps one starts at most one cell below its range on each axis, so the cells searched are those of the
  // range widened by one below (in this slab's layers, local layer 0 included), when they are few enough;
  // else every placed box one by one. Either way with the slab's rule.
  auto testOwned = [&](const LocalBox& a, const LocalBox& b) {
    if (boxesOverlap(a, b) && owned(a, b) && passesFilter(a, b)) add(makePairKey(a.slot, b.slot));
  };
  const double boxesPerCell = double(placed) / double(cells);
  auto againstPlaced = [&](const LocalBox& a, const std::uint32_t lo[3], const std::uint32_t hi[3]) {
    const std::uint32_t uLo = lo[U] > 0 ? lo[U] - 1 : 0, vLo = lo[V] > 0 ? lo[V] - 1 : 0;
    const std::uint32_t lLo = std::max(lo[A], a0) - a0, lHi = std::min(hi[A], a1 - 1) + 1 - a0;
    const double rangeCells = double(hi[U] - uLo + 1) * double(hi[V] - vLo + 1) * double(lHi - lLo + 1);
    if (rangeCells * (1.0 + boxesPerCell) >= double(placed)) {
      for (std::uint32_t k = 0; k < placed; ++k) testOwned(a, box[k]);
      counts.candidates += placed;
      return;
    }
    for (std::uint32_t layer = lLo; layer <= lHi; ++layer)
      for (std::uint32_t v = vLo; v <= hi[V]; ++v) {
        const std::uint32_t row = (layer * dv + v) * du;
        const std::uint32_t from = start[row + uLo], to = start[row + hi[U] + 1];
        for (std::uint32_t k = from; k < to; ++k) testOwned(a, box[k]);
        counts.candidates += to - from;
      }
  };
  auto rangeOf = [&](const LocalBox& a, std::uint32_t lo[3], std::uint32_t hi[3]) {
    lo[U] = cellU(a.lo[U]), lo[V] = cellV(a.lo[V]), lo[A] = cellA(a.lo[A]);
    hi[U] = cellU(a.hi[U]), hi[V] = cellV(a.hi[V]), hi[A] = cellA(a.hi[A]);
  };
  for (std::size_t w = 0; w < t.wide.size(); ++w) {
    const LocalBox a = boxOf(p, member[t.wide[w]]);
    std::uint32_t lo[3], hi[3];
    rangeOf(a, lo, hi);
    againstPlaced(a, lo, hi);
    for (std::size_t x = w + 1; x < t.wide.size(); ++x) testOwned(a, boxOf(p, member[t.wide[x]]));
    counts.candidates += t.wide.size() - w - 1;
  }
  for (std::uint32_t h : huge) {
    const LocalBox a = boxOf(p, h);
    std::uint32_t lo[3], hi[3];
    rangeOf(a, lo, hi);
    if (hi[A] < a0 || lo[A] >= a1) continue;  // the layer of any of its pairs lies in its range
    for (std::uint32_t w : t.wide) testOwned(a, boxOf(p, member[w]));
    counts.candidates += t.wide.size();
    againstPlaced(a, lo, hi);
  }
  return counts;
}

SlabSearchCounts SlabSearch::searchSlabByHomeCell(std::size_t slab, const ProxyArrays& p,
                                                  const std::vector<std::uint32_t>& huge, const Grid& g,
                                                  Scratch& t, PairBuckets* buckets) {
  // The axes as constants: a box's corner read at a run-time axis from its copy on the stack stalled every
  // box (the store could not be forwarded to the load).
  switch (m_axis) {
    case 0:
      return searchSlabByHomeCellOn<0>(slab, p, huge, g, t, buckets);
    case 1:
      return searchSlabByHomeCellOn<1>(slab, p, huge, g, t, buckets);
    default:
      return searchSlabByHomeCellOn<2>(slab, p, huge, g, t, buckets);
  }
}

}  // namespace gpucol
