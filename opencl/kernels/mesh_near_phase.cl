// Near phase of the mesh pipeline on the device (thesis §5.4.1): every candidate triangle pair of the whole
// batch in one kernel, Möller's test and the contact generation of §5.3.4, the intersecting pairs' records
// appended at an atomic counter.
//
// The double test and the contact are those of the CPU, from the same source: plugin/src/shared_math/
// triangle_test.h (one pair) and triangle_lanes.h (four pairs in double4 lanes), double arithmetic on the float
// input (cl_khr_fp64, which the host checks), no contraction, so the device decides every pair as the CPU does
// and its contacts carry the same bits. The triangles are built in A's scaled frame as
// plugin/src/mesh_pairs/cpu_mesh_pair.cpp builds them.
//
// The early-out (mesh_near_filter_test) comes first in the same kernel: the CPU's float plane and interval
// tests (plugin/src/shared_math/triangle_pretest.h, their error bounds proven there), straight-line code on
// vector lanes, several candidates per work-item, and the double test only on the survivors, four at a time in
// double4 lanes (gpucol_triangle_contact4). Without it (mesh_near_test) every candidate takes the double path,
// as the thesis's GPU kernel took every candidate through contact generation.
#include "opencl/shared/mesh_pipeline_types.h"
#include "plugin/src/shared_math/box_carry.h"
#include "plugin/src/shared_math/triangle_lanes.h"
#include "plugin/src/shared_math/triangle_pretest.h"

#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

// Helpers of the early-out are always inlined: a call left in the work-item loop stops a CPU device's
// vectorisation across work-items (PoCL's inliner judged them too costly).
#define GPUCOL_INLINE __attribute__((always_inline))

// Corner c of triangle `triangle` in the triangle soup arena (mesh_device_cache.h: 9 floats per triangle).
GPUCOL_INLINE void mesh_corner(__global const float* soup, uint triangle, int c, float* out) {
  __global const float* p = soup + 9u * triangle + 3 * c;
  out[0] = p[0];
  out[1] = p[1];
  out[2] = p[2];
}

// Triangles triangleA of A and triangleB of B of pair `p` (a private copy) in A's scaled frame, in float, as
// cpu_mesh_pair.cpp builds them. Its loops are unrolled: left as loops, PoCL vectorised them (two floats
// wide) inside each work-item, and the loop over the work-items, no longer innermost, stayed scalar.
GPUCOL_INLINE void mesh_pair_triangles(const GpucolMeshPair* p, __global const float* soup,
                                       const uint triangleA, const uint triangleB, float af[3][3],
                                       float bf[3][3]) {
#pragma unroll
  for (int c = 0; c < 3; ++c) {
    float v[3];
    mesh_corner(soup, p->trianglesA + triangleA, c, v);
#pragma unroll
    for (int k = 0; k < 3; ++k) af[c][k] = p->scaleA[k] * v[k];
    mesh_corner(soup, p->trianglesB + triangleB, c, v);
#pragma unroll
    for (int k = 0; k < 3; ++k) {
      bf[c][k] = gpucol_carry_point(p->bLinear[3 * k], p->bLinear[3 * k + 1], p->bLinear[3 * k + 2], v[0], v[1],
                                    v[2], p->bTranslation[k]);
    }
  }
  // Mirrored scalings swap vertices 1 and 2 (selects rather than branches: the early-out stays vector code).
  const bool flipA = p->flipA != 0u, flipB = p->flipB != 0u;
#pragma unroll
  for (int k = 0; k < 3; ++k) {
    const float a1 = af[1][k], a2 = af[2][k], b1 = bf[1][k], b2 = bf[2][k];
    af[1][k] = flipA ? a2 : a1;
    af[2][k] = flipA ? a1 : a2;
    bf[1][k] = flipB ? b2 : b1;
    bf[2][k] = flipB ? b1 : b2;
  }
}

// The triangles of candidate `key` of pair `p` (mesh_pair_triangles).
GPUCOL_INLINE void mesh_key_triangles(const GpucolMeshPair* p, __global const float* soup, const ulong key,
                                      const uint bitsA, const uint bitsB, float af[3][3], float bf[3][3]) {
  mesh_pair_triangles(p, soup, (uint)((key >> bitsB) & ((1ul << bitsA) - 1ul)),
                      (uint)(key & ((1ul << bitsB) - 1ul)), af, bf);
}

// The triangles of candidate `key`, its pair read from `pairs`.
GPUCOL_INLINE void mesh_candidate_triangles(__global const GpucolMeshPair* pairs, __global const float* soup,
                                            const ulong key, const uint bitsA, const uint bitsB,
                                            float af[3][3], float bf[3][3]) {
  const GpucolMeshPair p = pairs[(uint)(key >> (bitsA + bitsB))];
  mesh_key_triangles(&p, soup, key, bitsA, bitsB, af, bf);
}

// The early-out tests GPUCOL_LANES candidates per work-item, one in each lane of float vectors. PoCL does
// not vectorise it across work-items: it runs LLVM's SLP vectoriser inside one work-item first, and the
// two-wide code that leaves (of three-float values) makes the loop over work-items give up ("instruction
// return type cannot be vectorized"), so one work-item used to run one candidate in scalar code. Written in
// lanes, the vectors are there whatever the compiler does. Every lane runs the scalar code's operations in
// its order: OpenCL's vector fmax / fmin, comparisons and conversions are those of the scalars element by
// element (PoCL's fmax keeps the non-NaN operand in both), so each lane gives the scalar test's answer.
// GPUCOL_LANES (4, 8 or 16) is a build option of the host, which sizes the launch by it.
// The lanes' types and arithmetic are triangle_pretest.h's (gpucol_lanes, gpucol_mask: -1 true, 0 false).
#if GPUCOL_LANES == 4
#define GPUCOL_LOAD_LANES(p) vload4(0, p)
#define GPUCOL_STORE_LANES(v, i, p) vstore4(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint4(x)
#elif GPUCOL_LANES == 8
#define GPUCOL_LOAD_LANES(p) vload8(0, p)
#define GPUCOL_STORE_LANES(v, i, p) vstore8(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint8(x)
#elif GPUCOL_LANES == 16
#define GPUCOL_LOAD_LANES(p) vload16(0, p)
#define GPUCOL_STORE_LANES(v, i, p) vstore16(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint16(x)
#endif

// Lane `lane` of the corners (mesh_prefilter_lanes).
GPUCOL_INLINE void mesh_store_corners(const float af[3][3], const float bf[3][3], int lane,
                                      float corners[18][GPUCOL_LANES]) {
#pragma unroll
  for (int c = 0; c < 3; ++c) {
#pragma unroll
    for (int k = 0; k < 3; ++k) {
      corners[3 * c + k][lane] = af[c][k];
      corners[9 + 3 * c + k][lane] = bf[c][k];
    }
  }
}

// The early-out of GPUCOL_LANES candidates from `first` (lanes past n repeat the last candidate): -1 in the
// lanes whose triangles float arithmetic proves apart as the double test would find them
// (floatCertainlyApartBranchFree, then floatIntervalsApartBranchFree), else 0. The triangles stay in
// `corners`: corner c of A is rows 3c .. 3c + 2, of B rows 9 + 3c .., one lane per candidate.
GPUCOL_INLINE gpucol_mask mesh_prefilter_lanes(__global const GpucolMeshPair* restrict pairs,
                                             __global const float* restrict soup,
                                             __global const ulong* restrict keys, uint first, uint n,
                                             uint bitsA, uint bitsB, float corners[18][GPUCOL_LANES]) {
  // The lanes' candidates usually belong to one pair (the traversal appends each work-item's candidates 16 at
  // a time): then the pair's map is read once, not gathered lane by lane (PoCL vectorises the lane loop, and
  // gathering the pair's fields took most of its time). Both loops compute the same values.
  const uint pairShift = bitsA + bitsB;
  const uint firstPair = (uint)(keys[first] >> pairShift);
  bool onePair = true;
  for (int lane = 1; lane < GPUCOL_LANES; ++lane)
    onePair = onePair && (uint)(keys[min(first + (uint)lane, n - 1u)] >> pairShift) == firstPair;
  if (onePair) {
    const GpucolMeshPair p = pairs[firstPair];
    for (int lane = 0; lane < GPUCOL_LANES; ++lane) {
      float af[3][3], bf[3][3];
      mesh_key_triangles(&p, soup, keys[min(first + (uint)lane, n - 1u)], bitsA, bitsB, af, bf);
      mesh_store_corners(af, bf, lane, corners);
    }
  } else {
    for (int lane = 0; lane < GPUCOL_LANES; ++lane) {
      float af[3][3], bf[3][3];
      mesh_candidate_triangles(pairs, soup, keys[min(first + (uint)lane, n - 1u)], bitsA, bitsB, af, bf);
      mesh_store_corners(af, bf, lane, corners);
    }
  }
  GpucolLanes3 t[6];
#pragma unroll
  for (int c = 0; c < 6; ++c) {
    t[c] = gpucol_lanes3(GPUCOL_LOAD_LANES(corners[3 * c]), GPUCOL_LOAD_LANES(corners[3 * c + 1]),
              GPUCOL_LOAD_LANES(corners[3 * c + 2]));
  }
  return gpucol_float_certainly_apart(t[0], t[1], t[2], t[3], t[4], t[5]) |
         gpucol_float_intervals_apart(t[0], t[1], t[2], t[3], t[4], t[5]);
}

// The record of candidate `candidate`: GPUCOL_HIT_INTERSECTS in the flags when they intersect, and with
// `contact` its flags and `values` (point x y z, normal x y z, depth, deepest x y z; read only then).
GpucolNearHit mesh_hit_record(uint candidate, bool intersects, bool contact, bool onFaceOfB, bool sameFacing,
                              const float values[10]) {
  GpucolNearHit hit;
  hit.candidate = candidate;
  hit.flags = intersects ? GPUCOL_HIT_INTERSECTS : 0u;
  for (int k = 0; k < 3; ++k) hit.point[k] = hit.normal[k] = hit.deepest[k] = 0.0f;
  hit.depth = 0.0f;
  if (intersects && contact) {
    hit.flags |= GPUCOL_HIT_CONTACT | (onFaceOfB ? GPUCOL_HIT_ON_FACE_OF_B : 0u) |
                 (sameFacing ? GPUCOL_HIT_SAME_FACING : 0u);
    for (int k = 0; k < 3; ++k) {
      hit.point[k] = values[k];
      hit.normal[k] = values[3 + k];
      hit.deepest[k] = values[7 + k];
    }
    hit.depth = values[6];
  }
  return hit;
}

// The hit record of candidate `candidate` whose triangles are af, bf: GPUCOL_HIT_INTERSECTS in the flags when
// they intersect, and the contact (the double test of plugin/src/shared_math/triangle_test.h).
GpucolNearHit mesh_near_hit(const float af[3][3], const float bf[3][3], uint candidate) {
  double a[3][3], b[3][3];
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 3; ++k) {
      a[c][k] = (double)af[c][k];
      b[c][k] = (double)bf[c][k];
    }
  }
  const GpucolContact r = gpucol_triangle_contact(a, b);
  float values[10];
  if (r.intersects && r.contact) {
    for (int k = 0; k < 3; ++k) {
      values[k] = (float)r.point[k];
      values[3 + k] = (float)r.normalOnB[k];
      values[7 + k] = (float)r.deepest[k];
    }
    values[6] = (float)r.depth;
  }
  return mesh_hit_record(candidate, r.intersects, r.contact, r.onFaceOfB, r.sameFacing, values);
}

// Candidate j's hit record, intersecting or not (the near phase without the early-out).
__kernel void mesh_near_test(__global const GpucolMeshPair* pairs, __global const float* soup,
                             __global const ulong* keys, const uint n,
                             const uint bitsA, const uint bitsB, __global GpucolNearHit* hits) {
  const uint j = get_global_id(0);
  if (j >= n) return;
  float af[3][3], bf[3][3];
  mesh_candidate_triangles(pairs, soup, keys[j], bitsA, bitsB, af, bf);
  hits[j] = mesh_near_hit(af, bf, j);
}

// The early-out and the double test of candidates first .. first + GPUCOL_LANES - 1 of the n in `keys`:
// they are tested in lanes (mesh_prefilter_lanes), then the lanes that survive take the double test one
// after the other, and the records of the intersecting ones are appended at hits[counters[4]] (at most one
// per candidate: `hits` has room for every candidate of `keys`, so nothing is dropped).
void mesh_test_lanes(__global const GpucolMeshPair* restrict pairs, __global const float* restrict soup,
                     __global const ulong* restrict keys, const uint first, const uint n, const uint bitsA,
                     const uint bitsB, __global GpucolNearHit* restrict hits, __global uint* restrict counters) {
  float corners[18][GPUCOL_LANES];
  const gpucol_mask apart =
      mesh_prefilter_lanes(pairs, soup, keys, first, n, bitsA, bitsB, corners);
  uint survives[GPUCOL_LANES];
  GPUCOL_STORE_LANES(GPUCOL_UINT_LANES(apart + 1), 0, survives);
  const uint lanes = min((uint)GPUCOL_LANES, n - first);
  uint survivor[GPUCOL_LANES];
  uint survivors = 0u;
  for (uint lane = 0u; lane < lanes; ++lane) {
    survivor[survivors] = lane;
    survivors += survives[lane] != 0u ? 1u : 0u;
  }
  // The survivors four at a time through gpucol_triangle_contact4 (the free lanes of the last four repeat its last
  // survivor).
  for (uint group = 0u; group < survivors; group += 4u) {
    uint lane4[4];
    for (uint j = 0u; j < 4u; ++j) lane4[j] = survivor[min(group + j, survivors - 1u)];
    GpucolVec4 t[6];
    for (int c = 0; c < 6; ++c) {
      double4 xyz[3];
      for (int k = 0; k < 3; ++k) {
        const int row = 3 * c + k;
        xyz[k] = (double4)((double)corners[row][lane4[0]], (double)corners[row][lane4[1]],
                           (double)corners[row][lane4[2]], (double)corners[row][lane4[3]]);
      }
      t[c] = gpucol_vec4(xyz[0], xyz[1], xyz[2]);
    }
    const GpucolContact4 r = gpucol_triangle_contact4(t);
    // Lane by lane from here: the masks and values as arrays.
    long onePair[4], intersects[4], contact[4], onFaceOfB[4], sameFacing[4];
    vstore4(r.onePair, 0, onePair);
    vstore4(r.intersects, 0, intersects);
    vstore4(r.contact, 0, contact);
    vstore4(r.onFaceOfB, 0, onFaceOfB);
    vstore4(r.sameFacing, 0, sameFacing);
    float values[10][4];
    const double4 rows[10] = {r.point.x,  r.point.y, r.point.z,   r.normal.x,  r.normal.y,
                              r.normal.z, r.depth,   r.deepest.x, r.deepest.y, r.deepest.z};
    for (int k = 0; k < 10; ++k) vstore4(convert_float4(rows[k]), 0, values[k]);
    const uint inGroup = min(4u, survivors - group);
    for (uint j = 0u; j < inGroup; ++j) {
      const uint lane = lane4[j];
      GpucolNearHit hit;
      if (onePair[j] != 0) {
        float af[3][3], bf[3][3];
        for (int c = 0; c < 3; ++c) {
          for (int k = 0; k < 3; ++k) {
            af[c][k] = corners[3 * c + k][lane];
            bf[c][k] = corners[9 + 3 * c + k][lane];
          }
        }
        hit = mesh_near_hit(af, bf, first + lane);
      } else {
        if (intersects[j] == 0) continue;
        float laneValues[10];
        for (int k = 0; k < 10; ++k) laneValues[k] = values[k][j];
        hit = mesh_hit_record(first + lane, true, contact[j] != 0, onFaceOfB[j] != 0, sameFacing[j] != 0,
                              laneValues);
      }
      if (hit.flags & GPUCOL_HIT_INTERSECTS) hits[atomic_inc(&counters[4])] = hit;
    }
  }
}

// The early-out and the double test in one pass, work-item w on candidates GPUCOL_LANES w .. (mesh_test_lanes).
// The hits' order varies between runs; the host puts them in candidate order. One launch and one wait: a
// separate early-out kernel, a scan and gather of its survivors and a test kernel on them took longer on
// PoCL. (On a CPU device the default path runs mesh_test_lanes inside the traversal instead:
// mesh_middle_phase.cl, GPUCOL_FUSED_NEAR.)
__kernel void mesh_near_filter_test(__global const GpucolMeshPair* restrict pairs,
                                    __global const float* restrict soup,
                                    __global const ulong* restrict keys, const uint capacity,
                                    const uint bitsA, const uint bitsB, __global GpucolNearHit* restrict hits,
                                    __global uint* restrict counters) {
  // counters[0] holds the candidate count (written by the traversal just before, or by the host), of which
  // `keys` holds at most `capacity`; hits are appended at counters[4] (mesh_pipeline.cpp's kCounterWords).
  const uint n = min(counters[0], capacity);
  const uint first = (uint)get_global_id(0) * GPUCOL_LANES;
  if (first >= n) return;
  mesh_test_lanes(pairs, soup, keys, first, n, bitsA, bitsB, hits, counters);
}

// The GPU's shape of mesh_near_filter_test: one candidate per work-item, the double test of mesh_near_hit
// straight away (scalar code: a GPU has no vector lanes for the float early-out to fill, and the double test's
// first plane test rejects as early), the intersecting records of a work-group appended with one atomic on
// counters[4] (each takes a slot of the group's count in local memory). Launched over `capacity` items in
// whole groups; work-items past the count read from counters[0] write nothing.
__kernel void mesh_near_each(__global const GpucolMeshPair* restrict pairs, __global const float* restrict soup,
                             __global const ulong* restrict keys, const uint capacity, const uint bitsA,
                             const uint bitsB, __global GpucolNearHit* restrict hits,
                             __global uint* restrict counters) {
  __local uint groupCount, groupBase;
  const uint n = min(counters[0], capacity);
  // Uniform over the group: a group wholly past the count leaves before any barrier.
  if (get_group_id(0) * get_local_size(0) >= n) return;
  if (get_local_id(0) == 0) groupCount = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint j = get_global_id(0);
  GpucolNearHit hit;
  uint slot = 0xffffffffu;
  if (j < n) {
    float af[3][3], bf[3][3];
    mesh_candidate_triangles(pairs, soup, keys[j], bitsA, bitsB, af, bf);
    hit = mesh_near_hit(af, bf, j);
    if (hit.flags & GPUCOL_HIT_INTERSECTS) slot = atomic_inc(&groupCount);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) == 0 && groupCount > 0u) groupBase = atomic_add(&counters[4], groupCount);
  barrier(CLK_LOCAL_MEM_FENCE);
  if (slot != 0xffffffffu) hits[groupBase + slot] = hit;
}
