// The grid pair search of Avril et al. 2012 (§3–§4) in kernels; stage numbers are those of
// plugin/src/broadphase/grid_pair_finder.h, whose CPU implementation this must match pair for pair. The
// host (opencl/host/opencl_pair_finder.cpp) chooses the grid (stages 0–3) and chains these kernels with the
// scan (scan.cl) and the radix sort (radix_sort.cl).
#include "opencl/shared/grid_params.h"
#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
#include "plugin/src/shared_math/pair_mapping.h"

// Binning and the dedupe rule must compute the same cell for the same float: no contraction, no fast math.
#pragma OPENCL FP_CONTRACT OFF

#ifdef GPUCOL_RECORD_STRIDE
// Every slot's box and filter read in place in the host's records (a device that shares the host's memory:
// GridBroadphase's proxies), GPUCOL_RECORD_STRIDE bytes per slot with the fields at the byte offsets the
// host defines; and every slot's flags.
#define PROXY_PARAMS __global const uchar *boxes, __global const uchar *flags
#define WRITABLE_BOXES_PARAM __global const uchar *boxes
GpucolProxyBox load_box(__global const uchar* boxes, const uint s) {
  __global const uchar* r = boxes + (size_t)s * GPUCOL_RECORD_STRIDE;
  __global const float* lo = (__global const float*)(r + GPUCOL_RECORD_MIN);
  __global const float* hi = (__global const float*)(r + GPUCOL_RECORD_MAX);
  GpucolProxyBox b;
  b.minX = lo[0], b.minY = lo[1], b.minZ = lo[2];
  b.maxX = hi[0], b.maxY = hi[1], b.maxZ = hi[2];
  b.group = *(__global const int*)(r + GPUCOL_RECORD_GROUP);
  b.mask = *(__global const int*)(r + GPUCOL_RECORD_MASK);
  return b;
}
#else
// Every slot's box and filter in the device's copy (grid_params.h), and its flags.
#define PROXY_PARAMS __global const GpucolProxyBox *boxes, __global const uchar *flags
#define WRITABLE_BOXES_PARAM __global GpucolProxyBox *boxes
GpucolProxyBox load_box(__global const GpucolProxyBox* boxes, const uint s) {
  return boxes[s];
}
#endif
#define PROXY_ARGS boxes, flags

// Stage 8: overlap on all three axes, touching counts.
bool boxes_overlap(const GpucolProxyBox a, const GpucolProxyBox b) {
  return a.minX <= b.maxX && b.minX <= a.maxX && a.minY <= b.maxY && b.minY <= a.maxY && a.minZ <= b.maxZ &&
         b.minZ <= a.maxZ;
}

// Stage 8's filter: Bullet's group/mask rule, bit for bit.
bool filters_accept(const GpucolProxyBox a, const GpucolProxyBox b) {
  return (a.group & b.mask) != 0 && (b.group & a.mask) != 0;
}

// Stage 8: overlap and filter of slots sa and sb.
bool accept_pair(PROXY_PARAMS, const uint sa, const uint sb) {
  const GpucolProxyBox a = load_box(boxes, sa), b = load_box(boxes, sb);
  return boxes_overlap(a, b) && filters_accept(a, b);
}

// Stage 4: the cell coordinate, monotone in x (see grid_pair_finder.h).
uint cell_of(const float x, const float origin, const float invCell, const uint dim) {
  const float t = (x - origin) * invCell;
  if (!(t > 0.0f)) {
    return 0u;
  }
  if (t >= (float)(dim - 1u)) {
    return dim - 1u;
  }
  return min((uint)t, dim - 1u);
}

// Stage 4: the cells box b covers on each axis, lo[a]..hi[a].
typedef struct {
  uint lo[3];
  uint hi[3];
} CellRange;

CellRange cell_range(const GpucolProxyBox b, const GpucolGridParams g) {
  CellRange r;
  r.lo[0] = cell_of(b.minX, g.originX, g.invCell, g.dimX);
  r.hi[0] = cell_of(b.maxX, g.originX, g.invCell, g.dimX);
  r.lo[1] = cell_of(b.minY, g.originY, g.invCell, g.dimY);
  r.hi[1] = cell_of(b.maxY, g.originY, g.invCell, g.dimY);
  r.lo[2] = cell_of(b.minZ, g.originZ, g.invCell, g.dimZ);
  r.hi[2] = cell_of(b.maxZ, g.originZ, g.invCell, g.dimZ);
  return r;
}

// Stage 9: the cell holding the min corner of the overlap of a and b.
ulong overlap_cell(const GpucolProxyBox a, const GpucolProxyBox b, const GpucolGridParams g) {
  const uint cx = cell_of(max(a.minX, b.minX), g.originX, g.invCell, g.dimX);
  const uint cy = cell_of(max(a.minY, b.minY), g.originY, g.invCell, g.dimY);
  const uint cz = cell_of(max(a.minZ, b.minZ), g.originZ, g.invCell, g.dimZ);
  return ((ulong)cz * g.dimY + cy) * g.dimX + cx;
}

// Stage 7: candidate k of n objects -> (a, b); exact whatever square root (pair_mapping.h).
void map_pair(const ulong n, const ulong k, ulong* a, ulong* b) {
#if defined(GPUCOL_MAPPING_NEWTON) || !defined(cl_khr_fp64)
  gpucol_pair_from_index_newton(n, k, a, b);
#else
  gpucol_pair_from_index(n, k, a, b);
#endif
}

// Appends a pair (a < b) as the compressed key (a << slotBits) | b; the host sorts and expands them. When
// the output is full the pair is counted but not written, and the host grows the buffer and runs again.
void append_pair(const uint a, const uint b, const uint slotBits, __global ulong* pairs, const uint capacity,
                 volatile __global uint* pairCount) {
  const uint at = atomic_inc(pairCount);
  if (at < capacity) {
    pairs[at] = ((ulong)a << slotBits) | (ulong)b;
  }
}

// Stage 4, count: cells covered by each binned box.
__kernel void grid_count_cells(PROXY_PARAMS, __global const GpucolGridParams* grid, __global const uint* binned,
                               const uint binnedCount, __global uint* cellCounts, __global uint* overflow) {
  const uint i = get_global_id(0);
  if (i >= binnedCount) {
    return;
  }
  const uint s = binned[i];
  const GpucolGridParams g = *grid;
  const CellRange span = cell_range(load_box(boxes, s), g);
  const ulong count = (ulong)(span.hi[0] - span.lo[0] + 1u) * (span.hi[1] - span.lo[1] + 1u) *
                      (span.hi[2] - span.lo[2] + 1u);
  if (count > 0xffffffffUL) {
    *overflow = 1u;
  }
  cellCounts[i] = count > 0xffffffffUL ? 0u : (uint)count;
}

// Stage 4, fill: one (cell, slot) entry per covered cell, at the box's scanned offset, for the radix sort
// of a sparse grid (stage 5).
__kernel void grid_write_keys(PROXY_PARAMS, __global const GpucolGridParams* grid, __global const uint* binned,
                              const uint binnedCount, __global const uint* keyOffsets, __global ulong* cellKeys,
                              __global uint* keySlots) {
  const uint i = get_global_id(0);
  if (i >= binnedCount) {
    return;
  }
  const uint s = binned[i];
  const GpucolGridParams g = *grid;
  const CellRange span = cell_range(load_box(boxes, s), g);
  uint o = keyOffsets[i];
  for (uint z = span.lo[2]; z <= span.hi[2]; ++z) {
    for (uint y = span.lo[1]; y <= span.hi[1]; ++y) {
      const ulong row = ((ulong)z * g.dimY + y) * g.dimX;
      for (uint x = span.lo[0]; x <= span.hi[0]; ++x) {
        cellKeys[o] = row + x;
        keySlots[o] = s;
        ++o;
      }
    }
  }
}

// Stages 4-5 on a dense grid (sortsByCounting in opencl_pair_finder.h), the counting sort over the
// cells, run twice. Counting (place = 0): one atomic increment of cellStart[c + 1] per binned box of each
// cell c it covers (cellStart[0] stays 0); the host then scans them. Placing (place = 1): each entry takes
// the next place of its cell at cellStart[c + 1], which the scan left at the cell's first entry and placing
// leaves at its end, that is at cell c + 1's first: cellStart then holds every cell's first entry and the
// total. With about as many cells as boxes this costs less than a count per box and the radix sort's passes
// over every entry, and holds less. The order inside a cell depends on the threads; the pairs do not (stage 9
// orders each pair's slots, stage 10 sorts the pairs).
__kernel void grid_count_or_place_entries(PROXY_PARAMS, __global const GpucolGridParams* grid,
                                          __global const uint* binned, const uint binnedCount,
                                          volatile __global uint* cellStart, const uint place,
                                          __global uint* keySlots) {
  const uint i = get_global_id(0);
  if (i >= binnedCount) {
    return;
  }
  const uint s = binned[i];
  const GpucolGridParams g = *grid;
  const CellRange span = cell_range(load_box(boxes, s), g);
  for (uint z = span.lo[2]; z <= span.hi[2]; ++z) {
    for (uint y = span.lo[1]; y <= span.hi[1]; ++y) {
      const uint row = (z * g.dimY + y) * g.dimX;  // a dense grid's cells fit 32 bits
      for (uint x = span.lo[0]; x <= span.hi[0]; ++x) {
        const uint at = atomic_inc(&cellStart[row + x + 1u]);
        if (place) {
          keySlots[at] = s;
        }
      }
    }
  }
}

// Stage 6 on a dense grid: how many cells hold an entry, from the counts before they are scanned
// (cellCount[c + 1] is cell c's), each work-item adding up `chunk` cells with one atomic addition.
__kernel void grid_count_filled_cells(__global const uint* cellCount, const uint cells, const uint chunk,
                                      volatile __global uint* filled) {
  const ulong first = (ulong)get_global_id(0) * chunk;
  if (first >= cells) {
    return;
  }
  const uint end = (uint)min((ulong)cells, first + chunk);
  uint n = 0u;
  for (uint c = (uint)first; c < end; ++c) {
    n += cellCount[c + 1u] > 0u ? 1u : 0u;
  }
  if (n > 0u) {
    atomic_add(filled, n);
  }
}

// Stage 6 on a dense grid: 1 for each cell that holds an entry (a run).
__kernel void grid_mark_filled_cells(__global const uint* cellStart, const uint cells, __global uint* runHeads) {
  const uint c = get_global_id(0);
  if (c < cells) {
    runHeads[c] = cellStart[c + 1u] > cellStart[c] ? 1u : 0u;
  }
}

// Stage 6 on a dense grid: first entry and cell of every run (runIndex = scanned heads); runStart[runCount]
// = the entries' count.
__kernel void grid_write_filled_cells(__global const uint* cellStart, const uint cells,
                                      __global const uint* runIndex, const uint runCount, __global uint* runStart,
                                      __global uint* runCell) {
  const uint c = get_global_id(0);
  if (c >= cells) {
    return;
  }
  if (cellStart[c + 1u] > cellStart[c]) {
    runStart[runIndex[c]] = cellStart[c];
    runCell[runIndex[c]] = c;
  }
  if (c == 0u) {
    runStart[runCount] = cellStart[cells];
  }
}

// Stage 6: 1 where a run of equal cells starts in the sorted keys.
__kernel void grid_mark_runs(__global const ulong* cellKeys, const uint keyCount, __global uint* runHeads) {
  const uint i = get_global_id(0);
  if (i < keyCount) {
    runHeads[i] = (i == 0u || cellKeys[i] != cellKeys[i - 1u]) ? 1u : 0u;
  }
}

// Stage 6: first entry and cell of every run (runIndex = scanned heads); runStart[runCount] = keyCount.
__kernel void grid_write_runs(__global const ulong* cellKeys, const uint keyCount, __global const uint* runIndex,
                              const uint runCount, __global uint* runStart, __global uint* runCell) {
  const uint i = get_global_id(0);
  if (i >= keyCount) {
    return;
  }
  if (i == 0u || cellKeys[i] != cellKeys[i - 1u]) {
    runStart[runIndex[i]] = i;
    runCell[runIndex[i]] = (uint)cellKeys[i];
  }
  if (i == 0u) {
    runStart[runCount] = keyCount;
  }
}

// Stage 6: m(m-1)/2 candidates per run of m entries (the scan then numbers them globally).
__kernel void grid_count_run_pairs(__global const uint* runStart, const uint runCount, __global uint* runPairs,
                                   __global uint* overflow) {
  const uint r = get_global_id(0);
  if (r >= runCount) {
    return;
  }
  const ulong pairs = gpucol_pair_count(runStart[r + 1u] - runStart[r]);
  if (pairs > 0xffffffffUL) {
    *overflow = 1u;
  }
  runPairs[r] = pairs > 0xffffffffUL ? 0u : (uint)pairs;
}

// Stages 7–9: each work-item takes `chunkLength` consecutive candidates. The first is placed by a binary
// search over the scanned counts (its run) and the mapping function (its (i, j) in the run); the rest step
// through the run's pairs in the same row-major order, as the CPU finder does, which on a CPU device is far
// cheaper than a search and a square root per candidate (a GPU uses chunks of one). Each pair is tested,
// filtered, and kept only in the cell holding the min corner of the two boxes' overlap. A null runCell: every
// cell is a run, and a run's number is its cell (Bins::runsAreCells in opencl_pair_finder.cpp).
__kernel void grid_test_candidates(PROXY_PARAMS, __global const GpucolGridParams* grid,
                                   __global const uint* runStart, __global const uint* runCell,
                                   __global const uint* runPrefix, const uint runCount, const uint total,
                                   const uint chunkLength, __global const uint* keySlots, const uint slotBits,
                                   __global ulong* pairs, const uint capacity, volatile __global uint* pairCount) {
  const ulong begin = (ulong)get_global_id(0) * chunkLength;
  if (begin >= total) {
    return;
  }
  const uint end = (uint)min((ulong)total, begin + chunkLength);
  const GpucolGridParams g = *grid;
  // Largest r with runPrefix[r] <= k: that run has candidates and holds k (empty runs repeat a prefix).
  uint run = 0u, hi = runCount - 1u;
  while (run < hi) {
    const uint mid = run + (hi - run + 1u) / 2u;
    if (runPrefix[mid] <= (uint)begin) {
      run = mid;
    } else {
      hi = mid - 1u;
    }
  }
  uint start = runStart[run];
  uint m = runStart[run + 1u] - start;
  ulong i = 0, j = 0;
  map_pair(m, begin - runPrefix[run], &i, &j);
  uint k = (uint)begin;
  while (k < end) {
    // Row i: box a is read once for its candidates (i, j), j < m, that fall in this chunk.
    const uint a = keySlots[start + (uint)i];
    const GpucolProxyBox boxA = load_box(boxes, a);
    const uint rowEnd = (uint)min((ulong)end, (ulong)k + (m - j));
    for (; k < rowEnd; ++k, ++j) {
      const uint b = keySlots[start + (uint)j];
      const GpucolProxyBox boxB = load_box(boxes, b);
      if (boxes_overlap(boxA, boxB) && filters_accept(boxA, boxB) &&
          overlap_cell(boxA, boxB, g) == (ulong)(runCell != 0 ? runCell[run] : run)) {
        append_pair(min(a, b), max(a, b), slotBits, pairs, capacity, pairCount);
      }
    }
    if (j < m) {
      break;  // the chunk ends inside the row
    }
    // Next row, then the next run that has pairs.
    if (++i + 1u == m) {
      do {
        ++run;
      } while (run + 1u < runCount && runStart[run + 1u] - runStart[run] < 2u);
      if (run >= runCount) {
        break;
      }
      start = runStart[run];
      m = runStart[run + 1u] - start;
      i = 0;
    }
    j = i + 1u;
  }
}

// Stage 3: every huge box against every other active box; a pair of two huge boxes belongs to the row of
// the lower slot. `huge` ascends. Each item takes slots (stepping by the global size), skips those not active
// and tests each active box against every huge box: the few huge boxes stay in cache and every box is read
// once. Walking huge box by huge box instead read all active boxes once per huge box (1.6 GB for 50 huge
// boxes among 1M). Whether a box is huge itself is
// a binary search of the short list, so no list of the active slots or per-slot mark is made for this.
__kernel void grid_test_huge(PROXY_PARAMS, __global const uint* huge, const uint hugeCount,
                             const uint slotCount, const uint slotBits, __global ulong* pairs,
                             const uint capacity, volatile __global uint* pairCount) {
  for (ulong i = get_global_id(0); i < slotCount; i += get_global_size(0)) {
    const uint s = (uint)i;
    if ((flags[s] & GPUCOL_PROXY_ACTIVE) == 0u) {
      continue;
    }
    uint lo = 0u, hi = hugeCount;
    while (lo < hi) {
      const uint mid = (lo + hi) / 2u;
      if (huge[mid] < s) {
        lo = mid + 1u;
      } else {
        hi = mid;
      }
    }
    const bool alsoHuge = lo < hugeCount && huge[lo] == s;
    const GpucolProxyBox b = load_box(boxes, s);
    for (uint h = 0; h < hugeCount; ++h) {
      const uint sh = huge[h];
      if (s == sh || (alsoHuge && s < sh)) {
        continue;
      }
      const GpucolProxyBox hb = load_box(boxes, sh);
      if (boxes_overlap(hb, b) && filters_accept(hb, b)) {
        append_pair(min(sh, s), max(sh, s), slotBits, pairs, capacity, pairCount);
      }
    }
  }
}

// Stage 1: below the grid threshold every pair of the active list, through the mapping function (§3.2).
__kernel void brute_test_pairs(PROXY_PARAMS, __global const uint* active, const uint activeCount, const ulong total,
                               const uint slotBits, __global ulong* pairs, const uint capacity,
                               volatile __global uint* pairCount) {
  for (ulong k = get_global_id(0); k < total; k += get_global_size(0)) {
    ulong a = 0, b = 0;
    map_pair(activeCount, k, &a, &b);
    const uint sa = active[a];
    const uint sb = active[b];
    if (accept_pair(PROXY_ARGS, sa, sb)) {
      append_pair(sa, sb, slotBits, pairs, capacity, pairCount);
    }
  }
}

// Stage 11: writes the slots that changed since the last search into the kept arrays and marks them as no
// longer resting (their entries in the kept cells, and their pairs of the last search, are stale).
__kernel void grid_update_proxies(WRITABLE_BOXES_PARAM, __global uchar* flags, __global uchar* resting,
                                  __global const GpucolProxyUpdate* updates, const uint updateCount) {
  const uint i = get_global_id(0);
  if (i >= updateCount) {
    return;
  }
  const GpucolProxyUpdate u = updates[i];
#ifndef GPUCOL_RECORD_STRIDE  // read in place, the record holds the box already
  boxes[u.slot] = u.box;
#endif
  flags[u.slot] = (uchar)u.flags;
  resting[u.slot] = 0u;
}

// Stage 11: each moved (binned) proxy against the kept grid. For every cell of its range on the kept grid,
// the kept run of that cell (runs are in ascending cell order: one binary search per row of cells, then a
// walk along the row) gives the resting proxies binned there; entries of proxies that changed since the
// grid was built are stale and skipped. A pair is kept only in the cell holding the min corner of the
// overlap, as in stage 9, so it is reported once. Then the kept huge boxes that still rest. Moved proxies
// among themselves go through stages 4-9 on their own entries; moved huge boxes through grid_test_huge.
__kernel void grid_test_moved(PROXY_PARAMS, __global const GpucolGridParams* grid, __global const uchar* resting,
                              __global const uint* runStart, __global const uint* runCell, const uint runCount,
                              __global const uint* keySlots, __global const uint* keptHuge,
                              const uint keptHugeCount, __global const uint* moved, const uint movedCount,
                              const uint slotBits, __global ulong* pairs, const uint capacity,
                              volatile __global uint* pairCount) {
  const uint i = get_global_id(0);
  if (i >= movedCount) {
    return;
  }
  const uint sm = moved[i];
  const GpucolGridParams g = *grid;
  const GpucolProxyBox boxM = load_box(boxes, sm);
  const CellRange span = cell_range(boxM, g);
  for (uint z = span.lo[2]; z <= span.hi[2]; ++z) {
    for (uint y = span.lo[1]; y <= span.hi[1]; ++y) {
      const uint row = (uint)(((ulong)z * g.dimY + y) * g.dimX);
      // First run whose cell is at least the row's first cell of the range: that cell's own when every cell
      // is a run (no runCell), else found by binary search.
      uint r = row + span.lo[0];
      if (runCell != 0) {
        uint lo = 0u, hi = runCount;
        while (lo < hi) {
          const uint mid = lo + (hi - lo) / 2u;
          if (runCell[mid] < row + span.lo[0]) {
            lo = mid + 1u;
          } else {
            hi = mid;
          }
        }
        r = lo;
      }
      for (; r < runCount; ++r) {
        const uint c = runCell != 0 ? runCell[r] : r;
        if (c > row + span.hi[0]) {
          break;
        }
        for (uint e = runStart[r]; e < runStart[r + 1u]; ++e) {
          const uint s = keySlots[e];
          if (!resting[s]) {
            continue;
          }
          const GpucolProxyBox box = load_box(boxes, s);
          if (boxes_overlap(boxM, box) && filters_accept(boxM, box) &&
              overlap_cell(boxM, box, g) == (ulong)c) {
            append_pair(min(sm, s), max(sm, s), slotBits, pairs, capacity, pairCount);
          }
        }
      }
    }
  }
  for (uint h = 0u; h < keptHugeCount; ++h) {
    const uint s = keptHuge[h];
    if (resting[s] && accept_pair(PROXY_ARGS, sm, s)) {
      append_pair(min(sm, s), max(sm, s), slotBits, pairs, capacity, pairCount);
    }
  }
}
