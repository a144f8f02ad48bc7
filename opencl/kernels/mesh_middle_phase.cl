// Middle phase of the mesh pipeline on the device (thesis §5.4.2): tree against tree, breadth-first, one
// level per launch, segmented over every mesh pair of the batch (each front entry carries its pair, thesis
// §7.3). Each level runs twice: a counting pass writes, per front entry, how many child node pairs overlap,
// how many candidate triangle pairs it emits and how many box tests it made; the host scans the counts
// (scan.cl, Fig. 5.8) and sizes the next front and the candidate list from the totals; the writing pass
// repeats the tests and writes at the scanned offsets. So nothing has a fixed capacity.
//
// The box tests are those of plugin/src/bvh/tree_traversal.cpp (BoxCarrier::carry and overlaps) with the
// same operations in the same order and no contraction, so the device finds exactly the CPU's candidates.
#include "opencl/shared/mesh_pipeline_types.h"

#pragma OPENCL FP_CONTRACT OFF

typedef struct CarriedBox {
  float min[3];
  float max[3];
} CarriedBox;

// centre' = M c + t, extent' = |M| e + inflation, summed in the CPU's order (((x0 + x1) + x2) + t).
CarriedBox mesh_carry(__global const GpucolMeshPair* p, __global const float* lo, __global const float* hi) {
  float c[3], e[3];
  for (int j = 0; j < 3; ++j) {
    c[j] = (lo[j] + hi[j]) * 0.5f;
    e[j] = (hi[j] - lo[j]) * 0.5f;
  }
  CarriedBox out;
  for (int i = 0; i < 3; ++i) {
    const float ci = ((p->linear[3 * i] * c[0] + p->linear[3 * i + 1] * c[1]) + p->linear[3 * i + 2] * c[2]) +
                     p->translation[i];
    const float ei =
        ((p->absLinear[3 * i] * e[0] + p->absLinear[3 * i + 1] * e[1]) + p->absLinear[3 * i + 2] * e[2]) +
        p->inflation[i];
    out.min[i] = ci - ei;
    out.max[i] = ci + ei;
  }
  return out;
}

// Touching counts as overlapping (tree_traversal.cpp's overlaps()).
bool mesh_overlaps(__global const float* lo, __global const float* hi, const CarriedBox* b) {
  return (lo[0] <= b->max[0]) & (b->min[0] <= hi[0]) & (lo[1] <= b->max[1]) & (b->min[1] <= hi[1]) &
         (lo[2] <= b->max[2]) & (b->min[2] <= hi[2]);
}

bool mesh_nodes_overlap(__global const GpucolMeshPair* p, __global const GpucolTreeNode* nodes, uint a,
                        uint b) {
  __global const GpucolTreeNode* na = nodes + p->nodesA + a;
  __global const GpucolTreeNode* nb = nodes + p->nodesB + b;
  const CarriedBox box = mesh_carry(p, nb->min, nb->max);
  return mesh_overlaps(na->min, na->max, &box);
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
      const CarriedBox box = mesh_carry(p, cb->min, cb->max);
      for (int m = 0; m < 2; ++m) {
        __global const GpucolTreeNode* ca = nodes + p->nodesA + childrenA[m];
        if (mesh_overlaps(ca->min, ca->max, &box)) {
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
      const CarriedBox box = mesh_carry(p, cb->min, cb->max);
      if (mesh_overlaps(na->min, na->max, &box)) {
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
    const CarriedBox box = mesh_carry(p, nb->min, nb->max);
    for (int m = 0; m < 2; ++m) {
      __global const GpucolTreeNode* ca = nodes + p->nodesA + childrenA[m];
      if (mesh_overlaps(ca->min, ca->max, &box)) {
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
      CarriedBox triB;
      uint triangleB = nb->first;
      if (nb->count == 1u) {
        triB = mesh_carry(p, nb->min, nb->max);
      } else {
        __global const GpucolLeafEntry* eb = entries + p->entriesB + nb->first + j;
        triB = mesh_carry(p, eb->min, eb->max);
        triangleB = eb->triangle;
      }
      if (na->count == 1u) {
        ++tests;
        if (mesh_overlaps(na->min, na->max, &triB)) {
          if (write)
            keys[keyAt + candidates] = mesh_candidate_key(entry.pair, na->first, triangleB, bitsA, bitsB);
          ++candidates;
        }
        continue;
      }
      for (uint k = 0u; k < na->count; ++k) {
        __global const GpucolLeafEntry* ea = entries + p->entriesA + na->first + k;
        ++tests;
        if (mesh_overlaps(ea->min, ea->max, &triB)) {
          if (write)
            keys[keyAt + candidates] = mesh_candidate_key(entry.pair, ea->triangle, triangleB, bitsA, bitsB);
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
// Work-item = (pair, path) as in mesh_front_start: it walks its path `startDepth` levels down (the
// breadth-first front, with the same rules so that every front entry comes from exactly one path), then
// descends from its entry depth-first with a private stack, as a CPU thread would (tree_traversal.cpp,
// Alg. 5.1). Candidates are appended at an atomic counter: keys[n] for n < capacity; the host reads the
// counter and, when it went past the capacity, grows the buffer and runs the pass again, so nothing is ever
// dropped. The order of the appended keys varies between runs; the radix sort that follows gives the
// deterministic order.
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

void mesh_count_tests(__global uint* counters, uint tests) {
  if (tests == 0u) return;
  const uint old = atomic_add(&counters[2], tests);
  if (old + tests < old) atomic_inc(&counters[3]);
}

void mesh_append_key(__global uint* counters, __global ulong* keys, uint capacity, ulong key) {
  const uint at = atomic_inc(&counters[0]);
  if (at == 0xffffffffu) counters[1] = 1u;
  if (at < capacity) keys[at] = key;
}

__kernel void mesh_traverse_depth_first(__global const GpucolMeshPair* pairs,
                                        __global const GpucolTreeNode* nodes,
                                        __global const GpucolLeafEntry* entries, const uint pairCount,
                                        const uint startDepth, __global ulong* keys, const uint capacity,
                                        __global uint* counters, const uint bitsA, const uint bitsB) {
  const uint item = get_global_id(0);
  const uint pathsPerPair = 1u << (2u * startDepth);
  if (item >= pairCount * pathsPerPair) return;
  const uint pair = item >> (2u * startDepth);
  const uint path = item & (pathsPerPair - 1u);
  __global const GpucolMeshPair* p = pairs + pair;
  __global const GpucolTreeNode* treeA = nodes + p->nodesA;
  __global const GpucolTreeNode* treeB = nodes + p->nodesB;
  uint tests = 0u;

  // The path down to the start front. The root test repeats the host's (which sends only overlapping pairs),
  // so that this kernel alone decides, as mesh_front_start does.
  uint a = 0u, b = 0u;
  bool found = mesh_nodes_overlap(p, nodes, a, b);
  for (uint level = 0u; found && level < startDepth; ++level) {
    const uint rest = path >> (2u * level);
    __global const GpucolTreeNode* na = treeA + a;
    __global const GpucolTreeNode* nb = treeB + b;
    const bool leafA = na->count != 0u;
    const bool leafB = nb->count != 0u;
    if (leafA && leafB) {
      found = rest == 0u;
      break;
    }
    if (rest == 0u) tests += (leafA || leafB) ? 2u : 4u;
    const uint bitA = rest & 1u;
    const uint bitB = (rest >> 1) & 1u;
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
  if (!found) {
    mesh_count_tests(counters, tests);
    return;
  }

  uint2 stack[GPUCOL_DFS_STACK];
  uint top = 0u;
  stack[top++] = (uint2)(a, b);
  while (top > 0u) {
    const uint2 top2 = stack[--top];
    a = top2.x;
    b = top2.y;
    __global const GpucolTreeNode* na = treeA + a;
    __global const GpucolTreeNode* nb = treeB + b;
    const bool leafA = na->count != 0u;
    const bool leafB = nb->count != 0u;
    if (!leafA && !leafB) {
      const uint childrenA[2] = {a + 1u, na->first};
      const uint childrenB[2] = {b + 1u, nb->first};
      for (int k = 0; k < 2; ++k) {
        __global const GpucolTreeNode* cb = treeB + childrenB[k];
        const CarriedBox box = mesh_carry(p, cb->min, cb->max);
        for (int m = 0; m < 2; ++m) {
          __global const GpucolTreeNode* ca = treeA + childrenA[m];
          if (mesh_overlaps(ca->min, ca->max, &box)) stack[top++] = (uint2)(childrenA[m], childrenB[k]);
        }
      }
      tests += 4u;
    } else if (leafA && !leafB) {
      const uint childrenB[2] = {b + 1u, nb->first};
      for (int k = 0; k < 2; ++k) {
        __global const GpucolTreeNode* cb = treeB + childrenB[k];
        const CarriedBox box = mesh_carry(p, cb->min, cb->max);
        if (mesh_overlaps(na->min, na->max, &box)) stack[top++] = (uint2)(a, childrenB[k]);
      }
      tests += 2u;
    } else if (!leafA && leafB) {
      const uint childrenA[2] = {a + 1u, na->first};
      const CarriedBox box = mesh_carry(p, nb->min, nb->max);
      for (int m = 0; m < 2; ++m) {
        __global const GpucolTreeNode* ca = treeA + childrenA[m];
        if (mesh_overlaps(ca->min, ca->max, &box)) stack[top++] = (uint2)(childrenA[m], b);
      }
      tests += 2u;
    } else if (na->count == 1u && nb->count == 1u) {
      mesh_append_key(counters, keys, capacity, mesh_candidate_key(pair, na->first, nb->first, bitsA, bitsB));
    } else {
      // Leaves of several triangles test their triangles' boxes, as mesh_front_expand does.
      for (uint j = 0u; j < nb->count; ++j) {
        CarriedBox triB;
        uint triangleB = nb->first;
        if (nb->count == 1u) {
          triB = mesh_carry(p, nb->min, nb->max);
        } else {
          __global const GpucolLeafEntry* eb = entries + p->entriesB + nb->first + j;
          triB = mesh_carry(p, eb->min, eb->max);
          triangleB = eb->triangle;
        }
        if (na->count == 1u) {
          ++tests;
          if (mesh_overlaps(na->min, na->max, &triB))
            mesh_append_key(counters, keys, capacity,
                            mesh_candidate_key(pair, na->first, triangleB, bitsA, bitsB));
          continue;
        }
        for (uint k = 0u; k < na->count; ++k) {
          __global const GpucolLeafEntry* ea = entries + p->entriesA + na->first + k;
          ++tests;
          if (mesh_overlaps(ea->min, ea->max, &triB))
            mesh_append_key(counters, keys, capacity,
                            mesh_candidate_key(pair, ea->triangle, triangleB, bitsA, bitsB));
        }
      }
    }
  }
  mesh_count_tests(counters, tests);
}

#endif  // GPUCOL_DFS_STACK
