// Middle phase of the mesh pipeline on the device (thesis §5.4.2): tree against tree, breadth-first, one
// level per launch, segmented over every mesh pair of the batch (each front entry carries its pair, thesis
// §7.3). Each level runs twice: a counting pass writes, per front entry, how many child node pairs overlap,
// how many candidate triangle pairs it emits and how many box tests it made; the host scans the counts
// (scan.cl, Fig. 5.8) and sizes the next front and the candidate list from the totals; the writing pass
// repeats the tests and writes at the scanned offsets. So nothing has a fixed capacity.
//
// The box tests are those of plugin/src/bvh/tree_traversal.cpp (in both frames: B's box carried into A's, A's
// into B's), from the same source (plugin/src/shared_math/box_carry.h) and with no contraction, so the device
// finds exactly the CPU's candidates.
#include "opencl/shared/mesh_pipeline_types.h"
#include "plugin/src/shared_math/box_carry.h"

#pragma OPENCL FP_CONTRACT OFF

typedef struct CarriedBox {
  float min[3];
  float max[3];
} CarriedBox;

// centre' = M c + t, extent' = |M| e + inflation (box_carry.h).
CarriedBox mesh_carry(__global const GpucolBoxMap* m, __global const float* lo, __global const float* hi) {
  float c[3], e[3];
  for (int j = 0; j < 3; ++j) {
    c[j] = (lo[j] + hi[j]) * 0.5f;
    e[j] = (hi[j] - lo[j]) * 0.5f;
  }
  CarriedBox out;
  for (int i = 0; i < 3; ++i) {
    const float ci = GPUCOL_CARRY_ROW(m->linear[3 * i], m->linear[3 * i + 1], m->linear[3 * i + 2], c[0], c[1],
                                      c[2], m->translation[i]);
    const float ei = GPUCOL_CARRY_ROW(m->absLinear[3 * i], m->absLinear[3 * i + 1], m->absLinear[3 * i + 2], e[0],
                                      e[1], e[2], m->inflation[i]);
    out.min[i] = ci - ei;
    out.max[i] = ci + ei;
  }
  return out;
}

// Touching counts as overlapping (tree_traversal.cpp's overlaps()).
bool mesh_overlaps(__global const float* lo, __global const float* hi, const CarriedBox* b) {
  return GPUCOL_BOXES_OVERLAP(lo, hi, b->min, b->max);
}

// A's box [loA, hiA] and B's [loB, hiB] overlap in A's frame (B's carried in) and in B's (A's carried in).
bool mesh_boxes_overlap(__global const GpucolMeshPair* p, __global const float* loA, __global const float* hiA,
                        __global const float* loB, __global const float* hiB) {
  const CarriedBox inA = mesh_carry(&p->intoA, loB, hiB);
  const CarriedBox inB = mesh_carry(&p->intoB, loA, hiA);
  return mesh_overlaps(loA, hiA, &inA) & mesh_overlaps(loB, hiB, &inB);
}

bool mesh_nodes_overlap(__global const GpucolMeshPair* p, __global const GpucolTreeNode* nodes, uint a,
                        uint b) {
  __global const GpucolTreeNode* na = nodes + p->nodesA + a;
  __global const GpucolTreeNode* nb = nodes + p->nodesB + b;
  return mesh_boxes_overlap(p, na->min, na->max, nb->min, nb->max);
}

// The box and index of the i-th triangle of a leaf (tree_traversal.cpp's leafTriangle): a leaf of one
// triangle has the triangle's box, a leaf of several an entry per triangle.
typedef struct LeafTriangle {
  __global const float* lo;
  __global const float* hi;
  uint triangle;
} LeafTriangle;

LeafTriangle mesh_leaf_triangle(__global const GpucolTreeNode* leaf, __global const GpucolLeafEntry* entries,
                                uint i) {
  LeafTriangle out;
  if (leaf->count == 1u) {
    out.lo = leaf->min;
    out.hi = leaf->max;
    out.triangle = leaf->first;
  } else {
    __global const GpucolLeafEntry* entry = entries + leaf->first + i;
    out.lo = entry->min;
    out.hi = entry->max;
    out.triangle = entry->triangle;
  }
  return out;
}

ulong mesh_candidate_key(uint pair, uint triangleA, uint triangleB, uint bitsA, uint bitsB) {
  return ((ulong)pair << (bitsA + bitsB)) | ((ulong)triangleA << bitsB) | (ulong)triangleB;
}

// The first front: for every pair, the node pairs `startDepth` expansions below the roots whose boxes overlap
// and whose ancestors' boxes all overlap (so the front is the one the level-by-level descent would reach, and
// the candidates stay the CPU's). Work-item = (pair, path): two bits of the path per level choose A's and B's
// child; a side that is already a leaf must take bit 0 (it does not descend, thesis Alg. 5.1), and a leaf
// pair reached early must take 0 for every remaining level, so each node pair comes from exactly one path.
// startDepth 0 is the root test alone. Counting pass: counts[item] = 0 or 1; writing pass: `counts` holds
// the scanned offsets.
__kernel void mesh_front_start(__global const GpucolMeshPair* pairs, __global const GpucolTreeNode* nodes,
                               const uint pairCount, const uint startDepth, const uint write,
                               __global uint* counts, __global GpucolFrontEntry* front) {
  const uint item = get_global_id(0);
  const uint pathsPerPair = 1u << (2u * startDepth);
  if (item >= pairCount * pathsPerPair) return;
  const uint pair = item >> (2u * startDepth);
  const uint path = item & (pathsPerPair - 1u);
  __global const GpucolMeshPair* p = pairs + pair;
  uint a = 0u, b = 0u;
  bool found = mesh_nodes_overlap(p, nodes, a, b);
  for (uint level = 0u; found && level < startDepth; ++level) {
    const uint bitA = (path >> (2u * level)) & 1u;
    const uint bitB = (path >> (2u * level + 1u)) & 1u;
    __global const GpucolTreeNode* na = nodes + p->nodesA + a;
    __global const GpucolTreeNode* nb = nodes + p->nodesB + b;
    const bool leafA = na->count != 0u;
    const bool leafB = nb->count != 0u;
    if (leafA && leafB) {
      found = (path >> (2u * level)) == 0u;
      break;
    }
    if (leafA) {
      found = bitA == 0u;
    } else {
      a = bitA ? na->first : a + 1u;
    }
    if (leafB) {
      found = found && bitB == 0u;
    } else {
      b = bitB ? nb->first : b + 1u;
    }
    found = found && mesh_nodes_overlap(p, nodes, a, b);
  }
  if (!write) {
    counts[item] = found ? 1u : 0u;
  } else if (found) {
    GpucolFrontEntry entry;
    entry.pair = pair;
    entry.a = a;
    entry.b = b;
    front[counts[item]] = entry;
  }
}

// One level of the descent (thesis Alg. 5.1, §5.4.2): node-node gives 4 tests, leaf-node 2, leaf-leaf pairs
// become candidates. Leaves of several triangles test their triangles' boxes, as the CPU's emitLeafPair does.
// Counting pass: counts[i] = overlapping children, counts[n + i] = candidates, counts[2n + i] = box tests.
// Writing pass: `counts` holds the exclusive scan of those 3n values; children go to next[counts[i]] and
// candidates to keys[keyBase + counts[n + i] - childTotal] (childTotal = counts[n], the scan's value there).
__kernel void mesh_front_expand(__global const GpucolMeshPair* pairs, __global const GpucolTreeNode* nodes,
                                __global const GpucolLeafEntry* entries,
                                __global const GpucolFrontEntry* front, const uint n, const uint write,
                                __global uint* counts, __global GpucolFrontEntry* next, __global ulong* keys,
                                const uint keyBase, const uint childTotal, const uint bitsA,
                                const uint bitsB) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  const GpucolFrontEntry entry = front[i];
  __global const GpucolMeshPair* p = pairs + entry.pair;
  __global const GpucolTreeNode* na = nodes + p->nodesA + entry.a;
  __global const GpucolTreeNode* nb = nodes + p->nodesB + entry.b;
  const bool leafA = na->count != 0u;
  const bool leafB = nb->count != 0u;
  uint children = 0u, candidates = 0u, tests = 0u;
  const uint childAt = write ? counts[i] : 0u;
  const uint keyAt = write ? keyBase + (counts[n + i] - childTotal) : 0u;
  GpucolFrontEntry child;
  child.pair = entry.pair;
  if (!leafA && !leafB) {
    const uint childrenA[2] = {entry.a + 1u, na->first};
    const uint childrenB[2] = {entry.b + 1u, nb->first};
    for (int k = 0; k < 2; ++k) {
      __global const GpucolTreeNode* cb = nodes + p->nodesB + childrenB[k];
      for (int m = 0; m < 2; ++m) {
        __global const GpucolTreeNode* ca = nodes + p->nodesA + childrenA[m];
        if (mesh_boxes_overlap(p, ca->min, ca->max, cb->min, cb->max)) {
          if (write) {
            child.a = childrenA[m];
            child.b = childrenB[k];
            next[childAt + children] = child;
          }
          ++children;
        }
      }
    }
    tests = 4u;
  } else if (leafA && !leafB) {
    const uint childrenB[2] = {entry.b + 1u, nb->first};
    for (int k = 0; k < 2; ++k) {
      __global const GpucolTreeNode* cb = nodes + p->nodesB + childrenB[k];
      if (mesh_boxes_overlap(p, na->min, na->max, cb->min, cb->max)) {
        if (write) {
          child.a = entry.a;
          child.b = childrenB[k];
          next[childAt + children] = child;
        }
        ++children;
      }
    }
    tests = 2u;
  } else if (!leafA && leafB) {
    const uint childrenA[2] = {entry.a + 1u, na->first};
    for (int m = 0; m < 2; ++m) {
      __global const GpucolTreeNode* ca = nodes + p->nodesA + childrenA[m];
      if (mesh_boxes_overlap(p, ca->min, ca->max, nb->min, nb->max)) {
        if (write) {
          child.a = childrenA[m];
          child.b = entry.b;
          next[childAt + children] = child;
        }
        ++children;
      }
    }
    tests = 2u;
  } else if (na->count == 1u && nb->count == 1u) {
    // Leaves of one triangle: the leaf box is the triangle box, so the pair is a candidate.
    if (write) keys[keyAt] = mesh_candidate_key(entry.pair, na->first, nb->first, bitsA, bitsB);
    candidates = 1u;
  } else {
    for (uint j = 0u; j < nb->count; ++j) {
      const LeafTriangle triangleB = mesh_leaf_triangle(nb, entries + p->entriesB, j);
      for (uint k = 0u; k < na->count; ++k) {
        const LeafTriangle triangleA = mesh_leaf_triangle(na, entries + p->entriesA, k);
        ++tests;
        if (mesh_boxes_overlap(p, triangleA.lo, triangleA.hi, triangleB.lo, triangleB.hi)) {
          if (write)
            keys[keyAt + candidates] =
                mesh_candidate_key(entry.pair, triangleA.triangle, triangleB.triangle, bitsA, bitsB);
          ++candidates;
        }
      }
    }
  }
  if (!write) {
    counts[i] = children;
    counts[n + i] = candidates;
    counts[2u * n + i] = tests;
  }
}

// The depth-first alternative to the level-by-level descent above: one launch for the whole middle phase.
// Work-item = (pair, path) as in mesh_front_start, but with the levels' bits in the opposite order (the
// roots' choice highest, so that the paths below one node pair are consecutive): it walks its path
// `startDepth` levels down (the breadth-first front, with the same rules so that every front entry comes from
// exactly one path), then descends from its entry depth-first with a private stack, as a CPU thread would
// (tree_traversal.cpp, Alg. 5.1). Candidates are appended at an atomic counter: keys[n] for n < capacity; the
// host reads the counter and, when it went past the capacity, grows the buffer and runs the pass again, so
// nothing is ever dropped. The order of the appended keys varies between runs; the radix sort that follows
// gives the deterministic order.
//
// counters[0] = candidates appended, counters[1] = 1 when the counter wrapped past 2^32 - 1 (the host then
// refuses the batch), counters[2] / counters[3] = low / high word of the box tests. The tests are counted as
// the breadth-first descent counts them: each overlapping node pair's child tests once, by the path whose
// remaining bits are all zero below that pair (the root test is the host's).
//
// GPUCOL_DFS_STACK (a build option) is the stack's length: the host builds the kernel with at least
// 3 (depthA + depthB) + 1 entries for the deepest trees of the batch (each expansion pops one pair and pushes
// at most four, one level further down), so the stack cannot overflow.
#ifdef GPUCOL_DFS_STACK

// One frame's map (GpucolBoxMap) in vector form, read once per work-item: columns of M and |M| with the
// translation and the inflation, lane 3 zero. The depth-first kernel carries a box with 4-lane operations in the scalar code's
// order (((M_i0 c_0 + M_i1 c_1) + M_i2 c_2) + t_i), as tree_traversal.cpp's SSE path does, so the bits are
// mesh_carry's: a CPU device runs this divergent loop one work-item at a time, and 4 lanes are what it can
// vectorise there.
typedef struct Carrier4 {
  float4 column[3];
  float4 absColumn[3];
  float4 translation;
  float4 inflation;
} Carrier4;

Carrier4 mesh_carrier4(__global const GpucolBoxMap* m) {
  Carrier4 k;
  for (int j = 0; j < 3; ++j) {
    k.column[j] = (float4)(m->linear[j], m->linear[3 + j], m->linear[6 + j], 0.0f);
    k.absColumn[j] = (float4)(m->absLinear[j], m->absLinear[3 + j], m->absLinear[6 + j], 0.0f);
  }
  k.translation = (float4)(m->translation[0], m->translation[1], m->translation[2], 0.0f);
  k.inflation = (float4)(m->inflation[0], m->inflation[1], m->inflation[2], 0.0f);
  return k;
}

// A node read whole (32 bytes): its corners with lane 3 zero, `first` and `count`.
typedef struct Node4 {
  float4 lo;
  float4 hi;
  uint first;
  uint count;
} Node4;

Node4 mesh_node4(__global const GpucolTreeNode* node) {
  const float8 raw = vload8(0, (__global const float*)node);
  Node4 n;
  n.lo = (float4)(raw.s012, 0.0f);
  n.hi = (float4)(raw.s345, 0.0f);
  n.first = as_uint(raw.s6);
  n.count = as_uint(raw.s7);
  return n;
}

typedef struct Box4 {
  float4 lo;
  float4 hi;
} Box4;

Box4 mesh_carry4(const Carrier4* k, float4 lo, float4 hi) {
  const float4 c = (lo + hi) * 0.5f;
  const float4 e = (hi - lo) * 0.5f;
  const float4 centre = GPUCOL_CARRY_ROW(k->column[0], k->column[1], k->column[2], c.x, c.y, c.z, k->translation);
  const float4 extent =
      GPUCOL_CARRY_ROW(k->absColumn[0], k->absColumn[1], k->absColumn[2], e.x, e.y, e.z, k->inflation);
  Box4 out;
  out.lo = centre - extent;
  out.hi = centre + extent;
  return out;
}

// mesh_overlaps on 4 lanes (lane 3 compares zeros and passes); 1 or 0, for branch-free pushes.
uint mesh_overlaps4(float4 lo, float4 hi, const Box4* b) {
  const int4 ok = (lo <= b->hi) & (b->lo <= hi);
  return (uint)(ok.x & ok.y & ok.z) & 1u;
}

// mesh_boxes_overlap on 4 lanes: A's box and B's overlap in both frames; 1 or 0.
uint mesh_boxes_overlap4(const Carrier4* intoA, const Carrier4* intoB, float4 loA, float4 hiA, float4 loB,
                         float4 hiB) {
  const Box4 inA = mesh_carry4(intoA, loB, hiB);
  const Box4 inB = mesh_carry4(intoB, loA, hiA);
  return mesh_overlaps4(loA, hiA, &inA) & mesh_overlaps4(loB, hiB, &inB);
}

// Where both nodes descend, two children are carried together, one per half of a float8 (lanes 0-3 and
// 4-7), as tree_traversal.cpp's carryPair does: lane for lane mesh_carry4's operations in its order, so the
// same bits, in half the carrying instructions (measurement history, "Figures moved from code comments").
typedef struct Carrier8 {
  float8 column[3];
  float8 absColumn[3];
  float8 translation;
  float8 inflation;
} Carrier8;

Carrier8 mesh_carrier8(const Carrier4* k) {
  Carrier8 w;
  for (int j = 0; j < 3; ++j) {
    w.column[j] = (float8)(k->column[j], k->column[j]);
    w.absColumn[j] = (float8)(k->absColumn[j], k->absColumn[j]);
  }
  w.translation = (float8)(k->translation, k->translation);
  w.inflation = (float8)(k->inflation, k->inflation);
  return w;
}

typedef struct Box8 {
  float8 lo;
  float8 hi;
} Box8;

// mesh_carry4 of box 0 into lanes 0-3 and of box 1 into lanes 4-7.
Box8 mesh_carry8(const Carrier8* k, float4 lo0, float4 hi0, float4 lo1, float4 hi1) {
  const float8 lo = (float8)(lo0, lo1), hi = (float8)(hi0, hi1);
  const float8 c = (lo + hi) * 0.5f;
  const float8 e = (hi - lo) * 0.5f;
  const float8 centre = GPUCOL_CARRY_ROW(k->column[0], k->column[1], k->column[2], c.s00004444, c.s11115555,
                                         c.s22226666, k->translation);
  const float8 extent = GPUCOL_CARRY_ROW(k->absColumn[0], k->absColumn[1], k->absColumn[2], e.s00004444,
                                         e.s11115555, e.s22226666, k->inflation);
  Box8 out;
  out.lo = centre - extent;
  out.hi = centre + extent;
  return out;
}

// The comparisons of mesh_overlaps4 of [lo, hi] against both boxes of `b`: lanes 0-3 against box 0, 4-7
// against box 1 (-1 where the axis overlaps; lanes 3 and 7 compare zeros and pass).
int8 mesh_overlaps8(float4 lo, float4 hi, const Box8* b) {
  return ((float8)(lo, lo) <= b->hi) & (b->lo <= (float8)(hi, hi));
}

// 1 when lanes x, y, z of `ok` are all set, else 0, without a branch (PoCL's all() branches per lane).
uint mesh_all_axes(int4 ok) {
  return (uint)(ok.x & ok.y & ok.z) & 1u;
}

// Both frames' maps of one mesh pair, read once per pair rather than once per start path.
typedef struct PairCarriers {
  Carrier4 intoA;
  Carrier4 intoB;
  Carrier8 intoA8;
  Carrier8 intoB8;
} PairCarriers;

PairCarriers mesh_pair_carriers(__global const GpucolMeshPair* p) {
  PairCarriers k;
  k.intoA = mesh_carrier4(&p->intoA);
  k.intoB = mesh_carrier4(&p->intoB);
  k.intoA8 = mesh_carrier8(&k.intoA);
  k.intoB8 = mesh_carrier8(&k.intoB);
  return k;
}

// Asks for a node to be brought into the cache. On a CPU device the traversal waits on cache misses (the node
// arena of a 400K-triangle mesh is 25 MB), so the host builds this kernel with GPUCOL_CPU_PREFETCH there:
// OpenCL's prefetch() is an empty function in PoCL, clang's builtin is a prefetch instruction. A hint only;
// it never faults, so an address past the arena (a leaf's `first` is a triangle) is harmless. Elsewhere
// nothing: a GPU hides the latency with other work-items.
#if defined(GPUCOL_CPU_PREFETCH) && defined(__has_builtin)
#if __has_builtin(__builtin_prefetch)
#define GPUCOL_PREFETCH_NODE(node) __builtin_prefetch(node)
#endif
#endif
#ifndef GPUCOL_PREFETCH_NODE
#define GPUCOL_PREFETCH_NODE(node) ((void)(node))
#endif

// Expansions between popping a pair and expanding it: 4 on a CPU device (tree_traversal.cpp's kLookahead,
// whose cache misses it hides), 1 (a plain descent) elsewhere.
//
// The stack's length, GPUCOL_DFS_ROOM: a plain descent needs GPUCOL_DFS_STACK. With the ring, while the stack
// holds at most GPUCOL_DFS_STACK entries the ring is refilled; each of its at most GPUCOL_DFS_LOOKAHEAD
// expansions then pushes at most four, so the stack reaches at most GPUCOL_DFS_STACK + 4 GPUCOL_DFS_LOOKAHEAD
// before the descent turns plain, and a plain descent adds at most 3 per level below the pair it pops, at
// most GPUCOL_DFS_STACK in all.
#ifdef GPUCOL_CPU_PREFETCH
#define GPUCOL_DFS_LOOKAHEAD 4u
#else
#define GPUCOL_DFS_LOOKAHEAD 1u
#endif
#define GPUCOL_DFS_ROOM \
  (GPUCOL_DFS_LOOKAHEAD > 1u ? 2u * GPUCOL_DFS_STACK + 4u * GPUCOL_DFS_LOOKAHEAD : GPUCOL_DFS_STACK)

void mesh_count_tests(__global uint* counters, uint tests) {
  if (tests == 0u) return;
  const uint old = atomic_add(&counters[2], tests);
  if (old + tests < old) atomic_inc(&counters[3]);
}

// Candidates wait in a private batch of GPUCOL_DFS_BATCH and go out with one atomic_add for the batch: an
// atomic per candidate made the two threads of a CPU device take turns at one cache line.
#define GPUCOL_DFS_BATCH 16

// GPUCOL_FUSED_NEAR (a CPU device's default path; the host builds mesh_near_phase.cl's source and this one
// as one program): each batch of candidates takes the near test (mesh_test_lanes) as soon as it is written,
// so the traversal and the near phase are one launch (faster on PoCL than two kernels: measurement history,
// "Figures moved from code comments").
#ifdef GPUCOL_FUSED_NEAR
#define GPUCOL_NEAR_PARAMS , __global const float *restrict soup, __global GpucolNearHit *restrict hits
#define GPUCOL_NEAR_ARGS , soup, hits
#else
#define GPUCOL_NEAR_PARAMS
#define GPUCOL_NEAR_ARGS
#endif

// The fused near test reads a candidate's two triangles from the soup when its batch is flushed, up to
// GPUCOL_DFS_BATCH candidates later: asking for them when the candidate is found overlaps those cache misses
// (the soup of a 400K-triangle mesh is 14 MB) with the traversal, as cpu_mesh_pair.cpp's kSoupAhead does.
// A triangle's 36 bytes may straddle two cache lines, so both are asked for.
#if defined(GPUCOL_FUSED_NEAR) && defined(GPUCOL_CPU_PREFETCH)
#define GPUCOL_PREFETCH_TRIANGLE(t)             \
  do {                                          \
    GPUCOL_PREFETCH_NODE(soup + 9u * (t));      \
    GPUCOL_PREFETCH_NODE(soup + 9u * (t) + 8u); \
  } while (0)
#define GPUCOL_PREFETCH_CANDIDATE(p, triangleA, triangleB)   \
  do {                                                       \
    GPUCOL_PREFETCH_TRIANGLE((p)->trianglesA + (triangleA)); \
    GPUCOL_PREFETCH_TRIANGLE((p)->trianglesB + (triangleB)); \
  } while (0)
#else
#define GPUCOL_PREFETCH_CANDIDATE(p, triangleA, triangleB) ((void)0)
#endif

void mesh_flush_keys(__global const GpucolMeshPair* restrict pairs, __global uint* counters,
                     __global ulong* keys, uint capacity, const ulong* batch, uint count, const uint bitsA,
                     const uint bitsB GPUCOL_NEAR_PARAMS) {
  if (count == 0u) return;
  const uint at = atomic_add(&counters[0], count);
  if (at + count < at) counters[1] = 1u;
  for (uint i = 0u; i < count; ++i) {
    if (at + i >= at && at + i < capacity) keys[at + i] = batch[i];
  }
#ifdef GPUCOL_FUSED_NEAR
  // Keys past the capacity were not written: the host runs the pass again with room for all and drops
  // whatever hits this one appended.
  if (at + count < at || at + count > capacity) return;
  for (uint first = at; first < at + count; first += GPUCOL_LANES)
    mesh_test_lanes(pairs, soup, keys, first, at + count, bitsA, bitsB, hits, counters);
#endif
}

// The depth-first descent below start path `item` (pair, path) of mesh_traverse_depth_first: candidates go
// through the private `batch` of *batchedOut keys (flushed when full), box tests are added to *testsOut.
void mesh_depth_first_path(__global const GpucolMeshPair* restrict pairs,
                           __global const GpucolTreeNode* restrict nodes,
                           __global const GpucolLeafEntry* restrict entries, const uint item,
                           const uint startDepth, __global ulong* restrict keys, const uint capacity,
                           __global uint* restrict counters, const uint bitsA, const uint bitsB,
                           const PairCarriers* carriers, ulong* batch, uint* batchedOut,
                           uint* testsOut GPUCOL_NEAR_PARAMS) {
  const uint pathsPerPair = 1u << (2u * startDepth);
  const uint pair = item >> (2u * startDepth);
  const uint path = item & (pathsPerPair - 1u);
  __global const GpucolMeshPair* p = pairs + pair;
  __global const GpucolTreeNode* treeA = nodes + p->nodesA;
  __global const GpucolTreeNode* treeB = nodes + p->nodesB;
  __global const GpucolLeafEntry* entriesA = entries + p->entriesA;
  __global const GpucolLeafEntry* entriesB = entries + p->entriesB;
  const Carrier4 intoA = carriers->intoA;
  const Carrier4 intoB = carriers->intoB;
  const Carrier8 intoA8 = carriers->intoA8;
  const Carrier8 intoB8 = carriers->intoB8;
  const ulong pairKey = (ulong)pair << (bitsA + bitsB);
  uint tests = *testsOut;
  uint batched = *batchedOut;

  // The path down to the start front. The root test repeats the host's (which sends only overlapping pairs),
  // so that this kernel alone decides, as mesh_front_start does.
  // Level l's two bits are bits 2 (startDepth - 1 - l) and up: the roots' choice is the highest, so the paths
  // that share a walk down to some level are consecutive. deadBits: where the walk dies now, so do the paths
  // that differ from this one only in the low deadBits bits.
  uint a = 0u, b = 0u;
  Node4 na = mesh_node4(treeA), nb = mesh_node4(treeB);
  bool found = mesh_boxes_overlap4(&intoA, &intoB, na.lo, na.hi, nb.lo, nb.hi) != 0u;
  uint deadBits = 2u * startDepth;
  for (uint level = 0u; found && level < startDepth; ++level) {
    const uint shift = 2u * (startDepth - 1u - level);
    const uint fromHere = path & ((4u << shift) - 1u);  // the bits of this level and those below
    const bool leafA = na.count != 0u;
    const bool leafB = nb.count != 0u;
    if (leafA && leafB) {
      // The first path below the leaf pair goes on; the rest of its block dies.
      found = fromHere == 0u;
      deadBits = shift + 2u;
      break;
    }
    if (fromHere == 0u) tests += (leafA || leafB) ? 2u : 4u;
    const uint bitA = (path >> shift) & 1u;
    const uint bitB = (path >> (shift + 1u)) & 1u;
    deadBits = shift;
    if (leafA) {
      found = bitA == 0u;
    } else {
      a = bitA ? na.first : a + 1u;
    }
    if (leafB) {
      found = found && bitB == 0u;
    } else {
      b = bitB ? nb.first : b + 1u;
    }
    na = mesh_node4(treeA + a);
    nb = mesh_node4(treeB + b);
    found = found && mesh_boxes_overlap4(&intoA, &intoB, na.lo, na.hi, nb.lo, nb.hi) != 0u;
  }
  if (!found) {
#ifdef GPUCOL_SKIP_DEAD_PATHS
    // The paths of the dead block after this one would walk the same way and die at the same place (without
    // counting a test: the counting path of a block is its first): the shared counter moves past them, so
    // nobody takes them (the deeper the start, the more it saves: measurement history, "Figures moved from
    // code comments").
    atomic_max(&counters[5], (item | ((1u << deadBits) - 1u)) + 1u);
#endif
    *testsOut = tests;
    return;
  }

  // Children are written at the top in any case and the top moves up by the box test's outcome (no branch:
  // the tests come out about half and half), so the stack has one entry of room past its bound
  // (GPUCOL_DFS_ROOM).
  uint2 stack[GPUCOL_DFS_ROOM + 1];
  uint top = 0u;
  stack[top++] = (uint2)(a, b);
  // A popped pair waits in the ring for GPUCOL_DFS_LOOKAHEAD - 1 expansions, its nodes asked for when it
  // enters, as in tree_traversal.cpp's Traverser::run. The ring is refilled only while the stack is within
  // GPUCOL_DFS_STACK, else only when empty (a plain descent): see GPUCOL_DFS_ROOM for the bound.
  uint2 ring[GPUCOL_DFS_LOOKAHEAD];
  uint head = 0u, waiting = 0u;
  for (;;) {
    while (waiting < GPUCOL_DFS_LOOKAHEAD && top > 0u && (waiting == 0u || top <= GPUCOL_DFS_STACK)) {
      const uint2 entering = stack[--top];
      GPUCOL_PREFETCH_NODE(treeA + entering.x);
      GPUCOL_PREFETCH_NODE(treeB + entering.y);
      ring[(head + waiting) % GPUCOL_DFS_LOOKAHEAD] = entering;
      ++waiting;
    }
    if (waiting == 0u) break;
    a = ring[head].x;
    b = ring[head].y;
    head = (head + 1u) % GPUCOL_DFS_LOOKAHEAD;
    --waiting;
    na = mesh_node4(treeA + a);
    nb = mesh_node4(treeB + b);
    const bool leafA = na.count != 0u;
    const bool leafB = nb.count != 0u;
    if (!leafA && !leafB) {
      const uint a0 = a + 1u, a1 = na.first;
      const Node4 ca0 = mesh_node4(treeA + a0), ca1 = mesh_node4(treeA + a1);
      const uint b0 = b + 1u, b1 = nb.first;
      const Node4 cb0 = mesh_node4(treeB + b0), cb1 = mesh_node4(treeB + b1);
      // The children's far children (the near one is the next node) are what the pairs pushed now read when
      // popped, as in tree_traversal.cpp.
      GPUCOL_PREFETCH_NODE(treeA + ca0.first);
      GPUCOL_PREFETCH_NODE(treeA + ca1.first);
      GPUCOL_PREFETCH_NODE(treeB + cb0.first);
      GPUCOL_PREFETCH_NODE(treeB + cb1.first);
      // Each child carried once into the other frame, for two tests; B's two children together and A's
      // two together (mesh_carry8). with0 holds A0 against B0 (lanes 0-3) and B1 (4-7), with1 the same for
      // A1; inB0 holds B0 against A0 (0-3) and A1 (4-7), inB1 the same for B1. A child pair overlaps where
      // all three axes do in both frames.
      const Box8 boxesB = mesh_carry8(&intoA8, cb0.lo, cb0.hi, cb1.lo, cb1.hi);
      const Box8 boxesA = mesh_carry8(&intoB8, ca0.lo, ca0.hi, ca1.lo, ca1.hi);
      const int8 inB0 = mesh_overlaps8(cb0.lo, cb0.hi, &boxesA);
      const int8 inB1 = mesh_overlaps8(cb1.lo, cb1.hi, &boxesA);
      const int8 withB0 = mesh_overlaps8(ca0.lo, ca0.hi, &boxesB) & (int8)(inB0.lo, inB1.lo);
      const int8 withB1 = mesh_overlaps8(ca1.lo, ca1.hi, &boxesB) & (int8)(inB0.hi, inB1.hi);
      stack[top] = (uint2)(a0, b0);
      top += mesh_all_axes(withB0.lo);
      stack[top] = (uint2)(a1, b0);
      top += mesh_all_axes(withB1.lo);
      stack[top] = (uint2)(a0, b1);
      top += mesh_all_axes(withB0.hi);
      stack[top] = (uint2)(a1, b1);
      top += mesh_all_axes(withB1.hi);
      tests += 4u;
    } else if (leafA && !leafB) {
      const uint b0 = b + 1u, b1 = nb.first;
      const Node4 cb0 = mesh_node4(treeB + b0), cb1 = mesh_node4(treeB + b1);
      GPUCOL_PREFETCH_NODE(treeB + cb0.first);
      GPUCOL_PREFETCH_NODE(treeB + cb1.first);
      const Box4 box0 = mesh_carry4(&intoA, cb0.lo, cb0.hi);
      const Box4 box1 = mesh_carry4(&intoA, cb1.lo, cb1.hi);
      const Box4 boxA = mesh_carry4(&intoB, na.lo, na.hi);
      stack[top] = (uint2)(a, b0);
      top += mesh_overlaps4(na.lo, na.hi, &box0) & mesh_overlaps4(cb0.lo, cb0.hi, &boxA);
      stack[top] = (uint2)(a, b1);
      top += mesh_overlaps4(na.lo, na.hi, &box1) & mesh_overlaps4(cb1.lo, cb1.hi, &boxA);
      tests += 2u;
    } else if (!leafA && leafB) {
      const uint a0 = a + 1u, a1 = na.first;
      const Node4 ca0 = mesh_node4(treeA + a0), ca1 = mesh_node4(treeA + a1);
      GPUCOL_PREFETCH_NODE(treeA + ca0.first);
      GPUCOL_PREFETCH_NODE(treeA + ca1.first);
      const Box4 boxB = mesh_carry4(&intoA, nb.lo, nb.hi);
      const Box4 boxA0 = mesh_carry4(&intoB, ca0.lo, ca0.hi);
      const Box4 boxA1 = mesh_carry4(&intoB, ca1.lo, ca1.hi);
      stack[top] = (uint2)(a0, b);
      top += mesh_overlaps4(ca0.lo, ca0.hi, &boxB) & mesh_overlaps4(nb.lo, nb.hi, &boxA0);
      stack[top] = (uint2)(a1, b);
      top += mesh_overlaps4(ca1.lo, ca1.hi, &boxB) & mesh_overlaps4(nb.lo, nb.hi, &boxA1);
      tests += 2u;
    } else if (na.count == 1u && nb.count == 1u) {
      GPUCOL_PREFETCH_CANDIDATE(p, na.first, nb.first);
      batch[batched++] = pairKey | ((ulong)na.first << bitsB) | (ulong)nb.first;
    } else {
      // Leaves of several triangles test their triangles' boxes, as mesh_front_expand does.
      for (uint j = 0u; j < nb.count; ++j) {
        float4 loB = nb.lo, hiB = nb.hi;
        uint triangleB = nb.first;
        if (nb.count != 1u) {
          __global const GpucolLeafEntry* eb = entriesB + nb.first + j;
          loB = (float4)(vload3(0, eb->min), 0.0f);
          hiB = (float4)(vload3(0, eb->max), 0.0f);
          triangleB = eb->triangle;
        }
        for (uint k = 0u; k < na.count; ++k) {
          float4 loA = na.lo, hiA = na.hi;
          uint triangleA = na.first;
          if (na.count != 1u) {
            __global const GpucolLeafEntry* ea = entriesA + na.first + k;
            loA = (float4)(vload3(0, ea->min), 0.0f);
            hiA = (float4)(vload3(0, ea->max), 0.0f);
            triangleA = ea->triangle;
          }
          ++tests;
          if (mesh_boxes_overlap4(&intoA, &intoB, loA, hiA, loB, hiB)) {
            GPUCOL_PREFETCH_CANDIDATE(p, triangleA, triangleB);
            batch[batched++] = pairKey | ((ulong)triangleA << bitsB) | (ulong)triangleB;
            if (batched == GPUCOL_DFS_BATCH) {
              mesh_flush_keys(pairs, counters, keys, capacity, batch, batched, bitsA, bitsB GPUCOL_NEAR_ARGS);
              batched = 0u;
            }
          }
        }
      }
    }
    if (batched == GPUCOL_DFS_BATCH) {
      mesh_flush_keys(pairs, counters, keys, capacity, batch, batched, bitsA, bitsB GPUCOL_NEAR_ARGS);
      batched = 0u;
    }
  }
  *batchedOut = batched;
  *testsOut = tests;
}

// Work-items take start paths from a shared counter (counters[5], zero before the launch) until none is left,
// rather than one path each: the paths' work differs widely (most die at once, a few hold most of the
// candidates), and on a CPU device, which runs a work-group's items one after the other on one thread, a
// fixed share left one thread idle while the other finished a heavy group. The host launches few work-items
// there and one per path on a GPU.
__kernel void mesh_traverse_depth_first(__global const GpucolMeshPair* restrict pairs,
                                        __global const GpucolTreeNode* restrict nodes,
                                        __global const GpucolLeafEntry* restrict entries,
                                        const uint pairCount, const uint startDepth,
                                        __global ulong* restrict keys, const uint capacity,
                                        __global uint* restrict counters, const uint bitsA,
                                        const uint bitsB GPUCOL_NEAR_PARAMS) {
  const uint paths = pairCount << (2u * startDepth);
  ulong batch[GPUCOL_DFS_BATCH];
  uint batched = 0u, tests = 0u;
  PairCarriers carriers;
  uint carried = 0xffffffffu;
  for (uint item = atomic_inc(&counters[5]); item < paths; item = atomic_inc(&counters[5])) {
    const uint pair = item >> (2u * startDepth);
    if (pair != carried) {
      carriers = mesh_pair_carriers(pairs + pair);
      carried = pair;
    }
    mesh_depth_first_path(pairs, nodes, entries, item, startDepth, keys, capacity, counters, bitsA, bitsB,
                          &carriers, batch, &batched, &tests GPUCOL_NEAR_ARGS);
    if (tests >= 0x80000000u) {  // long before the private count could wrap
      mesh_count_tests(counters, tests);
      tests = 0u;
    }
  }
  mesh_flush_keys(pairs, counters, keys, capacity, batch, batched, bitsA, bitsB GPUCOL_NEAR_ARGS);
  mesh_count_tests(counters, tests);
}

#endif  // GPUCOL_DFS_STACK
