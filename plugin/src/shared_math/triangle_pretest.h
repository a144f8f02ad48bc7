/* The float pre-tests of the near phase (Möller's plane rejections and interval step, proven to answer as
   the double test of triangle_test.h does, or to abstain): the CPU's floatCertainlyApartBranchFree and
   floatIntervalsApartBranchFree (plugin/src/narrowphase/triangle_plane.h, over rows of candidates that the
   compiler turns into vector code) and the device's early-out (opencl/kernels/mesh_near_phase.cl, several
   candidates per work-item in float vector lanes) run these functions. Branch-free: the outcome is close to a
   coin toss per pair.

   A value of gpucol_lanes is one candidate on the CPU (float; a mask is 0 or 1) and GPUCOL_LANES candidates
   on the device (floatN; a mask is 0 or -1, as vector comparisons give). Each lane runs the scalar operations
   in their order; fmax on the device, std::max's choice on the CPU, differ only for NaN input, for which the
   double test answers "apart" anyway (a NaN or infinite coordinate makes a plane degenerate). */
#ifndef GPUCOL_SHARED_MATH_TRIANGLE_PRETEST_H
#define GPUCOL_SHARED_MATH_TRIANGLE_PRETEST_H

#include "plugin/src/shared_math/shared_c.h"

#ifdef __OPENCL_VERSION__
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#if GPUCOL_LANES == 4
typedef float4 gpucol_lanes;
typedef int4 gpucol_mask;
#define GPUCOL_LANES_RECIPROCAL(x) convert_float4(1.0 / convert_double4(x))
#elif GPUCOL_LANES == 8
typedef float8 gpucol_lanes;
typedef int8 gpucol_mask;
#define GPUCOL_LANES_RECIPROCAL(x) convert_float8(1.0 / convert_double8(x))
#elif GPUCOL_LANES == 16
typedef float16 gpucol_lanes;
typedef int16 gpucol_mask;
#define GPUCOL_LANES_RECIPROCAL(x) convert_float16(1.0 / convert_double16(x))
#else
#error "GPUCOL_LANES must be 4, 8 or 16"
#endif
#define GPUCOL_MASK_NOT(m) (~(m))
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_max(gpucol_lanes a, gpucol_lanes b) {
  return fmax(a, b);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_min(gpucol_lanes a, gpucol_lanes b) {
  return fmin(a, b);
}
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_abs(gpucol_lanes a) {
  return fabs(a);
}
/* c ? x : y lane by lane. */
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_select(gpucol_mask c, gpucol_lanes x, gpucol_lanes y) {
  return select(y, x, c);
}
#else
#include <stdint.h>
#include <string.h>
typedef float gpucol_lanes;
typedef int gpucol_mask;
/* 1 / x: OpenCL allows a float division 2.5 ulp of error, so the device divides in double and rounds, which
   gives the correctly rounded quotient that the CPU's float division gives (53 >= 2 * 24 + 2 bits). */
#define GPUCOL_LANES_RECIPROCAL(x) (1.0f / (x))
#define GPUCOL_MASK_NOT(m) (!(m))
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_max(gpucol_lanes a, gpucol_lanes b) {
  return a < b ? b : a;
}
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_min(gpucol_lanes a, gpucol_lanes b) {
  return b < a ? b : a;
}
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_abs(gpucol_lanes a) {
  return fabsf(a);
}
/* c ? x : y on the bits: written as a plain conditional, the compiler moves the arithmetic that uses the
   result into the branches, which it may then not run unconditionally (float operations can trap), and the
   loop stops being vector code. */
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes_select(gpucol_mask c, gpucol_lanes x, gpucol_lanes y) {
  uint32_t xBits, yBits;
  memcpy(&xBits, &x, sizeof x);
  memcpy(&yBits, &y, sizeof y);
  const uint32_t mask = 0u - (uint32_t)c;
  const uint32_t bits = (xBits & mask) | (yBits & ~mask);
  float out;
  memcpy(&out, &bits, sizeof out);
  return out;
}
#endif

/* Margin of the float pre-test below, in units of the scale max|e1| * max|e2| * max_i max|q_i - v0|
   (infinity norms of the plane triangle's edges and of the other triangle's vertices taken from v0): 64
   float ulps.

   Why it is enough (u = 2^-24; gamma_k = k u / (1 - k u); E1, E2, R the three factors of the scale, exact):
   the float edges e = fl(v - v0) and offsets r = fl(q - v0) have relative error u per component; a normal
   component fl(fl(x y) - fl(z w)) of rounded edges is within gamma_4 (|x y| + |z w|) <= 2 gamma_4 E1 E2 of
   the exact one; the dot product adds a rounding per product and per sum (gamma_3). Summed over the three
   terms, |d_float - d_exact| <= (gamma_4 * 6 + gamma_4 (1 + gamma_4) * 6) E1 E2 R < 48.1 u E1 E2 R. The
   double test computes the same distance to within 1e-15 E1 E2 R and snaps it to 0 when within
   GPUCOL_SNAP_RELATIVE (1e-12) of errorScale * extent = E1 E2 R. So |d_float| > 48.2 u E1 E2 R (48.2 u
   = 2.9e-6 >> 1e-12) proves that the double distance is non-zero after snapping and has d_float's sign. The
   margin is computed in float from the rounded factors, which costs at most five more roundings of 64 u:
   still above 63.9 u, with room to spare. */
#define GPUCOL_FLOAT_SIDE_MARGIN (64.0f / 16777216.0f)
/* Range of each factor E1, E2, R inside which the float pre-test is valid: no intermediate overflows
   (6 E1 E2 R < 2^123), and the absolute error of underflowing products (2^-149 each) stays below 2^-10 of
   the margin (which is at least 2^-138). Outside it the pre-test abstains and the double test decides. */
#define GPUCOL_FLOAT_SIDE_MIN_FACTOR 0x1p-40f
#define GPUCOL_FLOAT_SIDE_MAX_FACTOR 0x1p40f
/* Range of every factor (E1, E2, R of both planes) inside which floatIntervalsApartBranchFree is valid:
   narrower than the plane test's, because it multiplies four factors (the line direction nA x nB), which
   must neither overflow nor lose precision to underflow. Outside it the interval stage abstains. */
#define GPUCOL_FLOAT_INTERVAL_MIN_FACTOR 0x1p-20f
#define GPUCOL_FLOAT_INTERVAL_MAX_FACTOR 0x1p20f
/* The interval stage needs the planes' intersection line to be well defined: its float direction must have
   a component of at least this times EA1 EA2 EB1 EB2 (about sin 1e-3 for well-shaped triangles), so that
   the direction's rounding (below 2^-17 of that product in float, 2^-46 in double) cannot matter. */
#define GPUCOL_FLOAT_LINE_MINIMUM 0x1p-10f

/* A point or vector per lane. */
GPUCOL_LANE_VECTOR(GpucolLanes3, gpucol_lanes3, gpucol_lanes)
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes3_max_abs(GpucolLanes3 v) {
  return gpucol_lanes_max(gpucol_lanes_max(gpucol_lanes_abs(v.x), gpucol_lanes_abs(v.y)),
                          gpucol_lanes_abs(v.z));
}
/* v's coordinate on the axis picked by useX / useY (else z). */
GPUCOL_SHARED_FORCE_INLINE gpucol_lanes gpucol_lanes3_axis(GpucolLanes3 v, gpucol_mask useX,
                                                           gpucol_mask useY) {
  return gpucol_lanes_select(useX, v.x, gpucol_lanes_select(useY, v.y, v.z));
}
GPUCOL_SHARED_FORCE_INLINE gpucol_mask gpucol_interval_factor(gpucol_lanes x) {
  return (x >= GPUCOL_FLOAT_INTERVAL_MIN_FACTOR) & (x <= GPUCOL_FLOAT_INTERVAL_MAX_FACTOR);
}

/* The float distances of q0, q1, q2 from the plane through v0 spanned by e1 and e2, unnormalised (times
   |e1 x e2|), as every float pre-test computes them, with the bound on their error (`margin`,
   GPUCOL_FLOAT_SIDE_MARGIN times the three factors) and the factors, whose range each caller checks: the
   same expressions everywhere, so that the margin's bound holds for all of them. */
typedef struct GpucolFloatPlane {
  GpucolLanes3 normal;   /* e1 x e2 */
  GpucolLanes3 distance; /* of q0, q1, q2 */
  gpucol_lanes edge1, edge2, extent, margin;
} GpucolFloatPlane;

GPUCOL_SHARED_FORCE_INLINE GpucolFloatPlane gpucol_float_plane(GpucolLanes3 v0, GpucolLanes3 e1,
                                                               GpucolLanes3 e2, GpucolLanes3 q0,
                                                               GpucolLanes3 q1, GpucolLanes3 q2) {
  GpucolFloatPlane p;
  p.normal = gpucol_lanes3_cross(e1, e2);
  p.edge1 = gpucol_lanes3_max_abs(e1);
  p.edge2 = gpucol_lanes3_max_abs(e2);
  const GpucolLanes3 r0 = gpucol_lanes3_sub(q0, v0), r1 = gpucol_lanes3_sub(q1, v0),
                     r2 = gpucol_lanes3_sub(q2, v0);
  p.distance = gpucol_lanes3(gpucol_lanes3_dot(p.normal, r0), gpucol_lanes3_dot(p.normal, r1),
                             gpucol_lanes3_dot(p.normal, r2));
  p.extent = gpucol_lanes_max(gpucol_lanes_max(gpucol_lanes3_max_abs(r0), gpucol_lanes3_max_abs(r1)),
                              gpucol_lanes3_max_abs(r2));
  p.margin = GPUCOL_FLOAT_SIDE_MARGIN * p.edge1 * p.edge2 * p.extent;
  return p;
}

/* Float pre-test of q0, q1, q2 against `plane`, conservative by GPUCOL_FLOAT_SIDE_MARGIN: it only reports
   what the double test is certain to find (`apart`: all three certainly non-zero with one sign, so
   gpucol_all_on_one_side will hold; `off`: one certainly non-zero, so gpucol_all_in_plane will not). NaN,
   infinite or out-of-range input reports nothing. Branch-free: in the near phase the outcome is close to a
   coin toss, so a branch would be mispredicted half the time. */
GPUCOL_SHARED_FORCE_INLINE void gpucol_float_plane_side(GpucolLanes3 v0, GpucolLanes3 v1, GpucolLanes3 v2,
                                                        GpucolLanes3 q0, GpucolLanes3 q1, GpucolLanes3 q2,
                                                        gpucol_mask* apart, gpucol_mask* off) {
  const GpucolFloatPlane p =
      gpucol_float_plane(v0, gpucol_lanes3_sub(v1, v0), gpucol_lanes3_sub(v2, v0), q0, q1, q2);
  const gpucol_lanes d0 = p.distance.x, d1 = p.distance.y, d2 = p.distance.z, m = p.margin;
  /* `&` rather than `&&`: comparisons are cheaper than branches; NaN fails every one of them. */
  const gpucol_mask inRange =
      (p.edge1 >= GPUCOL_FLOAT_SIDE_MIN_FACTOR) & (p.edge1 <= GPUCOL_FLOAT_SIDE_MAX_FACTOR) &
      (p.edge2 >= GPUCOL_FLOAT_SIDE_MIN_FACTOR) & (p.edge2 <= GPUCOL_FLOAT_SIDE_MAX_FACTOR) &
      (p.extent >= GPUCOL_FLOAT_SIDE_MIN_FACTOR) & (p.extent <= GPUCOL_FLOAT_SIDE_MAX_FACTOR);
  const gpucol_mask above = (d0 > m) & (d1 > m) & (d2 > m);
  const gpucol_mask below = (d0 < -m) & (d1 < -m) & (d2 < -m);
  *apart = inRange & (above | below);
  *off = inRange & ((gpucol_lanes_abs(d0) > m) | (gpucol_lanes_abs(d1) > m) | (gpucol_lanes_abs(d2) > m));
}

/* True when float arithmetic proves that the double test (gpucol_triangles_intersect) answers "no" at one of
   Möller's two plane rejections: all of b on one side of a's plane, or (b certainly not in a's plane, so the
   coplanar branch is not taken) all of a on one side of b's plane. A degenerate triangle is rejected by the
   double test before or instead of these steps, so it answers "no" in every branch this function can prove.
   Several times cheaper than the double test, and most candidate pairs of the middle phase end here. */
GPUCOL_SHARED_FORCE_INLINE gpucol_mask gpucol_float_certainly_apart(GpucolLanes3 a0, GpucolLanes3 a1,
                                                                    GpucolLanes3 a2, GpucolLanes3 b0,
                                                                    GpucolLanes3 b1, GpucolLanes3 b2) {
  gpucol_mask apartB, offB, apartA, offA;
  gpucol_float_plane_side(a0, a1, a2, b0, b1, b2, &apartB, &offB);
  gpucol_float_plane_side(b0, b1, b2, a0, a1, a2, &apartA, &offA);
  return apartB | (offB & apartA);
}

/* One triangle's interval on the line's axis (coordinates p, distances d to the other plane, margin m) and
   the bound on its endpoints' error, as (low, high, error); see gpucol_float_intervals_apart. */
GPUCOL_SHARED_FORCE_INLINE GpucolLanes3 gpucol_float_interval(GpucolLanes3 p, GpucolLanes3 d, gpucol_lanes m,
                                                              gpucol_lanes edges, gpucol_lanes largest) {
  const float u = 1.0f / 16777216.0f;
  /* The lone vertex as gpucol_lone_vertex picks it for non-zero distances, then the next two in cyclic order.
   */
  const gpucol_mask lone2 = (d.x > 0) == (d.y > 0);
  const gpucol_mask lone1 = GPUCOL_MASK_NOT(lone2) & ((d.x > 0) == (d.z > 0));
  const gpucol_lanes dLone = gpucol_lanes_select(lone2, d.z, gpucol_lanes_select(lone1, d.y, d.x));
  const gpucol_lanes pLone = gpucol_lanes_select(lone2, p.z, gpucol_lanes_select(lone1, p.y, p.x));
  const gpucol_lanes dNext = gpucol_lanes_select(lone2, d.x, gpucol_lanes_select(lone1, d.z, d.y));
  const gpucol_lanes pNext = gpucol_lanes_select(lone2, p.x, gpucol_lanes_select(lone1, p.z, p.y));
  const gpucol_lanes dLast = gpucol_lanes_select(lone2, d.y, gpucol_lanes_select(lone1, d.x, d.z));
  const gpucol_lanes pLast = gpucol_lanes_select(lone2, p.y, gpucol_lanes_select(lone1, p.x, p.z));
  const gpucol_lanes inverse1 = GPUCOL_LANES_RECIPROCAL(dLone - dNext);
  const gpucol_lanes inverse2 = GPUCOL_LANES_RECIPROCAL(dLone - dLast);
  const gpucol_lanes t1 = pLone + (pNext - pLone) * (dLone * inverse1);
  const gpucol_lanes t2 = pLone + (pLast - pLone) * (dLone * inverse2);
  const gpucol_lanes inverseSmallest =
      gpucol_lanes_max(gpucol_lanes_abs(inverse1), gpucol_lanes_abs(inverse2));
  return gpucol_lanes3(gpucol_lanes_min(t1, t2), gpucol_lanes_max(t1, t2),
                       edges * (4.0f * m * inverseSmallest + 8.0f * u) + 4.0f * u * largest);
}

/* Float proof that Möller's interval step (step 3) rejects the pair in double: both triangles cross the
   other's plane, and their intervals on the planes' intersection line L are disjoint by more than float and
   double rounding could explain. Run on the pairs that gpucol_float_certainly_apart could not reject (a
   third of the candidates of the thesis scene; two thirds of those are rejected here), it leaves the double
   test to the pairs that intersect or nearly do. Returns 1 for "certainly apart", else 0; branch-free.

   Why the answer is the double test's (u = 2^-24; m the plane test's margin, which bounds the float error of
   every distance, see GPUCOL_FLOAT_SIDE_MARGIN):
   - Every distance is |d| > 2m, so float and double agree on every sign, the double snaps none of them to 0
     (so its coplanar branch is not taken) and both pick the same lone vertex and the same two edges per
     triangle. The exact crossing points of those edges with the other plane lie on L.
   - A crossing point is p_a + (p_b - p_a) r, r = d_a / (d_a - d_b) in [0, 1]. With both distances off by at
     most m, and |d_a| + |d_b| = S >= 4m, r is off by at most 2m / (S - 2m) <= 4m / S, plus 3.1u for the
     float division; the crossing's coordinate is then off by at most W (4m / S + 5.2u) + u |t| on any axis,
     W the infinity norm of the edge: the bound errA / errB below, with room to spare (W (4m/S + 8u) + 4u P,
     P the largest coordinate magnitude of the six vertices).
   - Float tests on its own axis k, the largest component of its direction D; the double on k', the largest
     of its own. Two points of L differ along axis x by (their distance along L) |D_x| / |D|, so a gap on k
     is at most the gap on k' times |D_k| / |D_k'|, which is below 1 + 2^-34 when |D_k| >=
   GPUCOL_FLOAT_LINE_MINIMUM EA1 EA2 EB1 EB2 (the double's direction is within 2^-46 of that product).
   - The intervals are called apart when their float gap exceeds 2 (errA + errB): the true gap on k then
     exceeds errA + errB less the comparison's own rounding (>= 7u P and 7u W), which covers the double's
     rounding of its crossing points on k' (below 2^-50 (W + P) and W 1e-15 E1 E2 R / S).
   A degenerate triangle is rejected by the double test anyway, so "apart" is its answer for those too. */
GPUCOL_SHARED_FORCE_INLINE gpucol_mask gpucol_float_intervals_apart(GpucolLanes3 a0, GpucolLanes3 a1,
                                                                    GpucolLanes3 a2, GpucolLanes3 b0,
                                                                    GpucolLanes3 b1, GpucolLanes3 b2) {
  /* Distances as gpucol_float_plane_side computes them (gpucol_float_plane), so the margin's bound holds. */
  const GpucolFloatPlane planeA =
      gpucol_float_plane(a0, gpucol_lanes3_sub(a1, a0), gpucol_lanes3_sub(a2, a0), b0, b1, b2);
  const GpucolFloatPlane planeB =
      gpucol_float_plane(b0, gpucol_lanes3_sub(b1, b0), gpucol_lanes3_sub(b2, b0), a0, a1, a2);
  const GpucolLanes3 nA = planeA.normal, nB = planeB.normal, dB = planeA.distance, dA = planeB.distance;
  const gpucol_lanes ea1 = planeA.edge1, ea2 = planeA.edge2, eb1 = planeB.edge1, eb2 = planeB.edge2;
  const gpucol_lanes extentB = planeA.extent, extentA = planeB.extent, mB = planeA.margin, mA = planeB.margin;
  gpucol_mask valid = gpucol_interval_factor(ea1) & gpucol_interval_factor(ea2) &
                      gpucol_interval_factor(eb1) & gpucol_interval_factor(eb2) &
                      gpucol_interval_factor(extentA) & gpucol_interval_factor(extentB);
  valid &= (gpucol_lanes_abs(dB.x) > 2.0f * mB) & (gpucol_lanes_abs(dB.y) > 2.0f * mB) &
           (gpucol_lanes_abs(dB.z) > 2.0f * mB);
  valid &= (gpucol_lanes_abs(dA.x) > 2.0f * mA) & (gpucol_lanes_abs(dA.y) > 2.0f * mA) &
           (gpucol_lanes_abs(dA.z) > 2.0f * mA);
  /* Both triangles cross the other's plane: neither all above nor all below. */
  valid &= GPUCOL_MASK_NOT((dB.x > 0) & (dB.y > 0) & (dB.z > 0)) &
           GPUCOL_MASK_NOT((dB.x < 0) & (dB.y < 0) & (dB.z < 0));
  valid &= GPUCOL_MASK_NOT((dA.x > 0) & (dA.y > 0) & (dA.z > 0)) &
           GPUCOL_MASK_NOT((dA.x < 0) & (dA.y < 0) & (dA.z < 0));

  const GpucolLanes3 direction = gpucol_lanes3_cross(nA, nB);
  const gpucol_lanes dx = gpucol_lanes_abs(direction.x), dy = gpucol_lanes_abs(direction.y),
                     dz = gpucol_lanes_abs(direction.z);
  /* Selections by value rather than by index, so that a loop over pairs stays vector code. */
  const gpucol_mask useX = (dx >= dy) & (dx >= dz), useY = GPUCOL_MASK_NOT(useX) & (dy >= dz);
  valid &=
      gpucol_lanes_max(gpucol_lanes_max(dx, dy), dz) >= GPUCOL_FLOAT_LINE_MINIMUM * (ea1 * ea2) * (eb1 * eb2);

  const gpucol_lanes largest = gpucol_lanes_max(
      gpucol_lanes_max(gpucol_lanes_max(gpucol_lanes3_max_abs(a0), gpucol_lanes3_max_abs(a1)),
                       gpucol_lanes_max(gpucol_lanes3_max_abs(a2), gpucol_lanes3_max_abs(b0))),
      gpucol_lanes_max(gpucol_lanes3_max_abs(b1), gpucol_lanes3_max_abs(b2)));
  const gpucol_lanes edgesA =
      gpucol_lanes_max(gpucol_lanes_max(ea1, ea2), gpucol_lanes3_max_abs(gpucol_lanes3_sub(a2, a1)));
  const gpucol_lanes edgesB =
      gpucol_lanes_max(gpucol_lanes_max(eb1, eb2), gpucol_lanes3_max_abs(gpucol_lanes3_sub(b2, b1)));
  const GpucolLanes3 pA =
      gpucol_lanes3(gpucol_lanes3_axis(a0, useX, useY), gpucol_lanes3_axis(a1, useX, useY),
                    gpucol_lanes3_axis(a2, useX, useY));
  const GpucolLanes3 pB =
      gpucol_lanes3(gpucol_lanes3_axis(b0, useX, useY), gpucol_lanes3_axis(b1, useX, useY),
                    gpucol_lanes3_axis(b2, useX, useY));
  const GpucolLanes3 iA = gpucol_float_interval(pA, dA, mA, edgesA, largest);
  const GpucolLanes3 iB = gpucol_float_interval(pB, dB, mB, edgesB, largest);
  const gpucol_lanes tolerance = 2.0f * (iA.z + iB.z);
  return valid & ((iA.x > iB.y + tolerance) | (iB.x > iA.y + tolerance));
}

#endif /* GPUCOL_SHARED_MATH_TRIANGLE_PRETEST_H */
