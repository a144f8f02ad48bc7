/* gpucol_triangle_contact (triangle_test.h) on four pairs at once, one per lane of a vector of four doubles:
   the CPU's generateContactRows (plugin/src/narrowphase/contact_rows.cpp; GCC/Clang vector extensions, one
   AVX instruction per step) and the device's mesh_near_lanes4 (opencl/kernels/mesh_near_phase.cl; double4)
   run this function. Each lane sees the one-pair function's IEEE operations in its order (division and sqrt
   are correctly rounded, a pick only moves bits), so the same results; choices are made by lane masks (all
   bits set where true), never by branches. Coplanar pairs and pairs with a non-finite coordinate are only
   flagged (onePair) and left to the one-pair function, whose early returns decide them. */
#ifndef GPUCOL_SHARED_MATH_TRIANGLE_LANES_H
#define GPUCOL_SHARED_MATH_TRIANGLE_LANES_H

#include "plugin/src/shared_math/triangle_test.h"

#ifdef __OPENCL_VERSION__
typedef double4 gpucol_d4;
typedef long4 gpucol_m4;
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_splat(double v) {
  return (double4)(v);
}
/* c ? a : b lane by lane. */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_pick(gpucol_m4 c, gpucol_d4 a, gpucol_d4 b) {
  return select(b, a, c);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_abs(gpucol_d4 v) {
  return fabs(v);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_sqrt(gpucol_d4 v) {
  return sqrt(v);
}
#else
#include <stdint.h>
typedef double gpucol_d4 __attribute__((vector_size(32)));
typedef int64_t gpucol_m4 __attribute__((vector_size(32)));
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_splat(double v) {
  const gpucol_d4 r = {v, v, v, v};
  return r;
}
/* c ? a : b lane by lane, by bits (so no arithmetic can change a value). */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_pick(gpucol_m4 c, gpucol_d4 a, gpucol_d4 b) {
  return (gpucol_d4)((c & (gpucol_m4)a) | (~c & (gpucol_m4)b));
}
/* fabs: the sign bit cleared. */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_abs(gpucol_d4 v) {
  const gpucol_m4 noSign = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
  return (gpucol_d4)((gpucol_m4)v & noSign);
}
/* sqrt of each lane (correctly rounded, so the same bits whichever instruction the compiler picks). */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_sqrt(gpucol_d4 v) {
  const gpucol_d4 r = {sqrt(v[0]), sqrt(v[1]), sqrt(v[2]), sqrt(v[3])};
  return r;
}
#endif

/* gpucol_min_d and gpucol_max_d lane by lane (the first where the comparison fails). */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_min(gpucol_d4 a, gpucol_d4 b) {
  return gpucol_d4_pick(b < a, b, a);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_d4_max(gpucol_d4 a, gpucol_d4 b) {
  return gpucol_d4_pick(a < b, b, a);
}

/* A point or vector per lane. */
GPUCOL_LANE_VECTOR(GpucolVec4, gpucol_vec4, gpucol_d4)
GPUCOL_SHARED_FORCE_INLINE GpucolVec4 gpucol_vec4_divide(GpucolVec4 v, gpucol_d4 s) {
  return gpucol_vec4(v.x / s, v.y / s, v.z / s);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_vec4_max_abs(GpucolVec4 v) {
  return gpucol_d4_max(gpucol_d4_max(gpucol_d4_abs(v.x), gpucol_d4_abs(v.y)), gpucol_d4_abs(v.z));
}
GPUCOL_SHARED_FORCE_INLINE GpucolVec4 gpucol_vec4_pick(gpucol_m4 c, GpucolVec4 a, GpucolVec4 b) {
  return gpucol_vec4(gpucol_d4_pick(c, a.x, b.x), gpucol_d4_pick(c, a.y, b.y), gpucol_d4_pick(c, a.z, b.z));
}
/* gpucol_same_strict_sign lane by lane. */
GPUCOL_SHARED_FORCE_INLINE gpucol_m4 gpucol_d4_same_sign(gpucol_d4 x, gpucol_d4 y) {
  const gpucol_d4 zero = gpucol_d4_splat(0.0);
  return ((x > zero) & (y > zero)) | ((x < zero) & (y < zero));
}
/* v's coordinate on the axis picked by onX / onY (else z). */
GPUCOL_SHARED_FORCE_INLINE gpucol_d4 gpucol_vec4_axis(GpucolVec4 v, gpucol_m4 onX, gpucol_m4 onY) {
  return gpucol_d4_pick(onX, v.x, gpucol_d4_pick(onY, v.y, v.z));
}

/* gpucol_make_plane and gpucol_signed_distances: the unnormalised normal of (p0, p1, p2), whether it is
   degenerate, and the snapped distances of q0, q1, q2 to its plane. */
GPUCOL_SHARED_FORCE_INLINE void gpucol_vec4_plane_distances(GpucolVec4 p0, GpucolVec4 p1, GpucolVec4 p2,
                                                            GpucolVec4 q0, GpucolVec4 q1, GpucolVec4 q2,
                                                            GpucolVec4* normal, gpucol_m4* degenerate,
                                                            gpucol_d4 d[3]) {
  const GpucolVec4 e1 = gpucol_vec4_sub(p1, p0), e2 = gpucol_vec4_sub(p2, p0);
  *normal = gpucol_vec4_cross(e1, e2);
  const gpucol_d4 errorScale = gpucol_vec4_max_abs(e1) * gpucol_vec4_max_abs(e2);
  *degenerate = ~(gpucol_vec4_dot(*normal, *normal) > gpucol_d4_splat(GPUCOL_DEGENERATE_SIN2) *
                                                          gpucol_vec4_dot(e1, e1) * gpucol_vec4_dot(e2, e2));
  const GpucolVec4 r0 = gpucol_vec4_sub(q0, p0), r1 = gpucol_vec4_sub(q1, p0), r2 = gpucol_vec4_sub(q2, p0);
  d[0] = gpucol_vec4_dot(*normal, r0);
  d[1] = gpucol_vec4_dot(*normal, r1);
  d[2] = gpucol_vec4_dot(*normal, r2);
  const gpucol_d4 extent =
      gpucol_d4_max(gpucol_d4_max(gpucol_vec4_max_abs(r0), gpucol_vec4_max_abs(r1)), gpucol_vec4_max_abs(r2));
  const gpucol_d4 tolerance = gpucol_d4_splat(GPUCOL_SNAP_RELATIVE) * errorScale * extent;
  for (int i = 0; i < 3; ++i)
    d[i] = gpucol_d4_pick(gpucol_d4_abs(d[i]) <= tolerance, gpucol_d4_splat(0.0), d[i]);
}

/* gpucol_plane_crossing: the segment where (v0, v1, v2) meets the other plane, the lone vertex as
   gpucol_lone_vertex picks it. */
GPUCOL_SHARED_FORCE_INLINE void gpucol_vec4_plane_crossing(GpucolVec4 v0, GpucolVec4 v1, GpucolVec4 v2,
                                                           const gpucol_d4 d[3], GpucolVec4* s0,
                                                           GpucolVec4* s1) {
  const gpucol_d4 zeroes = gpucol_d4_splat(0.0);
  const gpucol_m4 s01 = gpucol_d4_same_sign(d[0], d[1]), s02 = gpucol_d4_same_sign(d[0], d[2]);
  const gpucol_m4 firstAlone = gpucol_d4_same_sign(d[1], d[2]) | (d[0] != zeroes);
  const gpucol_m4 zero = ~s01 & ~s02 & firstAlone;
  const gpucol_m4 one = ~s01 & (s02 | (~firstAlone & (d[1] != zeroes)));
  /* The lone vertex a and the next two in cyclic order, b and c. */
  const GpucolVec4 va = gpucol_vec4_pick(zero, v0, gpucol_vec4_pick(one, v1, v2));
  const GpucolVec4 vb = gpucol_vec4_pick(zero, v1, gpucol_vec4_pick(one, v2, v0));
  const GpucolVec4 vc = gpucol_vec4_pick(zero, v2, gpucol_vec4_pick(one, v0, v1));
  const gpucol_d4 da = gpucol_d4_pick(zero, d[0], gpucol_d4_pick(one, d[1], d[2]));
  const gpucol_d4 db = gpucol_d4_pick(zero, d[1], gpucol_d4_pick(one, d[2], d[0]));
  const gpucol_d4 dc = gpucol_d4_pick(zero, d[2], gpucol_d4_pick(one, d[0], d[1]));
  const gpucol_d4 t0 = da / (da - db), t1 = da / (da - dc);
  const GpucolVec4 ab = gpucol_vec4_sub(vb, va), ac = gpucol_vec4_sub(vc, va);
  *s0 = gpucol_vec4(va.x + ab.x * t0, va.y + ab.y * t0, va.z + ab.z * t0);
  *s1 = gpucol_vec4(va.x + ac.x * t1, va.y + ac.y * t1, va.z + ac.z * t1);
}

/* What gpucol_triangle_contact4 found for its four pairs: lane masks, and the contact where `contact` holds.
 */
typedef struct GpucolContact4 {
  gpucol_m4 onePair; /* coplanar or non-finite: the one-pair function decides */
  gpucol_m4 intersects;
  gpucol_m4 contact; /* intersecting with a kept contact */
  gpucol_m4 onFaceOfB;
  gpucol_m4 sameFacing;
  GpucolVec4 point, normal, deepest;
  gpucol_d4 depth;
} GpucolContact4;

/* The four pairs whose corners are t[0..5] (A's vertices, then B's). */
GPUCOL_SHARED_FORCE_INLINE GpucolContact4 gpucol_triangle_contact4(const GpucolVec4 t[6]) {
  const GpucolVec4 a0 = t[0], a1 = t[1], a2 = t[2], b0 = t[3], b1 = t[4], b2 = t[5];
  const gpucol_d4 zero = gpucol_d4_splat(0.0);

  /* Möller's early rejections: a degenerate triangle, or one wholly on one side of the other's plane. */
  GpucolVec4 normalA, normalB;
  gpucol_m4 degenerateA, degenerateB;
  gpucol_d4 dB[3], dA[3];
  gpucol_vec4_plane_distances(a0, a1, a2, b0, b1, b2, &normalA, &degenerateA, dB);
  gpucol_vec4_plane_distances(b0, b1, b2, a0, a1, a2, &normalB, &degenerateB, dA);
  const gpucol_m4 rejected =
      degenerateA | (gpucol_d4_same_sign(dB[0], dB[1]) & gpucol_d4_same_sign(dB[0], dB[2])) | degenerateB |
      (gpucol_d4_same_sign(dA[0], dA[1]) & gpucol_d4_same_sign(dA[0], dA[2]));
  const gpucol_m4 coplanar = ((dB[0] == zero) & (dB[1] == zero) & (dB[2] == zero)) |
                             ((dA[0] == zero) & (dA[1] == zero) & (dA[2] == zero));
  /* x - x is 0 for a finite x, NaN otherwise. */
  gpucol_d4 sum = zero;
  for (int c = 0; c < 6; ++c) {
    const GpucolVec4 z = gpucol_vec4_sub(t[c], t[c]);
    sum += (z.x + z.y) + z.z;
  }
  const gpucol_m4 finite = sum == zero;

  const gpucol_d4 lengthA = gpucol_d4_sqrt(gpucol_vec4_dot(normalA, normalA));
  const gpucol_d4 lengthB = gpucol_d4_sqrt(gpucol_vec4_dot(normalB, normalB));
  const GpucolVec4 nA = gpucol_vec4_divide(normalA, lengthA);
  const GpucolVec4 nB = gpucol_vec4_divide(normalB, lengthB);

  /* Möller's interval test on the intersection line, on its dominant axis, with the crossings in 3-D. */
  const GpucolVec4 line = gpucol_vec4_cross(normalA, normalB);
  const gpucol_d4 fx = gpucol_d4_abs(line.x), fy = gpucol_d4_abs(line.y), fz = gpucol_d4_abs(line.z);
  const gpucol_m4 onX = (fx >= fy) & (fx >= fz), onY = ~(fx >= fy) & (fy >= fz);
  GpucolVec4 sA0, sA1, sB0, sB1;
  gpucol_vec4_plane_crossing(a0, a1, a2, dA, &sA0, &sA1);
  gpucol_vec4_plane_crossing(b0, b1, b2, dB, &sB0, &sB1);
  const gpucol_m4 swapA = gpucol_vec4_axis(sA1, onX, onY) < gpucol_vec4_axis(sA0, onX, onY);
  const gpucol_m4 swapB = gpucol_vec4_axis(sB1, onX, onY) < gpucol_vec4_axis(sB0, onX, onY);
  const GpucolVec4 lowA = gpucol_vec4_pick(swapA, sA1, sA0), highA = gpucol_vec4_pick(swapA, sA0, sA1);
  const GpucolVec4 lowB = gpucol_vec4_pick(swapB, sB1, sB0), highB = gpucol_vec4_pick(swapB, sB0, sB1);
  const gpucol_d4 lowAOn = gpucol_vec4_axis(lowA, onX, onY), highAOn = gpucol_vec4_axis(highA, onX, onY);
  const gpucol_d4 lowBOn = gpucol_vec4_axis(lowB, onX, onY), highBOn = gpucol_vec4_axis(highB, onX, onY);
  const gpucol_m4 separated = (lowAOn > highBOn) | (lowBOn > highAOn);

  /* §5.3.4: the smaller move of a triangle along the other's normal out of its plane. */
  const gpucol_d4 moveA = gpucol_d4_max(zero, -gpucol_d4_min(gpucol_d4_min(dA[0], dA[1]), dA[2]) / lengthB);
  const gpucol_d4 moveB = gpucol_d4_max(zero, -gpucol_d4_min(gpucol_d4_min(dB[0], dB[1]), dB[2]) / lengthA);
  const gpucol_m4 aMoves = moveA <= moveB;
  const gpucol_d4 move = gpucol_d4_pick(aMoves, moveA, moveB);

  /* §5.3.4: dropped when sliding apart along the line is shorter than the depth (the unit direction, or the
     direction itself when its squared length is not positive). */
  const gpucol_d4 lineSquared = gpucol_vec4_dot(line, line);
  const GpucolVec4 u =
      gpucol_vec4_pick(lineSquared > zero, gpucol_vec4_divide(line, gpucol_d4_sqrt(lineSquared)), line);
  const gpucol_d4 pA1 = gpucol_vec4_dot(u, gpucol_vec4_sub(a1, a0)),
                  pA2 = gpucol_vec4_dot(u, gpucol_vec4_sub(a2, a0));
  const gpucol_d4 pB0 = gpucol_vec4_dot(u, gpucol_vec4_sub(b0, a0)),
                  pB1 = gpucol_vec4_dot(u, gpucol_vec4_sub(b1, a0)),
                  pB2 = gpucol_vec4_dot(u, gpucol_vec4_sub(b2, a0));
  const gpucol_d4 slide = gpucol_d4_min(
      gpucol_d4_max(gpucol_d4_max(zero, pA1), pA2) - gpucol_d4_min(gpucol_d4_min(pB0, pB1), pB2),
      gpucol_d4_max(gpucol_d4_max(pB0, pB1), pB2) - gpucol_d4_min(gpucol_d4_min(zero, pA1), pA2));

  /* The contact: the middle of the common segment, the winning normal, the moving triangle's deepest vertex.
   */
  GpucolContact4 r;
  const GpucolVec4 low = gpucol_vec4_pick(lowAOn >= lowBOn, lowA, lowB);
  const GpucolVec4 high = gpucol_vec4_pick(highAOn <= highBOn, highA, highB);
  const gpucol_d4 oneHalf = gpucol_d4_splat(0.5);
  r.point = gpucol_vec4(oneHalf * (low.x + high.x), oneHalf * (low.y + high.y), oneHalf * (low.z + high.z));
  r.normal = gpucol_vec4_pick(aMoves, nB, gpucol_vec4(-nA.x, -nA.y, -nA.z));
  const gpucol_d4 d0 = gpucol_d4_pick(aMoves, dA[0], dB[0]), d1 = gpucol_d4_pick(aMoves, dA[1], dB[1]),
                  d2 = gpucol_d4_pick(aMoves, dA[2], dB[2]);
  const gpucol_m4 deepest0 = (d0 <= d1) & (d0 <= d2), deepest1 = ~(d0 <= d1) & (d1 <= d2);
  r.deepest = gpucol_vec4_pick(aMoves, gpucol_vec4_pick(deepest0, a0, gpucol_vec4_pick(deepest1, a1, a2)),
                               gpucol_vec4_pick(deepest0, b0, gpucol_vec4_pick(deepest1, b1, b2)));
  r.depth = zero - move;
  r.onePair = ~finite | (~rejected & coplanar);
  r.intersects = ~r.onePair & ~rejected & ~separated;
  r.contact = r.intersects & ~(slide < move);
  r.onFaceOfB = aMoves;
  r.sameFacing = gpucol_vec4_dot(nA, nB) > zero;
  return r;
}

#endif /* GPUCOL_SHARED_MATH_TRIANGLE_LANES_H */
