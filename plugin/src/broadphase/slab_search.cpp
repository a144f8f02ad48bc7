// The slab search (slab_search.h); stage numbers refer to grid_pair_finder.h.
#include "broadphase/slab_search.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

namespace gpucol {
namespace {

/// Slabs a scene is cut into when every slab holds its share (more slabs: less working memory per thread
/// and better balance, more boxes listed twice where they cross a slab boundary).
constexpr std::uint64_t kSlabsAimed = 32;
/// A slab is also closed once it has this many cells per box aimed at, so a sparse stretch of the grid
/// does not make one slab's cell array large.
constexpr std::uint64_t kCellsPerSlabBox = 8;
/// Layers up to which the planning keeps each box's first and last layer in 16 bits each.
constexpr std::uint32_t kPackedLayers = 1u << 16;
/// Binned boxes per task of the planning passes.
constexpr std::size_t kPlanGrain = 4096;
/// Tasks of the planning passes at most (each has a count per slab).
constexpr std::size_t kPlanChunks = 64;
/// An entry is a box index and, in its top three bits, on which axes the cell is the box's first (the cell
/// of its min corner on that axis). Stage 9 needs no box for that: cellOf is monotone, so the cell of the
/// overlap's min corner is, on each axis, the later of the two boxes' first cells, and since both boxes are
/// in the cell, the pair belongs to the cell exactly when on every axis one of them starts there.
constexpr int kStartShift = 29;
constexpr std::uint32_t kAllAxes = 7;
constexpr std::uint32_t kSlabBox = (1u << kStartShift) - 1;
/// SlabBoxReading::Auto reads the boxes in place in a scene of at most kInPlaceMaxBoxes binned boxes when the
/// threads' copies would hold more than kCopyBytesPerBox bytes per binned box: there the copies took 12-24 of
/// the 100 bytes per proxy a step may hold (measurement history, "Small scenes' peaks"). In larger scenes
/// they take less, and reading in place cost more: a pile of 10,000 boxes (the falling column after 80 steps,
/// about 10 pairs per box, a few large slabs) spent twice as long in its candidate tests.
constexpr std::size_t kCopyBytesPerBox = 8;
constexpr std::size_t kInPlaceMaxBoxes = 4096;
/// Stage 9 on two entries (or an entry and a huge box's bits) of one cell.
inline bool ownedByCell(std::uint32_t a, std::uint32_t b) {
  return ((a | b) >> kStartShift) == kAllAxes;
}

/// ownedByCell and boxesOverlap in one condition, so one branch, which is rarely taken. In the short runs of
/// 100K uniform boxes a cell owned 70% of its candidates, their boxes overlapped in 18%, and both held in 9%:
/// a branch on ownership first went either way at random. The tests took 11-13% less time with the single
/// branch, at 100K uniform and mixed boxes (measurement history). The sum is 8 only for an owned pair (7: all
/// three start bits) whose boxes overlap (1); GCC splits `a & b` of two conditions back into two branches.
inline bool ownedAndOverlapping(std::uint32_t ea, std::uint32_t eb, const LocalBox& a, const LocalBox& b) {
  return ((ea | eb) >> kStartShift) + std::uint32_t(boxesOverlap(a, b)) == kAllAxes + 1;
}

/// The extent along one axis of binned box i (slot s): kept by the grid choice, or read from that axis's two
/// arrays (the planning passes read nothing else there), or from the records.
class AxisExtent {
 public:
  AxisExtent(const ProxyArrays& p, int axis, const AxisExtents* kept)
      : m_p(p),
        m_axis(axis),
        m_bySlot(kept && kept->bySlot),
        m_keptLo(kept ? kept->lo.data() : nullptr),
        m_keptHi(kept ? kept->hi.data() : nullptr),
        m_lo(axis == 0   ? p.minX
             : axis == 1 ? p.minY
                         : p.minZ),
        m_hi(axis == 0   ? p.maxX
             : axis == 1 ? p.maxY
                         : p.maxZ) {}
  float lo(std::size_t i, std::uint32_t s) const {
    return m_keptLo ? bitsFloat(m_keptLo[m_bySlot ? s : i]) : m_lo ? m_lo[s] : m_p.box(s).lo[m_axis];
  }
  float hi(std::size_t i, std::uint32_t s) const {
    return m_keptHi ? bitsFloat(m_keptHi[m_bySlot ? s : i]) : m_hi ? m_hi[s] : m_p.box(s).hi[m_axis];
  }

 private:
  const ProxyArrays& m_p;
  int m_axis;
  bool m_bySlot;
  const std::uint32_t* m_keptLo;
  const std::uint32_t* m_keptHi;
  const float* m_lo;
  const float* m_hi;
};

}  // namespace

bool SlabSearch::plan(const ProxyArrays& p, const std::vector<std::uint32_t>& binned, const Grid& g,
                      std::uint32_t slabBoxes, std::uint32_t minSlabs, SlabBoxReading reading,
                      AxisExtents* kept, bool homeCells) {
  m_firstLayer.clear();
  m_inPlace = false;
  m_home = homeCells;
  const std::size_t n = binned.size();
  m_axis = 0;
  for (int a = 1; a < 3; ++a)
    if (g.dims[a] > g.dims[m_axis]) m_axis = a;
  const std::uint32_t layers = g.dims[m_axis];
  auto layerOf = [&](float x) { return cellOf(x, g.origin[m_axis], g.invCell, layers); };
  const std::size_t keptSize = kept && kept->bySlot ? p.count : n;
  const bool useKept =
      kept && kept->axis == m_axis && kept->lo.size() == keptSize && kept->hi.size() == keptSize;
  m_tookKept = useKept;
  const AxisExtent extent(p, m_axis, useKept ? kept : nullptr);
  auto releaseKept = [&] {
    if (useKept) std::vector<std::uint32_t>().swap(kept->lo), std::vector<std::uint32_t>().swap(kept->hi);
  };
  // Each box's first and last layer, packed in 32 bits by the first pass for the two after it (in place,
  // each pass over the boxes is a walk over Bullet's proxies in memory), when layers fit 16 bits. Over kept
  // extents they are written on the box's own kept min (read just before), which becomes the layer list:
  // the kept extents and the layers are never held side by side. Kept by slot (a BoxSurvey's), the list is
  // then indexed by slot too.
  const bool packLayers = layers <= kPackedLayers;
  const bool layersBySlot = useKept && kept->bySlot;
  auto layerIndex = [&](std::size_t i) -> std::size_t { return layersBySlot ? binned[i] : i; };
  if (packLayers && !useKept) resizeExact(m_boxLayers, n);
  std::uint32_t* packed = !packLayers ? nullptr : useKept ? kept->lo.data() : m_boxLayers.data();
  auto layersOf = [&](std::size_t i) {
    if (packLayers)
      return std::pair<std::uint32_t, std::uint32_t>(m_boxLayers[layerIndex(i)] & 0xFFFFu,
                                                     m_boxLayers[layerIndex(i)] >> 16);
    return std::pair<std::uint32_t, std::uint32_t>(layerOf(extent.lo(i, binned[i])),
                                                   layerOf(extent.hi(i, binned[i])));
  };
  // f(slab) for every slab binned[i]'s box reaches (after the slabs are cut).
  auto forSlabsOf = [&](std::size_t i, auto&& f) {
    const auto [first, last] = layersOf(i);
    for (std::uint32_t k = m_layerSlab[first], end = m_layerSlab[last]; k <= end; ++k) f(k);
  };
  const std::size_t chunks =
      std::min(kPlanChunks, std::max<std::size_t>(1, (n + kPlanGrain - 1) / kPlanGrain));
  const std::size_t chunk = (n + chunks - 1) / chunks;
  auto forChunks = [&](auto&& f) {
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      const std::size_t begin = c * chunk, end = std::min(n, begin + chunk);
      if (begin < end) f(c, begin, end);
    });
  };

  // Boxes by the layer of their min corner (a count per chunk and layer: atomic increments of a few dozen
  // shared counters were slower than the whole search's binning; the chunks are fewer when layers are many,
  // so the counts stay within 8 bytes per box), then slabs cut from the bottom layer up.
  const std::size_t layerChunks = std::min(chunks, std::max<std::size_t>(1, n / layers));
  const std::size_t layerChunk = (n + layerChunks - 1) / layerChunks;
  m_chunkCount.assign(layerChunks * layers, 0);
  tbb::parallel_for(std::size_t(0), layerChunks, [&](std::size_t c) {
    std::size_t* count = m_chunkCount.data() + c * layers;
    for (std::size_t i = c * layerChunk, end = std::min(n, i + layerChunk); i < end; ++i) {
      const std::uint32_t first = layerOf(extent.lo(i, binned[i]));
      ++count[first];
      if (packed) packed[layerIndex(i)] = first | layerOf(extent.hi(i, binned[i])) << 16;
    }
  });
  if (packed && useKept) {
    m_boxLayers.swap(kept->lo);
    releaseKept();
  }
  m_layerSlab.resize(layers);
  tbb::parallel_for(std::uint32_t(0), layers, [&](std::uint32_t l) {
    std::size_t sum = 0;
    for (std::size_t c = 0; c < layerChunks; ++c) sum += m_chunkCount[c * layers + l];
    m_layerSlab[l] = std::uint32_t(sum);
  });
  const std::uint64_t aim = slabBoxes ? slabBoxes : std::max<std::uint64_t>(kMinSlabBoxes, n / kSlabsAimed);
  const std::uint64_t layerCells = g.cells() / layers;
  m_firstLayer.push_back(0);
  std::uint64_t boxes = 0, cells = 0;
  for (std::uint32_t l = 0; l < layers; ++l) {
    boxes += m_layerSlab[l];
    cells += layerCells;
    m_layerSlab[l] = std::uint32_t(m_firstLayer.size() - 1);
    if ((boxes >= aim || cells >= kCellsPerSlabBox * aim) && l + 1 < layers) {
      m_firstLayer.push_back(l + 1);
      boxes = cells = 0;
    }
  }
  m_firstLayer.push_back(layers);
  const std::size_t slabCount = slabs();
  if (slabCount < minSlabs) {
    releaseKept();
    m_firstLayer.clear();
    std::vector<std::uint32_t>().swap(m_boxLayers);
    return false;
  }

  // Slab lists: each chunk counts its boxes per slab, then writes them at offsets that put slab k's boxes
  // in ascending slot order (slab-major, chunk-minor), whatever the threads did.
  m_chunkCount.assign(chunks * slabCount, 0);
  forChunks([&](std::size_t c, std::size_t begin, std::size_t end) {
    std::size_t* count = m_chunkCount.data() + c * slabCount;
    for (std::size_t i = begin; i < end; ++i) forSlabsOf(i, [&](std::uint32_t k) { ++count[k]; });
  });
  m_memberStart.assign(slabCount + 1, 0);
  std::size_t sum = 0;
  for (std::size_t k = 0; k < slabCount; ++k) {
    m_memberStart[k] = sum;
    for (std::size_t c = 0; c < chunks; ++c) sum += std::exchange(m_chunkCount[c * slabCount + k], sum);
  }
  m_memberStart[slabCount] = sum;
  m_members.resize(sum);
  forChunks([&](std::size_t c, std::size_t begin, std::size_t end) {
    std::size_t* next = m_chunkCount.data() + c * slabCount;
    for (std::size_t i = begin; i < end; ++i)
      forSlabsOf(i, [&](std::uint32_t k) { m_members[next[k]++] = binned[i]; });
  });
  releaseKept();
  // The box copies held at once: each thread's of the largest slab it may take, so at most those of the
  // largest slabs, one per thread.
  std::vector<std::size_t> slabSizes(slabCount);
  for (std::size_t k = 0; k < slabCount; ++k) slabSizes[k] = m_memberStart[k + 1] - m_memberStart[k];
  const std::size_t threads =
      std::min({slabCount, std::size_t(std::max(1, tbb::this_task_arena::max_concurrency())),
                tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)});
  std::partial_sort(slabSizes.begin(), slabSizes.begin() + std::ptrdiff_t(threads), slabSizes.end(),
                    std::greater<>());
  std::size_t copied = 0;
  for (std::size_t k = 0; k < threads; ++k) copied += slabSizes[k];
  m_inPlace = !m_home && (reading == SlabBoxReading::InPlace ||
                          (reading == SlabBoxReading::Auto && n <= kInPlaceMaxBoxes &&
                           copied * sizeof(LocalBox) > kCopyBytesPerBox * n));
  return true;
}

SlabSearchCounts SlabSearch::search(const ProxyArrays& p, const std::vector<std::uint32_t>& huge,
                                    const Grid& g, std::vector<std::vector<std::uint64_t>>& out,
                                    std::size_t first, PairBuckets* buckets) {
  std::vector<std::uint32_t>().swap(m_boxLayers);  // the plan's (kept until now for the caller's peak)
  const std::size_t slabCount = slabs();
  std::vector<SlabSearchCounts> counts(slabCount + huge.size());
  // Slabs differ in cost (a pile at the bottom of a column): one slab per task, taken as threads free up.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, slabCount, 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
          // Found into the thread's list, then copied at their exact size (lists grown by push_back hold
          // up to twice their pairs, and all of them are held until the gather), or into buckets the rest
          // of what searchSlab has not handed over.
          Scratch& t = m_scratch.local();
          counts[k] = m_home ? searchSlabByHomeCell(k, p, huge, g, t, buckets)
                             : searchSlab(k, p, huge, g, t, buckets);
          if (buckets)
            buckets->addToPiece(k, t.pairs);
          else
            out[first + k].assign(t.pairs.begin(), t.pairs.end());
        }
      },
      tbb::simple_partitioner());
  // Stage 3: huge boxes among themselves, each pair from the earlier one in `huge`.
  tbb::parallel_for(std::size_t(0), huge.size(), [&](std::size_t i) {
    auto& list = buckets ? m_scratch.local().pairs : out[first + slabCount + i];
    list.clear();
    counts[slabCount + i].candidates = hugeAgainstLaterHuge(p, huge, i, list);
    if (buckets) buckets->addToPiece(slabCount + i, list);
  });
  SlabSearchCounts total;
  for (const SlabSearchCounts& c : counts)
    total.keys += c.keys, total.candidates += c.candidates, total.wide += c.wide;
  return total;
}

SlabSearchCounts SlabSearch::searchSlab(std::size_t slab, const ProxyArrays& p,
                                        const std::vector<std::uint32_t>& huge, const Grid& g, Scratch& t,
                                        PairBuckets* buckets) {
  t.pairs.clear();
  // Into buckets, a full list that holds a part's worth is handed over rather than grown: a slab of a pile
  // has several pairs per box, and a doubling list held up to twice its keys, three times while it grew.
  auto add = [&](std::uint64_t key) { addPair(slab, t, buckets, key); };
  SlabSearchCounts counts;
  const std::size_t begin = m_memberStart[slab], m = m_memberStart[slab + 1] - begin;
  if (m == 0) return counts;
  if (m > kSlabBox)
    throw std::runtime_error("gpucol::GridBroadphase: " + std::to_string(m) +
                             " boxes in one slab exceed the 2^29 - 1 limit of one slab");
  const int A = m_axis;
  const std::uint32_t a0 = m_firstLayer[slab], a1 = m_firstLayer[slab + 1];
  // The slab's own grid: the global grid's cells with layers a0..a1-1 along the slab axis.
  std::uint32_t dims[3] = {g.dims[0], g.dims[1], g.dims[2]};
  dims[A] = a1 - a0;
  const std::uint32_t cells = dims[0] * dims[1] * dims[2];  // at most the global grid's count (32 bits)
  // Built axis by axis rather than by writing r.lo[A] in place: the store at a run-time index and the 16-byte
  // reload of the range that followed could not be forwarded and stalled the copy of every box.
  auto toSlab = [&](const CellRange& whole) {
    CellRange r;
    for (int i = 0; i < 3; ++i) {
      r.lo[i] = i == A ? std::max(whole.lo[i], a0) - a0 : whole.lo[i];
      r.hi[i] = i == A ? std::min(whole.hi[i], a1 - 1) - a0 : whole.hi[i];
    }
    return r;
  };
  if (!m_inPlace) resizeExact(t.box, m);
  resizeExact(t.cells, m);
  std::uint64_t keys = 0;
  const std::uint32_t* member = m_members.data() + begin;
  for (std::size_t j = 0; j < m; ++j) {
    if (j + kBoxPrefetchAhead < m) p.prefetchBox(member[j + kBoxPrefetchAhead]);
    const LocalBox b = boxOf(p, member[j]);
    if (!m_inPlace) t.box[j] = b;
    const CellRange r = toSlab(cellRange(b, g));
    keys += r.count();
    t.cells[j] = PackedCells::of(r, dims);
  }
  if (keys > std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("gpucol::GridBroadphase: " + std::to_string(keys) +
                             " (cell, proxy) entries exceed the 2^32 entry limit of one grid");
  counts.keys = keys;
  auto testSlab = [&](auto&& box) {
    // A range's first cells in slab coordinates; on the slab axis none when the box starts below the slab.
    auto firstCells = [&](const CellRange& whole, std::uint32_t first[3]) {
      for (int i = 0; i < 3; ++i) first[i] = whole.lo[i];
      first[A] = whole.lo[A] >= a0 ? whole.lo[A] - a0 : std::numeric_limits<std::uint32_t>::max();
    };
    auto startBits = [](const std::uint32_t first[3], std::uint32_t x, std::uint32_t y, std::uint32_t z) {
      return (std::uint32_t(x == first[0]) | std::uint32_t(y == first[1]) << 1 |
              std::uint32_t(z == first[2]) << 2)
             << kStartShift;
    };
    // f(cell, start bits) for every slab cell of box j, the bits (an entry's top three) saying on which axes
    // the cell is the box's first.
    auto forCellsOf = [&](std::size_t j, auto&& f) {
      const LocalBox& b = box(j);
      if (t.cells[j].fits()) {
        const std::uint32_t axes =
            cellOf(b.lo[A], g.origin[A], g.invCell, g.dims[A]) >= a0 ? kAllAxes : kAllAxes & ~(1u << A);
        t.cells[j].forEach(
            dims, [&](std::uint32_t c, std::uint32_t firstOn) { f(c, (firstOn & axes) << kStartShift); });
        return;
      }
      const CellRange whole = cellRange(b, g);
      std::uint32_t first[3];
      firstCells(whole, first);
      forEachCellOf(toSlab(whole), dims,
                    [&](std::uint32_t c, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
                      f(c, startBits(first, x, y, z));
                    });
    };

    // Stages 4-5: a counting sort of the slab's entries by cell. Counts go up, an inclusive scan turns them
    // into cell ends, and placing counts them back down to each cell's start.
    reserveExact(t.cellStart, std::size_t(cells) + 1);
    t.cellStart.assign(std::size_t(cells) + 1, 0);
    std::uint32_t* start = t.cellStart.data();
    for (std::size_t j = 0; j < m; ++j) forCellsOf(j, [&](std::uint32_t c, std::uint32_t) { ++start[c]; });
    for (std::uint32_t c = 1; c <= cells; ++c) start[c] += start[c - 1];
    resizeExact(t.entries, keys);
    for (std::size_t j = 0; j < m; ++j)
      forCellsOf(
          j, [&](std::uint32_t c, std::uint32_t bits) { t.entries[--start[c]] = std::uint32_t(j) | bits; });

    // Stages 8-9 per cell of two or more boxes: the cell's ownership from the entries alone, then the overlap
    // and the filter.
    for (std::uint32_t c = 0; c < cells; ++c) {
      const std::uint32_t e0 = start[c], runLength = start[c + 1] - e0;
      if (runLength < 2) continue;
      counts.candidates += std::uint64_t(runLength) * (runLength - 1) / 2;
      const std::uint32_t* run = t.entries.data() + e0;
      auto boxAt = [&](std::uint32_t i) -> decltype(auto) { return box(run[i] & kSlabBox); };
      if (runLength >= kLocalRunMin && runLength <= kLocalRunMax) {
        forEachOverlapInRun(runLength, boxAt, [&](std::uint32_t i, std::uint32_t j) {
          if (ownedByCell(run[i], run[j]) && passesFilter(boxAt(i), boxAt(j)))
            add(makePairKey(boxAt(i).slot, boxAt(j).slot));
        });
        continue;
      }
      for (std::uint32_t i = 0; i + 1 < runLength; ++i) {
        const LocalBox& a = boxAt(i);
        for (std::uint32_t j = i + 1; j < runLength; ++j) {
          const LocalBox& b = boxAt(j);
          if (ownedAndOverlapping(run[i], run[j], a, b) && passesFilter(a, b))
            add(makePairKey(a.slot, b.slot));
        }
      }
    }

    // Stage 3: huge boxes against this slab's boxes, through the cells the huge box covers when they are few
    // enough, else one by one; either way a pair is this slab's when the overlap's min corner lies in it. In
    // a cell strictly inside the huge box's range every box listed overlaps it, and the overlap's min corner
    // is in that cell exactly when the box starts there on every axis (the whole-grid search's rule).
    const double keysPerCell = double(keys) / double(cells);
    for (std::uint32_t h : huge) {
      const LocalBox a = boxOf(p, h);
      const CellRange whole = cellRange(a, g);
      if (whole.hi[A] < a0 || whole.lo[A] >= a1) continue;
      const CellRange r = toSlab(whole);
      if (double(r.count()) * (1.0 + keysPerCell) < double(m)) {
        std::uint32_t first[3], last[3] = {whole.hi[0], whole.hi[1], whole.hi[2]};
        firstCells(whole, first);
        last[A] -= a0;  // not below the slab: the range reaches it
        forEachCellOf(r, dims, [&](std::uint32_t c, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
          const std::uint32_t hugeBits = startBits(first, x, y, z);
          const bool inner = hugeBits == 0 && x != last[0] && y != last[1] && z != last[2];
          counts.candidates += start[c + 1] - start[c];
          for (std::uint32_t e = start[c]; e < start[c + 1]; ++e) {
            const std::uint32_t entry = t.entries[e];
            if (!ownedByCell(hugeBits, entry)) continue;
            const LocalBox& b = box(entry & kSlabBox);
            if (inner ? passesFilter(a, b) : boxesOverlap(a, b) && passesFilter(a, b))
              add(makePairKey(a.slot, b.slot));
          }
        });
      } else {
        counts.candidates += m;
        for (std::size_t j = 0; j < m; ++j) {
          const LocalBox& b = box(j);
          const std::uint32_t layer = cellOf(std::max(a.lo[A], b.lo[A]), g.origin[A], g.invCell, g.dims[A]);
          if (layer >= a0 && layer < a1 && boxesOverlap(a, b) && passesFilter(a, b))
            add(makePairKey(a.slot, b.slot));
        }
      }
    }
    return counts;
  };
  if (m_inPlace) return testSlab([&](std::size_t j) { return boxOf(p, member[j]); });
  return testSlab([&](std::size_t j) -> const LocalBox& { return t.box[j]; });
}

std::size_t SlabSearch::bytesOf(const Scratch& t) {
  return (t.box.capacity() + t.sorted.capacity()) * sizeof(LocalBox) +
         t.cells.capacity() * sizeof(PackedCells) +
         (t.cellStart.capacity() + t.entries.capacity() + t.wide.capacity()) * 4 + t.pairs.capacity() * 8;
}

void SlabSearch::growPairs(Scratch& t) {
  constexpr std::size_t kFirstPairs = 256;
  std::vector<std::uint64_t> bigger;
  bigger.reserve(std::max(kFirstPairs, 2 * t.pairs.capacity()));
  t.growthBytes = std::max(t.growthBytes, bytesOf(t) + bigger.capacity() * 8);
  bigger.assign(t.pairs.begin(), t.pairs.end());
  t.pairs.swap(bigger);
}

std::size_t SlabSearch::bytes() const {
  std::size_t bytes =
      (m_firstLayer.capacity() + m_layerSlab.capacity() + m_members.capacity() + m_boxLayers.capacity()) * 4 +
      (m_memberStart.capacity() + m_chunkCount.capacity()) * sizeof(std::size_t);
  // A thread's scratch only grows during a search, so its largest moment is now or while its list grew.
  for (const Scratch& t : m_scratch) bytes += std::max(bytesOf(t), t.growthBytes);
  return bytes;
}

void SlabSearch::release() {
  auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  release(m_firstLayer), release(m_layerSlab), release(m_memberStart), release(m_members);
  release(m_boxLayers);
  release(m_chunkCount);
  m_scratch.clear();
}

}  // namespace gpucol
