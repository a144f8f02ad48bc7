// Near phase of the mesh pipeline on the device (thesis §5.4.1): one work-item per candidate triangle pair of
// the whole batch, Möller's test and the contact generation of §5.3.4 in one kernel, then a compaction of the
// intersecting pairs by the scanned flags (scan.cl).
//
// It is plugin/src/narrowphase/triangle_contact.cpp (generateContactAndTest, with triangle_plane.h and
// coplanar_triangles.cpp) written again in OpenCL C: double arithmetic on the float input (cl_khr_fp64, which
// the host checks), the same operations in the same order and no contraction, so the device decides every
// pair as the CPU does and its contacts carry the same bits up to the final float rounding. The triangles are
// built in A's scaled frame as plugin/src/bullet/collide_meshes.cpp builds them (triangleOfA, triangleOfB).
//
// The early-out is a stage of its own (mesh_near_prefilter): the float plane and interval tests of
// triangle_plane.h (floatCertainlyApartBranchFree, floatIntervalsApartBranchFree, their error bounds proven
// there), straight-line code that a CPU device runs as vector code across work-items, then a compaction by
// scan, and the double test only on the survivors. Without it every candidate takes the double path, as the
// thesis's GPU kernel took every candidate through contact generation.
#include "opencl/shared/mesh_pipeline_types.h"

#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

// Helpers of the early-out are always inlined: a call left in the work-item loop stops a CPU device's
// vectorisation across work-items (PoCL's inliner judged them too costly).
#define GPUCOL_INLINE __attribute__((always_inline))

// triangle_plane.h: kDegenerateSin2, kSnapRelative, kFloatSideMargin and its factor range.
#define DEGENERATE_SIN2 1e-12
#define SNAP_RELATIVE 1e-12
#define FLOAT_SIDE_MARGIN (64.0f / 16777216.0f)
#define FLOAT_SIDE_MIN_FACTOR 0x1p-40f
#define FLOAT_SIDE_MAX_FACTOR 0x1p40f
// triangle_plane.h: kFloatIntervalMinFactor, kFloatIntervalMaxFactor, kFloatLineMinimum.
#define FLOAT_INTERVAL_MIN_FACTOR 0x1p-20f
#define FLOAT_INTERVAL_MAX_FACTOR 0x1p20f
#define FLOAT_LINE_MINIMUM 0x1p-10f

typedef struct V3 {
  double x[3];
} V3;

V3 v3_sub(V3 a, V3 b) {
  V3 r;
  for (int i = 0; i < 3; ++i) r.x[i] = a.x[i] - b.x[i];
  return r;
}

// Eigen's cross product, component by component.
V3 v3_cross(V3 a, V3 b) {
  V3 r;
  r.x[0] = a.x[1] * b.x[2] - a.x[2] * b.x[1];
  r.x[1] = a.x[2] * b.x[0] - a.x[0] * b.x[2];
  r.x[2] = a.x[0] * b.x[1] - a.x[1] * b.x[0];
  return r;
}

// Eigen's order for a dot product of 3 doubles (measured: its vectorised sum adds the first two terms first).
double v3_dot(V3 a, V3 b) {
  return (a.x[0] * b.x[0] + a.x[1] * b.x[1]) + a.x[2] * b.x[2];
}

double v3_max_abs(V3 a) {
  return fmax(fmax(fabs(a.x[0]), fabs(a.x[1])), fabs(a.x[2]));
}

// triangle_plane.h TrianglePlane / makePlane.
typedef struct Plane {
  V3 origin;
  V3 normal;
  double errorScale;
  bool degenerate;
} Plane;

Plane make_plane(V3 v0, V3 v1, V3 v2) {
  const V3 e1 = v3_sub(v1, v0);
  const V3 e2 = v3_sub(v2, v0);
  Plane plane;
  plane.origin = v0;
  plane.normal = v3_cross(e1, e2);
  plane.errorScale = v3_max_abs(e1) * v3_max_abs(e2);
  plane.degenerate =
      !(v3_dot(plane.normal, plane.normal) > DEGENERATE_SIN2 * v3_dot(e1, e1) * v3_dot(e2, e2));
  return plane;
}

void signed_distances(const Plane* plane, V3 q0, V3 q1, V3 q2, double* d) {
  const V3 r0 = v3_sub(q0, plane->origin);
  const V3 r1 = v3_sub(q1, plane->origin);
  const V3 r2 = v3_sub(q2, plane->origin);
  d[0] = v3_dot(plane->normal, r0);
  d[1] = v3_dot(plane->normal, r1);
  d[2] = v3_dot(plane->normal, r2);
  const double extent = fmax(fmax(v3_max_abs(r0), v3_max_abs(r1)), v3_max_abs(r2));
  const double tolerance = SNAP_RELATIVE * plane->errorScale * extent;
  for (int i = 0; i < 3; ++i) d[i] = fabs(d[i]) <= tolerance ? 0.0 : d[i];
}

bool same_strict_sign(double x, double y) {
  return (x > 0.0 && y > 0.0) || (x < 0.0 && y < 0.0);
}
bool all_on_one_side(const double* d) {
  return same_strict_sign(d[0], d[1]) && same_strict_sign(d[0], d[2]);
}
bool all_in_plane(const double* d) {
  return d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0;
}

int lone_vertex(const double* d) {
  if (same_strict_sign(d[0], d[1])) return 2;
  if (same_strict_sign(d[0], d[2])) return 1;
  if (same_strict_sign(d[1], d[2]) || d[0] != 0.0) return 0;
  if (d[1] != 0.0) return 1;
  return 2;
}

void plane_crossing(const V3* v, const double* d, V3* s0, V3* s1) {
  const int a = lone_vertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  const double tb = d[a] / (d[a] - d[b]);
  const double tc = d[a] / (d[a] - d[c]);
  for (int i = 0; i < 3; ++i) {
    s0->x[i] = v[a].x[i] + (v[b].x[i] - v[a].x[i]) * tb;
    s1->x[i] = v[a].x[i] + (v[c].x[i] - v[a].x[i]) * tc;
  }
}

int dominant_axis(V3 v) {
  const double x = fabs(v.x[0]), y = fabs(v.x[1]), z = fabs(v.x[2]);
  return x >= y ? (x >= z ? 0 : 2) : (y >= z ? 1 : 2);
}

double orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

bool straddles(double x, double y) {
  return (x <= 0.0 && y >= 0.0) || (x >= 0.0 && y <= 0.0);
}

bool inside_or_on(const double* tx, const double* ty, double px, double py) {
  const double o0 = orient2d(tx[0], ty[0], tx[1], ty[1], px, py);
  const double o1 = orient2d(tx[1], ty[1], tx[2], ty[2], px, py);
  const double o2 = orient2d(tx[2], ty[2], tx[0], ty[0], px, py);
  return (o0 >= 0.0 && o1 >= 0.0 && o2 >= 0.0) || (o0 <= 0.0 && o1 <= 0.0 && o2 <= 0.0);
}

// coplanar_triangles.cpp with the point: the mean of the overlap polygon's corners.
bool coplanar_overlap(const V3* a, const V3* b, int dropAxis, V3* point) {
  const int u = dropAxis == 0 ? 1 : 0;
  const int v = dropAxis == 2 ? 1 : 2;
  double ax[3], ay[3], bx[3], by[3];
  for (int i = 0; i < 3; ++i) {
    ax[i] = a[i].x[u];
    ay[i] = a[i].x[v];
    bx[i] = b[i].x[u];
    by[i] = b[i].x[v];
  }
  V3 sum;
  sum.x[0] = sum.x[1] = sum.x[2] = 0.0;
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const int i1 = i == 2 ? 0 : i + 1;
    for (int j = 0; j < 3; ++j) {
      const int j1 = j == 2 ? 0 : j + 1;
      const double o1 = orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j], by[j]);
      const double o2 = orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j1], by[j1]);
      if (!straddles(o1, o2) || (o1 == 0.0 && o2 == 0.0)) continue;
      const double o3 = orient2d(bx[j], by[j], bx[j1], by[j1], ax[i], ay[i]);
      const double o4 = orient2d(bx[j], by[j], bx[j1], by[j1], ax[i1], ay[i1]);
      // Both zero (they straddle) puts a's edge on b's line: collinear edges, or by rounding an edge far
      // shorter than the other triangle (a needle 1e-44 wide gave 0 / 0 = NaN). The containment tests below
      // find the endpoints that matter, as coplanar_triangles.cpp does since 4429c70.
      if (!straddles(o3, o4) || o3 == o4) continue;
      const double t = o3 / (o3 - o4);
      for (int k = 0; k < 3; ++k) sum.x[k] += a[i].x[k] + (a[i1].x[k] - a[i].x[k]) * t;
      ++count;
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (inside_or_on(bx, by, ax[i], ay[i])) {
      for (int k = 0; k < 3; ++k) sum.x[k] += a[i].x[k];
      ++count;
    }
    if (inside_or_on(ax, ay, bx[i], by[i])) {
      for (int k = 0; k < 3; ++k) sum.x[k] += b[i].x[k];
      ++count;
    }
  }
  if (count == 0) return false;
  for (int k = 0; k < 3; ++k) point->x[k] = sum.x[k] / (double)count;
  return true;
}

// Vertex of a mesh from the arena.
GPUCOL_INLINE void mesh_vertex(__global const float* vertices, uint firstVertex, uint vertex, float* out) {
  __global const float* p = vertices + 3u * (firstVertex + vertex);
  out[0] = p[0];
  out[1] = p[1];
  out[2] = p[2];
}

// The triangles of candidate `key` in A's scaled frame, in float, as collide_meshes.cpp builds them. Its
// loops are unrolled: left as loops, PoCL vectorised them (two floats wide) inside each work-item, and the
// loop over the work-items, no longer innermost, stayed scalar.
GPUCOL_INLINE void mesh_candidate_triangles(__global const GpucolMeshPair* pairs,
                                            __global const float* vertices, __global const uint* indices,
                                            const ulong key, const uint bitsA, const uint bitsB,
                                            float af[3][3], float bf[3][3]) {
  const uint pair = (uint)(key >> (bitsA + bitsB));
  const uint triangleA = (uint)((key >> bitsB) & ((1ul << bitsA) - 1ul));
  const uint triangleB = (uint)(key & ((1ul << bitsB) - 1ul));
  __global const GpucolMeshPair* p = pairs + pair;
  __global const uint* cornerA = indices + 3u * (p->trianglesA + triangleA);
  __global const uint* cornerB = indices + 3u * (p->trianglesB + triangleB);
#pragma unroll
  for (int c = 0; c < 3; ++c) {
    float v[3];
    mesh_vertex(vertices, p->verticesA, cornerA[c], v);
#pragma unroll
    for (int k = 0; k < 3; ++k) af[c][k] = p->scaleA[k] * v[k];
    mesh_vertex(vertices, p->verticesB, cornerB[c], v);
#pragma unroll
    for (int k = 0; k < 3; ++k) {
      // Eigen's order for a 3x3 float matrix times a vector (its unrolled sum pairs the last two terms
      // first).
      bf[c][k] = (p->bLinear[3 * k] * v[0] + (p->bLinear[3 * k + 1] * v[1] + p->bLinear[3 * k + 2] * v[2])) +
                 p->bTranslation[k];
    }
  }
  // Mirrored scalings swap vertices 1 and 2 (selects rather than branches: the prefilter stays vector code).
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

// The early-out works on F3 values, plain structs of three floats rather than F3 or arrays: a CPU device
// vectorises the kernel across work-items only when every value is a scalar it can widen (LLVM's loop
// vectoriser refuses F3 operations, and arrays picked by a select stay in memory).
typedef struct F3 {
  float x, y, z;
} F3;
GPUCOL_INLINE F3 f3(float x, float y, float z) {
  F3 r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
GPUCOL_INLINE F3 f3_sub(F3 a, F3 b) {
  return f3(a.x - b.x, a.y - b.y, a.z - b.z);
}
GPUCOL_INLINE F3 f3_cross(F3 a, F3 b) {
  return f3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
GPUCOL_INLINE float f3_dot(F3 a, F3 b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}
GPUCOL_INLINE float f3_max_abs(F3 v) {
  return fmax(fmax(fabs(v.x), fabs(v.y)), fabs(v.z));
}
// v's coordinate on the axis picked by useX / useY (else z), with scalar selects.
GPUCOL_INLINE float f3_axis(F3 v, bool useX, bool useY) {
  return useX ? v.x : (useY ? v.y : v.z);
}
GPUCOL_INLINE bool f3_interval_factor(float x) {
  return (x >= FLOAT_INTERVAL_MIN_FACTOR) & (x <= FLOAT_INTERVAL_MAX_FACTOR);
}

// triangle_plane.h floatPlaneSide of q0, q1, q2 against the plane of (v0, v1, v2), on F3 values.
GPUCOL_INLINE uint f3_plane_side(F3 v0, F3 v1, F3 v2, F3 q0, F3 q1, F3 q2) {
  const F3 e1 = f3_sub(v1, v0), e2 = f3_sub(v2, v0);
  const F3 n = f3_cross(e1, e2);
  const float edge1 = f3_max_abs(e1), edge2 = f3_max_abs(e2);
  const F3 r0 = f3_sub(q0, v0), r1 = f3_sub(q1, v0), r2 = f3_sub(q2, v0);
  const float d0 = f3_dot(n, r0), d1 = f3_dot(n, r1), d2 = f3_dot(n, r2);
  const float extent = fmax(fmax(f3_max_abs(r0), f3_max_abs(r1)), f3_max_abs(r2));
  const bool inRange = (edge1 >= FLOAT_SIDE_MIN_FACTOR) & (edge1 <= FLOAT_SIDE_MAX_FACTOR) &
                       (edge2 >= FLOAT_SIDE_MIN_FACTOR) & (edge2 <= FLOAT_SIDE_MAX_FACTOR) &
                       (extent >= FLOAT_SIDE_MIN_FACTOR) & (extent <= FLOAT_SIDE_MAX_FACTOR);
  const float m = FLOAT_SIDE_MARGIN * edge1 * edge2 * extent;
  const bool above = (d0 > m) & (d1 > m) & (d2 > m);
  const bool below = (d0 < -m) & (d1 < -m) & (d2 < -m);
  const bool off = (fabs(d0) > m) | (fabs(d1) > m) | (fabs(d2) > m);
  return (inRange & (above | below) ? 1u : 0u) | (inRange & off ? 2u : 0u);
}

// One triangle's interval on the line's axis (coordinates p, distances d to the other plane, margin m) and
// the bound on its endpoints' error: floatIntervalsApartBranchFree's `interval`. Its two reciprocals are
// taken in double and rounded to float: OpenCL allows a float division 2.5 ulp of error, the proof counts on
// about one.
GPUCOL_INLINE F3 f3_interval(F3 p, F3 d, float m, float edges, float largest) {
  const float u = 1.0f / 16777216.0f;
  const bool lone2 = (d.x > 0) == (d.y > 0), lone1 = !lone2 & ((d.x > 0) == (d.z > 0));
  const float dLone = lone2 ? d.z : (lone1 ? d.y : d.x);
  const float pLone = lone2 ? p.z : (lone1 ? p.y : p.x);
  const float dNext = lone2 ? d.x : (lone1 ? d.z : d.y);
  const float pNext = lone2 ? p.x : (lone1 ? p.z : p.y);
  const float dLast = lone2 ? d.y : (lone1 ? d.x : d.z);
  const float pLast = lone2 ? p.y : (lone1 ? p.x : p.z);
  const float inverse1 = (float)(1.0 / (double)(dLone - dNext));
  const float inverse2 = (float)(1.0 / (double)(dLone - dLast));
  const float t1 = pLone + (pNext - pLone) * (dLone * inverse1);
  const float t2 = pLone + (pLast - pLone) * (dLone * inverse2);
  const float inverseSmallest = fmax(fabs(inverse1), fabs(inverse2));
  return f3(fmin(t1, t2), fmax(t1, t2), edges * (4.0f * m * inverseSmallest + 8.0f * u) + 4.0f * u * largest);
}

// triangle_plane.h floatIntervalsApartBranchFree, the same expressions (its proof bounds every rounding, so
// the order of a sum does not matter; selects stand for its selectFloat).
GPUCOL_INLINE uint f3_intervals_apart(F3 a0, F3 a1, F3 a2, F3 b0, F3 b1, F3 b2) {
  const F3 e1 = f3_sub(a1, a0), e2 = f3_sub(a2, a0), f1 = f3_sub(b1, b0), f2 = f3_sub(b2, b0);
  const F3 nA = f3_cross(e1, e2), nB = f3_cross(f1, f2);
  const float ea1 = f3_max_abs(e1), ea2 = f3_max_abs(e2), eb1 = f3_max_abs(f1), eb2 = f3_max_abs(f2);
  const F3 rb0 = f3_sub(b0, a0), rb1 = f3_sub(b1, a0), rb2 = f3_sub(b2, a0);
  const F3 ra0 = f3_sub(a0, b0), ra1 = f3_sub(a1, b0), ra2 = f3_sub(a2, b0);
  const F3 dB = f3(f3_dot(nA, rb0), f3_dot(nA, rb1), f3_dot(nA, rb2));
  const F3 dA = f3(f3_dot(nB, ra0), f3_dot(nB, ra1), f3_dot(nB, ra2));
  const float extentB = fmax(fmax(f3_max_abs(rb0), f3_max_abs(rb1)), f3_max_abs(rb2));
  const float extentA = fmax(fmax(f3_max_abs(ra0), f3_max_abs(ra1)), f3_max_abs(ra2));
  const float mB = FLOAT_SIDE_MARGIN * ea1 * ea2 * extentB;
  const float mA = FLOAT_SIDE_MARGIN * eb1 * eb2 * extentA;
  bool valid = f3_interval_factor(ea1) & f3_interval_factor(ea2) & f3_interval_factor(eb1) &
               f3_interval_factor(eb2) & f3_interval_factor(extentA) & f3_interval_factor(extentB);
  valid &= (fabs(dB.x) > 2.0f * mB) & (fabs(dB.y) > 2.0f * mB) & (fabs(dB.z) > 2.0f * mB);
  valid &= (fabs(dA.x) > 2.0f * mA) & (fabs(dA.y) > 2.0f * mA) & (fabs(dA.z) > 2.0f * mA);
  valid &= !((dB.x > 0) & (dB.y > 0) & (dB.z > 0)) & !((dB.x < 0) & (dB.y < 0) & (dB.z < 0));
  valid &= !((dA.x > 0) & (dA.y > 0) & (dA.z > 0)) & !((dA.x < 0) & (dA.y < 0) & (dA.z < 0));

  const F3 direction = f3_cross(nA, nB);
  const float dx = fabs(direction.x), dy = fabs(direction.y), dz = fabs(direction.z);
  const bool useX = (dx >= dy) & (dx >= dz), useY = !useX & (dy >= dz);
  valid &= fmax(fmax(dx, dy), dz) >= FLOAT_LINE_MINIMUM * (ea1 * ea2) * (eb1 * eb2);

  const float largest = fmax(fmax(fmax(f3_max_abs(a0), f3_max_abs(a1)), fmax(f3_max_abs(a2), f3_max_abs(b0))),
                             fmax(f3_max_abs(b1), f3_max_abs(b2)));
  const float edgesA = fmax(fmax(ea1, ea2), f3_max_abs(f3_sub(a2, a1)));
  const float edgesB = fmax(fmax(eb1, eb2), f3_max_abs(f3_sub(b2, b1)));
  // Component by component: a select of whole F3 values became branches and a phi of <2 x float> (the ABI's
  // form of a returned F3), which kept PoCL's work-item loop scalar ("instruction return type cannot be
  // vectorized", "control flow cannot be substituted for a select").
  const F3 pA = f3(f3_axis(a0, useX, useY), f3_axis(a1, useX, useY), f3_axis(a2, useX, useY));
  const F3 pB = f3(f3_axis(b0, useX, useY), f3_axis(b1, useX, useY), f3_axis(b2, useX, useY));
  const F3 iA = f3_interval(pA, dA, mA, edgesA, largest);
  const F3 iB = f3_interval(pB, dB, mB, edgesB, largest);
  const float tolerance = 2.0f * (iA.z + iB.z);
  return (valid & ((iA.x > iB.y + tolerance) | (iB.x > iA.y + tolerance))) ? 1u : 0u;
}

// The early-out stage: survives[i] = 0 when float arithmetic proves candidate i's triangles apart as the
// double test would find them (floatCertainlyApartBranchFree, then floatIntervalsApartBranchFree), else 1.
// Both tests always run, and there is no bounds test either (the work-items past n repeat the last candidate
// into the padding of `survives`, which holds the launch's global size): no branch, so that a CPU device
// makes vector code of it.
__kernel void mesh_near_prefilter(__global const GpucolMeshPair* restrict pairs,
                                  __global const float* restrict vertices,
                                  __global const uint* restrict indices, __global const ulong* restrict keys,
                                  const uint n, const uint bitsA, const uint bitsB,
                                  __global uint* restrict survives) {
  const uint item = get_global_id(0);
  float af[3][3], bf[3][3];
  mesh_candidate_triangles(pairs, vertices, indices, keys[min(item, n - 1u)], bitsA, bitsB, af, bf);
  const F3 a0 = f3(af[0][0], af[0][1], af[0][2]), a1 = f3(af[1][0], af[1][1], af[1][2]),
           a2 = f3(af[2][0], af[2][1], af[2][2]);
  const F3 b0 = f3(bf[0][0], bf[0][1], bf[0][2]), b1 = f3(bf[1][0], bf[1][1], bf[1][2]),
           b2 = f3(bf[2][0], bf[2][1], bf[2][2]);
  const uint sideB = f3_plane_side(a0, a1, a2, b0, b1, b2);
  const uint sideA = f3_plane_side(b0, b1, b2, a0, a1, a2);
  const uint planesApart = (sideB | ((sideB >> 1) & sideA)) & 1u;
  survives[item] = 1u - (planesApart | f3_intervals_apart(a0, a1, a2, b0, b1, b2));
}

// The survivors' candidate indices in candidate order: `offsets` is the exclusive scan of
// mesh_near_prefilter's flags (`total` their sum), so candidate i survived when the next offset is larger.
__kernel void mesh_near_gather(__global const uint* offsets, const uint n, const uint total,
                               __global uint* survivors) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  const uint next = i + 1u < n ? offsets[i + 1u] : total;
  if (next != offsets[i]) survivors[offsets[i]] = i;
}

// One candidate (the list's j-th when `useList`, else the j-th): its hit record, with GPUCOL_HIT_INTERSECTS
// in the flags when the triangles intersect.
__kernel void mesh_near_test(__global const GpucolMeshPair* pairs, __global const float* vertices,
                             __global const uint* indices, __global const ulong* keys,
                             __global const uint* list, const uint useList, const uint n, const uint bitsA,
                             const uint bitsB, __global GpucolNearHit* hits) {
  const uint j = get_global_id(0);
  if (j >= n) return;
  const uint i = useList ? list[j] : j;
  float af[3][3], bf[3][3];
  mesh_candidate_triangles(pairs, vertices, indices, keys[i], bitsA, bitsB, af, bf);

  GpucolNearHit hit;
  hit.candidate = i;
  hit.flags = 0u;
  for (int k = 0; k < 3; ++k) hit.point[k] = hit.normal[k] = hit.deepest[k] = 0.0f;
  hit.depth = 0.0f;

  V3 a[3], b[3];
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 3; ++k) {
      a[c].x[k] = (double)af[c][k];
      b[c].x[k] = (double)bf[c][k];
    }
  }
  bool intersects = false;
  bool contact = false;
  V3 point, normalOnB, deepest;
  double depth = 0.0;
  bool onFaceOfB = true, sameFacing = false;
  do {
    const Plane planeA = make_plane(a[0], a[1], a[2]);
    if (planeA.degenerate) break;
    double dB[3];
    signed_distances(&planeA, b[0], b[1], b[2], dB);
    if (all_on_one_side(dB)) break;
    const Plane planeB = make_plane(b[0], b[1], b[2]);
    if (planeB.degenerate) break;
    double dA[3];
    signed_distances(&planeB, a[0], a[1], a[2], dA);
    if (all_on_one_side(dA)) break;

    const double lengthA = sqrt(v3_dot(planeA.normal, planeA.normal));
    const double lengthB = sqrt(v3_dot(planeB.normal, planeB.normal));
    V3 nA, nB;
    for (int k = 0; k < 3; ++k) {
      nA.x[k] = planeA.normal.x[k] / lengthA;
      nB.x[k] = planeB.normal.x[k] / lengthB;
    }
    const bool coplanarB = all_in_plane(dB);
    if (coplanarB || all_in_plane(dA)) {
      const int dropAxis = dominant_axis(coplanarB ? planeA.normal : planeB.normal);
      if (!coplanar_overlap(a, b, dropAxis, &point)) break;
      intersects = true;
      if (v3_dot(nA, nB) > 0) break;
      contact = true;
      normalOnB = nB;
      depth = 0.0;
      onFaceOfB = true;
      sameFacing = false;
      deepest = point;
      break;
    }

    const V3 lineDirection = v3_cross(planeA.normal, planeB.normal);
    const int axis = dominant_axis(lineDirection);
    V3 sA[2], sB[2];
    plane_crossing(a, dA, &sA[0], &sA[1]);
    plane_crossing(b, dB, &sB[0], &sB[1]);
    if (sA[1].x[axis] < sA[0].x[axis]) {
      const V3 t = sA[0];
      sA[0] = sA[1];
      sA[1] = t;
    }
    if (sB[1].x[axis] < sB[0].x[axis]) {
      const V3 t = sB[0];
      sB[0] = sB[1];
      sB[1] = t;
    }
    if (sA[0].x[axis] > sB[1].x[axis] || sB[0].x[axis] > sA[1].x[axis]) break;
    intersects = true;

    const double moveA = fmax(0.0, -fmin(fmin(dA[0], dA[1]), dA[2]) / lengthB);
    const double moveB = fmax(0.0, -fmin(fmin(dB[0], dB[1]), dB[2]) / lengthA);
    const bool aMoves = moveA <= moveB;
    const double move = aMoves ? moveA : moveB;

    const double lineLength = sqrt(v3_dot(lineDirection, lineDirection));
    V3 u;
    for (int k = 0; k < 3; ++k) u.x[k] = lineDirection.x[k] / lineLength;
    const double pA1 = v3_dot(u, v3_sub(a[1], a[0])), pA2 = v3_dot(u, v3_sub(a[2], a[0]));
    const double pB0 = v3_dot(u, v3_sub(b[0], a[0])), pB1 = v3_dot(u, v3_sub(b[1], a[0])),
                 pB2 = v3_dot(u, v3_sub(b[2], a[0]));
    const double slide = fmin(fmax(fmax(0.0, pA1), pA2) - fmin(fmin(pB0, pB1), pB2),
                              fmax(fmax(pB0, pB1), pB2) - fmin(fmin(0.0, pA1), pA2));
    if (slide < move) break;

    const V3 low = sA[0].x[axis] >= sB[0].x[axis] ? sA[0] : sB[0];
    const V3 high = sA[1].x[axis] <= sB[1].x[axis] ? sA[1] : sB[1];
    for (int k = 0; k < 3; ++k) {
      point.x[k] = 0.5 * (low.x[k] + high.x[k]);
      normalOnB.x[k] = aMoves ? nB.x[k] : -nA.x[k];
    }
    const double* d = aMoves ? dA : dB;
    const int deepestIndex = d[0] <= d[1] ? (d[0] <= d[2] ? 0 : 2) : (d[1] <= d[2] ? 1 : 2);
    deepest = aMoves ? a[deepestIndex] : b[deepestIndex];
    depth = 0.0 - move;
    onFaceOfB = aMoves;
    sameFacing = v3_dot(nA, nB) > 0;
    contact = true;
  } while (false);

  if (intersects) {
    hit.flags = GPUCOL_HIT_INTERSECTS;
    if (contact) {
      hit.flags |= GPUCOL_HIT_CONTACT | (onFaceOfB ? GPUCOL_HIT_ON_FACE_OF_B : 0u) |
                   (sameFacing ? GPUCOL_HIT_SAME_FACING : 0u);
      for (int k = 0; k < 3; ++k) {
        hit.point[k] = (float)point.x[k];
        hit.normal[k] = (float)normalOnB.x[k];
        hit.deepest[k] = (float)deepest.x[k];
      }
      hit.depth = (float)depth;
    }
  }
  hits[j] = hit;
}
