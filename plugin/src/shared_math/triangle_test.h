/* Möller's triangle-triangle test (Möller 1997; thesis §3.5) and the contact rule of thesis §5.3.4, one pair
   at a time, in double arithmetic on float input: the CPU's generateContactAndTest and trianglesIntersect
   (plugin/src/narrowphase) and the device's near phase (opencl/kernels/mesh_near_phase.cl) both run these
   functions. Why double: plugin/src/narrowphase/triangle_plane.h.
   Vectors are double[3]; dot products sum (x + y) + z and cross products go component by component, as
   Eigen's 3-vectors do, which the CPU's four-pair form (triangle_lanes.h) repeats lane by lane. */
#ifndef GPUCOL_SHARED_MATH_TRIANGLE_TEST_H
#define GPUCOL_SHARED_MATH_TRIANGLE_TEST_H

#include "plugin/src/shared_math/shared_c.h"

#ifdef __OPENCL_VERSION__
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

/* A triangle is degenerate when sin^2 of the angle between its edges v1-v0 and v2-v0 is below this.
   1e-12 is an angle of 1e-6 rad: moving one vertex by a float ulp (1.2e-7 relative) would tilt such a
   triangle's plane by a tenth of a radian, so its plane means nothing. Needles and slivers above it
   keep working. The test is written as !(a > b) so that NaN input is also called degenerate. */
#define GPUCOL_DEGENERATE_SIN2 1e-12
/* Relative tolerance under which a signed distance is snapped to exactly zero (Möller 1997 uses an
   absolute EPSILON; ours is relative, so it does not depend on the units of the mesh). The double error
   of d = n.(q - p0) is a few units of 1e-16 of |e1||e2||q - p0|; 1e-12 covers it with a wide margin and
   stays far below float's resolution (1.2e-7), so only configurations that are exact in the float input
   (a shared vertex, a vertex on the other plane, coplanar faces) are snapped. Snapping makes those exact:
   touching counts as intersecting instead of a coin toss, and a pair whose every vertex is in the other
   plane goes to the 2-D coplanar test. The side effect, the intersection line moving sideways by
   1e-12 / sin(angle), stays below 1e-6 of the pair's size at every angle once the coplanar case is
   taken out (it is at most min(angle, 1e-12 / angle)). */
#define GPUCOL_SNAP_RELATIVE 1e-12

GPUCOL_SHARED_INLINE void gpucol_sub3(const double a[3], const double b[3], double r[3]) {
  for (int i = 0; i < 3; ++i) r[i] = a[i] - b[i];
}

GPUCOL_SHARED_INLINE void gpucol_cross3(const double a[3], const double b[3], double r[3]) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}

GPUCOL_SHARED_INLINE double gpucol_dot3(const double a[3], const double b[3]) {
  return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
}

GPUCOL_SHARED_INLINE double gpucol_max_abs3(const double a[3]) {
  return gpucol_max_d(gpucol_max_d(fabs(a[0]), fabs(a[1])), fabs(a[2]));
}

/* The plane of a triangle: v0, the unnormalised normal e1 x e2, max|e1| max|e2| (the scale of the normal's
   rounding error), and whether it is degenerate (zero area or NaN: no plane). */
typedef struct GpucolPlane {
  double origin[3];
  double normal[3];
  double errorScale;
  int degenerate;
} GpucolPlane;

GPUCOL_SHARED_INLINE GpucolPlane gpucol_make_plane(const double v0[3], const double v1[3],
                                                   const double v2[3]) {
  double e1[3], e2[3];
  gpucol_sub3(v1, v0, e1);
  gpucol_sub3(v2, v0, e2);
  GpucolPlane plane;
  for (int i = 0; i < 3; ++i) plane.origin[i] = v0[i];
  gpucol_cross3(e1, e2, plane.normal);
  plane.errorScale = gpucol_max_abs3(e1) * gpucol_max_abs3(e2);
  /* !(a > b), so that NaN is degenerate too. */
  plane.degenerate = !(gpucol_dot3(plane.normal, plane.normal) >
                       GPUCOL_DEGENERATE_SIN2 * gpucol_dot3(e1, e1) * gpucol_dot3(e2, e2));
  return plane;
}

/* Signed distances (times |normal|) of q0, q1, q2 to the plane, those within the rounding tolerance snapped
   to exactly 0. Positive is on the outer side. */
GPUCOL_SHARED_INLINE void gpucol_signed_distances(const GpucolPlane* plane, const double q0[3],
                                                  const double q1[3], const double q2[3], double d[3]) {
  double r0[3], r1[3], r2[3];
  gpucol_sub3(q0, plane->origin, r0);
  gpucol_sub3(q1, plane->origin, r1);
  gpucol_sub3(q2, plane->origin, r2);
  d[0] = gpucol_dot3(plane->normal, r0);
  d[1] = gpucol_dot3(plane->normal, r1);
  d[2] = gpucol_dot3(plane->normal, r2);
  const double extent =
      gpucol_max_d(gpucol_max_d(gpucol_max_abs3(r0), gpucol_max_abs3(r1)), gpucol_max_abs3(r2));
  const double tolerance = GPUCOL_SNAP_RELATIVE * plane->errorScale * extent;
  for (int i = 0; i < 3; ++i) d[i] = fabs(d[i]) <= tolerance ? 0.0 : d[i];
}

/* Both strictly positive or both strictly negative (by sign: x * y underflows for tiny meshes). */
GPUCOL_SHARED_INLINE int gpucol_same_strict_sign(double x, double y) {
  return (x > 0.0 && y > 0.0) || (x < 0.0 && y < 0.0);
}

/* All three distances non-zero with one sign: the triangle misses the plane (Möller's early rejection). */
GPUCOL_SHARED_INLINE int gpucol_all_on_one_side(const double d[3]) {
  return gpucol_same_strict_sign(d[0], d[1]) && gpucol_same_strict_sign(d[0], d[2]);
}

/* All three distances zero: the triangle lies in the plane. */
GPUCOL_SHARED_INLINE int gpucol_all_in_plane(const double d[3]) {
  return d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0;
}

/* The vertex alone on its side of the other plane (Möller's "compute intervals"), for distances neither all
   on one side nor all zero. When it lies in the plane both crossings are that vertex, and no division by
   zero happens. */
GPUCOL_SHARED_INLINE int gpucol_lone_vertex(const double d[3]) {
  if (gpucol_same_strict_sign(d[0], d[1])) return 2;
  if (gpucol_same_strict_sign(d[0], d[2])) return 1;
  if (gpucol_same_strict_sign(d[1], d[2]) || d[0] != 0.0) return 0;
  if (d[1] != 0.0) return 1;
  return 2;
}

/* Interval [lo, hi] of a triangle on the intersection line, from its vertices' coordinates p on the line's
   dominant axis and their distances d to the other plane. */
GPUCOL_SHARED_INLINE void gpucol_line_interval(const double p[3], const double d[3], double* lo, double* hi) {
  const int a = gpucol_lone_vertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  const double t0 = p[a] + (p[b] - p[a]) * (d[a] / (d[a] - d[b]));
  const double t1 = p[a] + (p[c] - p[a]) * (d[a] / (d[a] - d[c]));
  *lo = gpucol_min_d(t0, t1);
  *hi = gpucol_max_d(t0, t1);
}

/* The same crossing points in 3-D: the segment where triangle v meets the other plane. */
GPUCOL_SHARED_INLINE void gpucol_plane_crossing(const double v[3][3], const double d[3], double s0[3],
                                                double s1[3]) {
  const int a = gpucol_lone_vertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  const double tb = d[a] / (d[a] - d[b]);
  const double tc = d[a] / (d[a] - d[c]);
  for (int i = 0; i < 3; ++i) {
    s0[i] = v[a][i] + (v[b][i] - v[a][i]) * tb;
    s1[i] = v[a][i] + (v[c][i] - v[a][i]) * tc;
  }
}

/* Index of the largest absolute component (the first of equals). */
GPUCOL_SHARED_INLINE int gpucol_dominant_axis(const double v[3]) {
  const double x = fabs(v[0]), y = fabs(v[1]), z = fabs(v[2]);
  return x >= y ? (x >= z ? 0 : 2) : (y >= z ? 1 : 2);
}

/* Twice the signed area of the 2-D triangle (a, b, c): positive when counter-clockwise. */
GPUCOL_SHARED_INLINE double gpucol_orient2d(double ax, double ay, double bx, double by, double cx,
                                            double cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

/* x and y are zero or of opposite signs: the segment between them reaches 0. */
GPUCOL_SHARED_INLINE int gpucol_straddles(double x, double y) {
  return (x <= 0.0 && y >= 0.0) || (x >= 0.0 && y <= 0.0);
}

/* Point in a 2-D triangle of either winding; the boundary counts as inside. */
GPUCOL_SHARED_INLINE int gpucol_inside_or_on(const double tx[3], const double ty[3], double px, double py) {
  const double o0 = gpucol_orient2d(tx[0], ty[0], tx[1], ty[1], px, py);
  const double o1 = gpucol_orient2d(tx[1], ty[1], tx[2], ty[2], px, py);
  const double o2 = gpucol_orient2d(tx[2], ty[2], tx[0], ty[0], px, py);
  return (o0 >= 0.0 && o1 >= 0.0 && o2 >= 0.0) || (o0 <= 0.0 && o1 <= 0.0 && o2 <= 0.0);
}

/* Whether coplanar triangles a and b overlap, in the plane that drops axis `dropAxis`; with `point` (not 0),
   also the mean of the corners of their overlap polygon: edge crossings and the corners inside the other. */
GPUCOL_SHARED_INLINE int gpucol_coplanar_overlap(const double a[3][3], const double b[3][3], int dropAxis,
                                                 double* point) {
  const int u = dropAxis == 0 ? 1 : 0;
  const int v = dropAxis == 2 ? 1 : 2;
  double ax[3], ay[3], bx[3], by[3];
  for (int i = 0; i < 3; ++i) {
    ax[i] = a[i][u];
    ay[i] = a[i][v];
    bx[i] = b[i][u];
    by[i] = b[i][v];
  }
  const int wantPoint = point != 0;
  double sum[3] = {0.0, 0.0, 0.0};
  int count = 0;
  /* Edge against edge: proper crossings and an endpoint on the other segment. Collinear edge pairs (all four
     orientations zero) are skipped: when they overlap, an endpoint of one lies on the other and the
     containment tests below find it. */
  for (int i = 0; i < 3; ++i) {
    const int i1 = i == 2 ? 0 : i + 1;
    for (int j = 0; j < 3; ++j) {
      const int j1 = j == 2 ? 0 : j + 1;
      const double o1 = gpucol_orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j], by[j]);
      const double o2 = gpucol_orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j1], by[j1]);
      if (!gpucol_straddles(o1, o2) || (o1 == 0.0 && o2 == 0.0)) continue;
      const double o3 = gpucol_orient2d(bx[j], by[j], bx[j1], by[j1], ax[i], ay[i]);
      const double o4 = gpucol_orient2d(bx[j], by[j], bx[j1], by[j1], ax[i1], ay[i1]);
      /* o3 == o4 (both zero, since they straddle): a's edge lies on b's line. Exact input reaches it only for
         collinear edges, rounding too: an edge below about 1e-16 of the other triangle's size has both ends
         "on" b's line while o1, o2 still straddle (the triangle fuzzer's needle 1e-44 wide gave 0 / 0 = NaN).
         The containment tests below find the endpoints that matter, as for collinear edges. */
      if (!gpucol_straddles(o3, o4) || o3 == o4) continue;
      if (!wantPoint) return 1;
      const double t = o3 / (o3 - o4);
      for (int k = 0; k < 3; ++k) sum[k] += a[i][k] + (a[i1][k] - a[i][k]) * t;
      ++count;
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (gpucol_inside_or_on(bx, by, ax[i], ay[i])) {
      if (!wantPoint) return 1;
      for (int k = 0; k < 3; ++k) sum[k] += a[i][k];
      ++count;
    }
    if (gpucol_inside_or_on(ax, ay, bx[i], by[i])) {
      if (!wantPoint) return 1;
      for (int k = 0; k < 3; ++k) sum[k] += b[i][k];
      ++count;
    }
  }
  if (count == 0) return 0;
  for (int k = 0; k < 3; ++k) point[k] = sum[k] / (double)count;
  return 1;
}

/* Möller's test (steps 1-3) on triangles a and b: 1 when they intersect (touching counts). */
GPUCOL_SHARED_INLINE int gpucol_triangles_intersect(const double a[3][3], const double b[3][3]) {
  /* Step 1: B's vertices against A's plane; B's plane is built only after this first early-out (a
     degenerate B is rejected either way). */
  const GpucolPlane planeA = gpucol_make_plane(a[0], a[1], a[2]);
  if (planeA.degenerate) return 0;
  double dB[3];
  gpucol_signed_distances(&planeA, b[0], b[1], b[2], dB);
  if (gpucol_all_on_one_side(dB)) return 0;
  const GpucolPlane planeB = gpucol_make_plane(b[0], b[1], b[2]);
  if (planeB.degenerate) return 0;
  if (gpucol_all_in_plane(dB)) return gpucol_coplanar_overlap(a, b, gpucol_dominant_axis(planeA.normal), 0);
  /* Step 2: A's vertices against B's plane. */
  double dA[3];
  gpucol_signed_distances(&planeB, a[0], a[1], a[2], dA);
  if (gpucol_all_on_one_side(dA)) return 0;
  if (gpucol_all_in_plane(dA)) return gpucol_coplanar_overlap(a, b, gpucol_dominant_axis(planeB.normal), 0);
  /* Step 3: both cross the line L where the planes meet; they intersect iff their intervals on L overlap.
     Möller's simplification: the coordinate on L's dominant axis orders points on L like L's parameter. */
  double line[3];
  gpucol_cross3(planeA.normal, planeB.normal, line);
  const int axis = gpucol_dominant_axis(line);
  const double pA[3] = {a[0][axis], a[1][axis], a[2][axis]};
  const double pB[3] = {b[0][axis], b[1][axis], b[2][axis]};
  double loA, hiA, loB, hiB;
  gpucol_line_interval(pA, dA, &loA, &hiA);
  gpucol_line_interval(pB, dB, &loB, &hiB);
  return loA <= hiB && loB <= hiA;
}

/* What gpucol_triangle_contact found: whether the triangles intersect, and whether a contact is kept with
   its values (TriangleContact of plugin/src/narrowphase/triangle_contact.h, in double). */
typedef struct GpucolContact {
  int intersects;
  int contact;
  double point[3];
  double normalOnB[3];
  double depth;
  double deepest[3];
  int onFaceOfB;
  int sameFacing;
} GpucolContact;

/* Möller's test and, for an intersecting pair, the contact of thesis §5.3.4 (the rule is documented at
   generateContact, triangle_contact.h). The test's signed distances are reused by the contact. */
GPUCOL_SHARED_INLINE GpucolContact gpucol_triangle_contact(const double a[3][3], const double b[3][3]) {
  GpucolContact out;
  out.intersects = 0;
  out.contact = 0;
  out.depth = 0.0;
  out.onFaceOfB = 1;
  out.sameFacing = 0;
  const GpucolPlane planeA = gpucol_make_plane(a[0], a[1], a[2]);
  if (planeA.degenerate) return out;
  double dB[3];
  gpucol_signed_distances(&planeA, b[0], b[1], b[2], dB);
  if (gpucol_all_on_one_side(dB)) return out;
  const GpucolPlane planeB = gpucol_make_plane(b[0], b[1], b[2]);
  if (planeB.degenerate) return out;
  double dA[3];
  gpucol_signed_distances(&planeB, a[0], a[1], a[2], dA);
  if (gpucol_all_on_one_side(dA)) return out;

  const double lengthA = sqrt(gpucol_dot3(planeA.normal, planeA.normal));
  const double lengthB = sqrt(gpucol_dot3(planeB.normal, planeB.normal));
  double nA[3], nB[3];
  for (int k = 0; k < 3; ++k) {
    nA[k] = planeA.normal[k] / lengthA;
    nB[k] = planeB.normal[k] / lengthB;
  }

  /* Coplanar (after snapping, the cases gpucol_triangles_intersect sends to the 2-D test): touching face on
     face, depth 0 along nB, at the mean of the overlap polygon's corners. Flush faces side by side (the sides
     of two stacked boxes of one size) press on nothing: only faces that face each other rest on each other.
   */
  const int coplanarB = gpucol_all_in_plane(dB);
  if (coplanarB || gpucol_all_in_plane(dA)) {
    const int dropAxis = gpucol_dominant_axis(coplanarB ? planeA.normal : planeB.normal);
    if (!gpucol_coplanar_overlap(a, b, dropAxis, out.point)) return out;
    out.intersects = 1;
    if (gpucol_dot3(nA, nB) > 0) return out;
    out.contact = 1;
    for (int k = 0; k < 3; ++k) {
      out.normalOnB[k] = nB[k];
      out.deepest[k] = out.point[k];
    }
    return out;
  }

  /* Möller's interval test on L with the crossing points kept in 3-D: on the dominant axis, as
     gpucol_triangles_intersect, so both decide alike. */
  double line[3];
  gpucol_cross3(planeA.normal, planeB.normal, line);
  const int axis = gpucol_dominant_axis(line);
  double sA[2][3], sB[2][3];
  gpucol_plane_crossing(a, dA, sA[0], sA[1]);
  gpucol_plane_crossing(b, dB, sB[0], sB[1]);
  const int swapA = sA[1][axis] < sA[0][axis], swapB = sB[1][axis] < sB[0][axis];
  const double* lowA = sA[swapA];
  const double* highA = sA[1 - swapA];
  const double* lowB = sB[swapB];
  const double* highB = sB[1 - swapB];
  if (lowA[axis] > highB[axis] || lowB[axis] > highA[axis]) return out;
  out.intersects = 1;

  /* §5.3.4: the distance to move each triangle along the other's normal out of its plane (the distances are
     scaled by |normal|; a triangle that only touches has minimum 0, exact by snapping). */
  const double moveA = gpucol_max_d(0.0, -gpucol_min_d(gpucol_min_d(dA[0], dA[1]), dA[2]) / lengthB);
  const double moveB = gpucol_max_d(0.0, -gpucol_min_d(gpucol_min_d(dB[0], dB[1]), dB[2]) / lengthA);
  const int aMoves = moveA <= moveB;
  const double move = aMoves ? moveA : moveB;

  /* §5.3.4: dropped when sliding the triangles apart along L is shorter than the depth. The whole triangles
     are projected on L's unit direction (the direction itself when its length is 0, as Eigen's normalized()),
     relative to a[0] so that a pair far from the origin keeps its precision. */
  const double lineSquared = gpucol_dot3(line, line);
  double u[3];
  if (lineSquared > 0.0) {
    const double lineLength = sqrt(lineSquared);
    for (int k = 0; k < 3; ++k) u[k] = line[k] / lineLength;
  } else {
    for (int k = 0; k < 3; ++k) u[k] = line[k];
  }
  double r[3];
  gpucol_sub3(a[1], a[0], r);
  const double pA1 = gpucol_dot3(u, r);
  gpucol_sub3(a[2], a[0], r);
  const double pA2 = gpucol_dot3(u, r);
  gpucol_sub3(b[0], a[0], r);
  const double pB0 = gpucol_dot3(u, r);
  gpucol_sub3(b[1], a[0], r);
  const double pB1 = gpucol_dot3(u, r);
  gpucol_sub3(b[2], a[0], r);
  const double pB2 = gpucol_dot3(u, r);
  const double slide =
      gpucol_min_d(gpucol_max_d(gpucol_max_d(0.0, pA1), pA2) - gpucol_min_d(gpucol_min_d(pB0, pB1), pB2),
                   gpucol_max_d(gpucol_max_d(pB0, pB1), pB2) - gpucol_min_d(gpucol_min_d(0.0, pA1), pA2));
  if (slide < move) return out;

  /* The common segment of the two crossings on L; its midpoint lies on both triangles. The moving triangle's
     deepest vertex is the one its move is measured from. 0 - 0 is +0: touching contacts do not print as -0.
   */
  const double* low = lowA[axis] >= lowB[axis] ? lowA : lowB;
  const double* high = highA[axis] <= highB[axis] ? highA : highB;
  const double* d = aMoves ? dA : dB;
  const int deepest = d[0] <= d[1] ? (d[0] <= d[2] ? 0 : 2) : (d[1] <= d[2] ? 1 : 2);
  for (int k = 0; k < 3; ++k) {
    out.point[k] = 0.5 * (low[k] + high[k]);
    out.normalOnB[k] = aMoves ? nB[k] : -nA[k];
    out.deepest[k] = aMoves ? a[deepest][k] : b[deepest][k];
  }
  out.depth = 0.0 - move;
  out.onFaceOfB = aMoves;
  out.sameFacing = gpucol_dot3(nA, nB) > 0;
  out.contact = 1;
  return out;
}

#endif /* GPUCOL_SHARED_MATH_TRIANGLE_TEST_H */
