// Near phase of the mesh pipeline on the device (thesis §5.4.1): every candidate triangle pair of the whole
// batch in one kernel, Möller's test and the contact generation of §5.3.4, the intersecting pairs' records
// appended at an atomic counter.
//
// It is plugin/src/narrowphase/triangle_contact.cpp (generateContactAndTest, with triangle_plane.h and
// coplanar_triangles.cpp) written again in OpenCL C: double arithmetic on the float input (cl_khr_fp64, which
// the host checks), the same operations in the same order and no contraction, so the device decides every
// pair as the CPU does and its contacts carry the same bits up to the final float rounding. The triangles are
// built in A's scaled frame as plugin/src/bullet/collide_meshes.cpp builds them (triangleOfA, triangleOfB).
//
// The early-out (mesh_near_filter_test) comes first in the same kernel: the float plane and interval tests of
// triangle_plane.h (floatCertainlyApartBranchFree, floatIntervalsApartBranchFree, their error bounds proven
// there), straight-line code on vector lanes, several candidates per work-item, and the double test only on
// the survivors, four at a time in double4 lanes (mesh_near_lanes4). Without it (mesh_near_test) every candidate takes the double path, as the thesis's GPU
// kernel took every candidate through contact generation.
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

// Corner c of triangle `triangle` in the triangle soup arena (mesh_device_cache.h: 9 floats per triangle).
GPUCOL_INLINE void mesh_corner(__global const float* soup, uint triangle, int c, float* out) {
  __global const float* p = soup + 9u * triangle + 3 * c;
  out[0] = p[0];
  out[1] = p[1];
  out[2] = p[2];
}

// Triangles triangleA of A and triangleB of B of pair `p` (a private copy) in A's scaled frame, in float, as
// collide_meshes.cpp builds them. Its loops are unrolled: left as loops, PoCL vectorised them (two floats
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
      // Eigen's order for a 3x3 float matrix times a vector (its unrolled sum pairs the last two terms
      // first).
      bf[c][k] = (p->bLinear[3 * k] * v[0] + (p->bLinear[3 * k + 1] * v[1] + p->bLinear[3 * k + 2] * v[2])) +
                 p->bTranslation[k];
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
#if GPUCOL_LANES == 4
typedef float4 FloatLanes;
typedef int4 BoolLanes;  // -1 true, 0 false, as vector comparisons give
#define GPUCOL_LOAD_LANES(p) vload4(0, p)
#define GPUCOL_DOUBLE_LANES(x) convert_double4(x)
#define GPUCOL_FLOAT_LANES(x) convert_float4(x)
#define GPUCOL_STORE_LANES(v, i, p) vstore4(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint4(x)
#elif GPUCOL_LANES == 8
typedef float8 FloatLanes;
typedef int8 BoolLanes;
#define GPUCOL_LOAD_LANES(p) vload8(0, p)
#define GPUCOL_DOUBLE_LANES(x) convert_double8(x)
#define GPUCOL_FLOAT_LANES(x) convert_float8(x)
#define GPUCOL_STORE_LANES(v, i, p) vstore8(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint8(x)
#elif GPUCOL_LANES == 16
typedef float16 FloatLanes;
typedef int16 BoolLanes;
#define GPUCOL_LOAD_LANES(p) vload16(0, p)
#define GPUCOL_DOUBLE_LANES(x) convert_double16(x)
#define GPUCOL_FLOAT_LANES(x) convert_float16(x)
#define GPUCOL_STORE_LANES(v, i, p) vstore16(v, i, p)
#define GPUCOL_UINT_LANES(x) as_uint16(x)
#else
#error "GPUCOL_LANES must be 4, 8 or 16"
#endif

// A point or vector per lane.
typedef struct L3 {
  FloatLanes x, y, z;
} L3;
GPUCOL_INLINE L3 l3(FloatLanes x, FloatLanes y, FloatLanes z) {
  L3 r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
GPUCOL_INLINE L3 l3_sub(L3 a, L3 b) {
  return l3(a.x - b.x, a.y - b.y, a.z - b.z);
}
GPUCOL_INLINE L3 l3_cross(L3 a, L3 b) {
  return l3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
GPUCOL_INLINE FloatLanes l3_dot(L3 a, L3 b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}
GPUCOL_INLINE FloatLanes l3_max_abs(L3 v) {
  return fmax(fmax(fabs(v.x), fabs(v.y)), fabs(v.z));
}
// v's coordinate on the axis picked by useX / useY (else z).
GPUCOL_INLINE FloatLanes l3_axis(L3 v, BoolLanes useX, BoolLanes useY) {
  return select(select(v.z, v.y, useY), v.x, useX);
}
GPUCOL_INLINE BoolLanes l3_interval_factor(FloatLanes x) {
  return (x >= FLOAT_INTERVAL_MIN_FACTOR) & (x <= FLOAT_INTERVAL_MAX_FACTOR);
}

// triangle_plane.h floatPlaneSide of q0, q1, q2 against the plane of (v0, v1, v2): `apart` when all three are
// certainly on one side, `off` when one certainly is off the plane.
GPUCOL_INLINE void l3_plane_side(L3 v0, L3 v1, L3 v2, L3 q0, L3 q1, L3 q2, BoolLanes* apart, BoolLanes* off) {
  const L3 e1 = l3_sub(v1, v0), e2 = l3_sub(v2, v0);
  const L3 n = l3_cross(e1, e2);
  const FloatLanes edge1 = l3_max_abs(e1), edge2 = l3_max_abs(e2);
  const L3 r0 = l3_sub(q0, v0), r1 = l3_sub(q1, v0), r2 = l3_sub(q2, v0);
  const FloatLanes d0 = l3_dot(n, r0), d1 = l3_dot(n, r1), d2 = l3_dot(n, r2);
  const FloatLanes extent = fmax(fmax(l3_max_abs(r0), l3_max_abs(r1)), l3_max_abs(r2));
  const BoolLanes inRange = (edge1 >= FLOAT_SIDE_MIN_FACTOR) & (edge1 <= FLOAT_SIDE_MAX_FACTOR) &
                            (edge2 >= FLOAT_SIDE_MIN_FACTOR) & (edge2 <= FLOAT_SIDE_MAX_FACTOR) &
                            (extent >= FLOAT_SIDE_MIN_FACTOR) & (extent <= FLOAT_SIDE_MAX_FACTOR);
  const FloatLanes m = FLOAT_SIDE_MARGIN * edge1 * edge2 * extent;
  const BoolLanes above = (d0 > m) & (d1 > m) & (d2 > m);
  const BoolLanes below = (d0 < -m) & (d1 < -m) & (d2 < -m);
  *apart = inRange & (above | below);
  *off = inRange & ((fabs(d0) > m) | (fabs(d1) > m) | (fabs(d2) > m));
}

// One triangle's interval on the line's axis (coordinates p, distances d to the other plane, margin m) and
// the bound on its endpoints' error: floatIntervalsApartBranchFree's `interval`, as (low, high, error). Its
// two reciprocals are taken in double and rounded to float: OpenCL allows a float division 2.5 ulp of error,
// the proof counts on about one.
GPUCOL_INLINE L3 l3_interval(L3 p, L3 d, FloatLanes m, FloatLanes edges, FloatLanes largest) {
  const float u = 1.0f / 16777216.0f;
  const BoolLanes lone2 = (d.x > 0) == (d.y > 0);
  const BoolLanes lone1 = ~lone2 & ((d.x > 0) == (d.z > 0));
  const FloatLanes dLone = select(select(d.x, d.y, lone1), d.z, lone2);
  const FloatLanes pLone = select(select(p.x, p.y, lone1), p.z, lone2);
  const FloatLanes dNext = select(select(d.y, d.z, lone1), d.x, lone2);
  const FloatLanes pNext = select(select(p.y, p.z, lone1), p.x, lone2);
  const FloatLanes dLast = select(select(d.z, d.x, lone1), d.y, lone2);
  const FloatLanes pLast = select(select(p.z, p.x, lone1), p.y, lone2);
  const FloatLanes inverse1 = GPUCOL_FLOAT_LANES(1.0 / GPUCOL_DOUBLE_LANES(dLone - dNext));
  const FloatLanes inverse2 = GPUCOL_FLOAT_LANES(1.0 / GPUCOL_DOUBLE_LANES(dLone - dLast));
  const FloatLanes t1 = pLone + (pNext - pLone) * (dLone * inverse1);
  const FloatLanes t2 = pLone + (pLast - pLone) * (dLone * inverse2);
  const FloatLanes inverseSmallest = fmax(fabs(inverse1), fabs(inverse2));
  return l3(fmin(t1, t2), fmax(t1, t2), edges * (4.0f * m * inverseSmallest + 8.0f * u) + 4.0f * u * largest);
}

// triangle_plane.h floatIntervalsApartBranchFree, the same expressions (its proof bounds every rounding, so
// the order of a sum does not matter; selects stand for its selectFloat).
GPUCOL_INLINE BoolLanes l3_intervals_apart(L3 a0, L3 a1, L3 a2, L3 b0, L3 b1, L3 b2) {
  const L3 e1 = l3_sub(a1, a0), e2 = l3_sub(a2, a0), f1 = l3_sub(b1, b0), f2 = l3_sub(b2, b0);
  const L3 nA = l3_cross(e1, e2), nB = l3_cross(f1, f2);
  const FloatLanes ea1 = l3_max_abs(e1), ea2 = l3_max_abs(e2), eb1 = l3_max_abs(f1), eb2 = l3_max_abs(f2);
  const L3 rb0 = l3_sub(b0, a0), rb1 = l3_sub(b1, a0), rb2 = l3_sub(b2, a0);
  const L3 ra0 = l3_sub(a0, b0), ra1 = l3_sub(a1, b0), ra2 = l3_sub(a2, b0);
  const L3 dB = l3(l3_dot(nA, rb0), l3_dot(nA, rb1), l3_dot(nA, rb2));
  const L3 dA = l3(l3_dot(nB, ra0), l3_dot(nB, ra1), l3_dot(nB, ra2));
  const FloatLanes extentB = fmax(fmax(l3_max_abs(rb0), l3_max_abs(rb1)), l3_max_abs(rb2));
  const FloatLanes extentA = fmax(fmax(l3_max_abs(ra0), l3_max_abs(ra1)), l3_max_abs(ra2));
  const FloatLanes mB = FLOAT_SIDE_MARGIN * ea1 * ea2 * extentB;
  const FloatLanes mA = FLOAT_SIDE_MARGIN * eb1 * eb2 * extentA;
  BoolLanes valid = l3_interval_factor(ea1) & l3_interval_factor(ea2) & l3_interval_factor(eb1) &
                    l3_interval_factor(eb2) & l3_interval_factor(extentA) & l3_interval_factor(extentB);
  valid &= (fabs(dB.x) > 2.0f * mB) & (fabs(dB.y) > 2.0f * mB) & (fabs(dB.z) > 2.0f * mB);
  valid &= (fabs(dA.x) > 2.0f * mA) & (fabs(dA.y) > 2.0f * mA) & (fabs(dA.z) > 2.0f * mA);
  valid &= ~((dB.x > 0) & (dB.y > 0) & (dB.z > 0)) & ~((dB.x < 0) & (dB.y < 0) & (dB.z < 0));
  valid &= ~((dA.x > 0) & (dA.y > 0) & (dA.z > 0)) & ~((dA.x < 0) & (dA.y < 0) & (dA.z < 0));

  const L3 direction = l3_cross(nA, nB);
  const FloatLanes dx = fabs(direction.x), dy = fabs(direction.y), dz = fabs(direction.z);
  const BoolLanes useX = (dx >= dy) & (dx >= dz), useY = ~useX & (dy >= dz);
  valid &= fmax(fmax(dx, dy), dz) >= FLOAT_LINE_MINIMUM * (ea1 * ea2) * (eb1 * eb2);

  const FloatLanes largest =
      fmax(fmax(fmax(l3_max_abs(a0), l3_max_abs(a1)), fmax(l3_max_abs(a2), l3_max_abs(b0))),
           fmax(l3_max_abs(b1), l3_max_abs(b2)));
  const FloatLanes edgesA = fmax(fmax(ea1, ea2), l3_max_abs(l3_sub(a2, a1)));
  const FloatLanes edgesB = fmax(fmax(eb1, eb2), l3_max_abs(l3_sub(b2, b1)));
  const L3 pA = l3(l3_axis(a0, useX, useY), l3_axis(a1, useX, useY), l3_axis(a2, useX, useY));
  const L3 pB = l3(l3_axis(b0, useX, useY), l3_axis(b1, useX, useY), l3_axis(b2, useX, useY));
  const L3 iA = l3_interval(pA, dA, mA, edgesA, largest);
  const L3 iB = l3_interval(pB, dB, mB, edgesB, largest);
  const FloatLanes tolerance = 2.0f * (iA.z + iB.z);
  return valid & ((iA.x > iB.y + tolerance) | (iB.x > iA.y + tolerance));
}

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
GPUCOL_INLINE BoolLanes mesh_prefilter_lanes(__global const GpucolMeshPair* restrict pairs,
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
  L3 t[6];
#pragma unroll
  for (int c = 0; c < 6; ++c) {
    t[c] = l3(GPUCOL_LOAD_LANES(corners[3 * c]), GPUCOL_LOAD_LANES(corners[3 * c + 1]),
              GPUCOL_LOAD_LANES(corners[3 * c + 2]));
  }
  BoolLanes apartB, offB, apartA, offA;
  l3_plane_side(t[0], t[1], t[2], t[3], t[4], t[5], &apartB, &offB);
  l3_plane_side(t[3], t[4], t[5], t[0], t[1], t[2], &apartA, &offA);
  return apartB | (offB & apartA) | l3_intervals_apart(t[0], t[1], t[2], t[3], t[4], t[5]);
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
// they intersect, and the contact.
GpucolNearHit mesh_near_hit(const float af[3][3], const float bf[3][3], uint candidate) {
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

  float values[10];
  if (intersects && contact) {
    for (int k = 0; k < 3; ++k) {
      values[k] = (float)point.x[k];
      values[3 + k] = (float)normalOnB.x[k];
      values[7 + k] = (float)deepest.x[k];
    }
    values[6] = (float)depth;
  }
  return mesh_hit_record(candidate, intersects, contact, onFaceOfB, sameFacing, values);
}

// The double test of four candidates at once, one per lane of double4: generateContactRows of
// plugin/src/narrowphase/contact_rows.cpp, its steps in its order. Each lane sees the same IEEE operations
// in the same order as mesh_near_hit (division and sqrt are correctly rounded in double, select() only moves
// bits), so the same results; choices are made by lane masks, never by branches. Coplanar pairs and pairs
// with a non-finite coordinate are left to mesh_near_hit (its early returns decide them). PoCL, thesis
// scene, 3 alternating rounds of 150 calls, median end to end against one survivor at a time through
// mesh_near_hit: one thread, armadillo-27674 0.95-0.97 ms against 1.11-1.13, -399904 3.54-4.31 against
// 4.33-4.84; two threads, -27674 0.73-0.97 against 0.80-1.08, -399904 2.12-2.54 against 2.58-3.18.
typedef struct V4 {
  double4 x, y, z;
} V4;

// c ? a : b lane by lane (by the sign bit of c's lanes, which comparisons set whole).
GPUCOL_INLINE double4 d4_pick(long4 c, double4 a, double4 b) {
  return select(b, a, c);
}
// std::min and std::max (the first where the comparison fails).
GPUCOL_INLINE double4 d4_min(double4 a, double4 b) {
  return d4_pick(b < a, b, a);
}
GPUCOL_INLINE double4 d4_max(double4 a, double4 b) {
  return d4_pick(a < b, b, a);
}
GPUCOL_INLINE V4 v4(double4 x, double4 y, double4 z) {
  V4 r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
GPUCOL_INLINE V4 v4_sub(V4 a, V4 b) {
  return v4(a.x - b.x, a.y - b.y, a.z - b.z);
}
GPUCOL_INLINE V4 v4_divide(V4 v, double4 s) {
  return v4(v.x / s, v.y / s, v.z / s);
}
GPUCOL_INLINE double4 v4_dot(V4 a, V4 b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}
GPUCOL_INLINE V4 v4_cross(V4 a, V4 b) {
  return v4(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
GPUCOL_INLINE double4 v4_max_abs(V4 v) {
  return d4_max(d4_max(fabs(v.x), fabs(v.y)), fabs(v.z));
}
GPUCOL_INLINE V4 v4_pick(long4 c, V4 a, V4 b) {
  return v4(d4_pick(c, a.x, b.x), d4_pick(c, a.y, b.y), d4_pick(c, a.z, b.z));
}
GPUCOL_INLINE long4 d4_same_sign(double4 x, double4 y) {
  return ((x > 0.0) & (y > 0.0)) | ((x < 0.0) & (y < 0.0));
}
// v's coordinate on the axis picked by onX / onY (else z).
GPUCOL_INLINE double4 v4_axis(V4 v, long4 onX, long4 onY) {
  return d4_pick(onX, v.x, d4_pick(onY, v.y, v.z));
}

// make_plane and signed_distances: the unnormalised normal of (p0, p1, p2), whether it is degenerate, and
// the snapped distances of q0, q1, q2 to its plane.
GPUCOL_INLINE void v4_plane_distances(V4 p0, V4 p1, V4 p2, V4 q0, V4 q1, V4 q2, V4* normal, long4* degenerate,
                                      double4* d) {
  const V4 e1 = v4_sub(p1, p0), e2 = v4_sub(p2, p0);
  *normal = v4_cross(e1, e2);
  const double4 errorScale = v4_max_abs(e1) * v4_max_abs(e2);
  *degenerate = ~(v4_dot(*normal, *normal) > DEGENERATE_SIN2 * v4_dot(e1, e1) * v4_dot(e2, e2));
  const V4 r0 = v4_sub(q0, p0), r1 = v4_sub(q1, p0), r2 = v4_sub(q2, p0);
  d[0] = v4_dot(*normal, r0);
  d[1] = v4_dot(*normal, r1);
  d[2] = v4_dot(*normal, r2);
  const double4 extent = d4_max(d4_max(v4_max_abs(r0), v4_max_abs(r1)), v4_max_abs(r2));
  const double4 tolerance = SNAP_RELATIVE * errorScale * extent;
  for (int i = 0; i < 3; ++i) d[i] = d4_pick(fabs(d[i]) <= tolerance, (double4)(0.0), d[i]);
}

// plane_crossing: the segment where (v0, v1, v2) meets the other plane, the lone vertex as lone_vertex picks.
GPUCOL_INLINE void v4_plane_crossing(V4 v0, V4 v1, V4 v2, const double4* d, V4* s0, V4* s1) {
  const long4 s01 = d4_same_sign(d[0], d[1]), s02 = d4_same_sign(d[0], d[2]);
  const long4 firstAlone = d4_same_sign(d[1], d[2]) | (d[0] != 0.0);
  const long4 zero = ~s01 & ~s02 & firstAlone;
  const long4 one = ~s01 & (s02 | (~firstAlone & (d[1] != 0.0)));
  const V4 va = v4_pick(zero, v0, v4_pick(one, v1, v2));
  const V4 vb = v4_pick(zero, v1, v4_pick(one, v2, v0));
  const V4 vc = v4_pick(zero, v2, v4_pick(one, v0, v1));
  const double4 da = d4_pick(zero, d[0], d4_pick(one, d[1], d[2]));
  const double4 db = d4_pick(zero, d[1], d4_pick(one, d[2], d[0]));
  const double4 dc = d4_pick(zero, d[2], d4_pick(one, d[0], d[1]));
  const double4 t0 = da / (da - db), t1 = da / (da - dc);
  const V4 ab = v4_sub(vb, va), ac = v4_sub(vc, va);
  *s0 = v4(va.x + ab.x * t0, va.y + ab.y * t0, va.z + ab.z * t0);
  *s1 = v4(va.x + ac.x * t1, va.y + ac.y * t1, va.z + ac.z * t1);
}

// What mesh_near_lanes4 found for its four pairs: lane masks, and the contact where `contact` holds.
typedef struct Near4 {
  long4 onePair;  // coplanar or non-finite: mesh_near_hit decides
  long4 intersects;
  long4 contact;  // intersecting with a kept contact
  long4 onFaceOfB;
  long4 sameFacing;
  V4 point, normal, deepest;
  double4 depth;
} Near4;

// The four pairs whose corners are t[0..5] (A's then B's vertices; A's scaled frame, as mesh_near_hit's).
GPUCOL_INLINE Near4 mesh_near_lanes4(const V4* t) {
  const V4 a0 = t[0], a1 = t[1], a2 = t[2], b0 = t[3], b1 = t[4], b2 = t[5];
  const double4 zero = (double4)(0.0);
  V4 normalA, normalB;
  long4 degenerateA, degenerateB;
  double4 dB[3], dA[3];
  v4_plane_distances(a0, a1, a2, b0, b1, b2, &normalA, &degenerateA, dB);
  v4_plane_distances(b0, b1, b2, a0, a1, a2, &normalB, &degenerateB, dA);
  const long4 rejected = degenerateA | (d4_same_sign(dB[0], dB[1]) & d4_same_sign(dB[0], dB[2])) |
                         degenerateB | (d4_same_sign(dA[0], dA[1]) & d4_same_sign(dA[0], dA[2]));
  const long4 coplanar = ((dB[0] == zero) & (dB[1] == zero) & (dB[2] == zero)) |
                         ((dA[0] == zero) & (dA[1] == zero) & (dA[2] == zero));
  // x - x is 0 for a finite x, NaN otherwise.
  double4 sum = zero;
  for (int c = 0; c < 6; ++c) {
    const V4 z = v4_sub(t[c], t[c]);
    sum += (z.x + z.y) + z.z;
  }
  const long4 finite = sum == zero;

  const double4 lengthA = sqrt(v4_dot(normalA, normalA));
  const double4 lengthB = sqrt(v4_dot(normalB, normalB));
  const V4 nA = v4_divide(normalA, lengthA);
  const V4 nB = v4_divide(normalB, lengthB);

  const V4 line = v4_cross(normalA, normalB);
  const double4 fx = fabs(line.x), fy = fabs(line.y), fz = fabs(line.z);
  const long4 onX = (fx >= fy) & (fx >= fz), onY = ~(fx >= fy) & (fy >= fz);
  V4 sA0, sA1, sB0, sB1;
  v4_plane_crossing(a0, a1, a2, dA, &sA0, &sA1);
  v4_plane_crossing(b0, b1, b2, dB, &sB0, &sB1);
  const long4 swapA = v4_axis(sA1, onX, onY) < v4_axis(sA0, onX, onY);
  const long4 swapB = v4_axis(sB1, onX, onY) < v4_axis(sB0, onX, onY);
  const V4 lowA = v4_pick(swapA, sA1, sA0), highA = v4_pick(swapA, sA0, sA1);
  const V4 lowB = v4_pick(swapB, sB1, sB0), highB = v4_pick(swapB, sB0, sB1);
  const double4 lowAOn = v4_axis(lowA, onX, onY), highAOn = v4_axis(highA, onX, onY);
  const double4 lowBOn = v4_axis(lowB, onX, onY), highBOn = v4_axis(highB, onX, onY);
  const long4 separated = (lowAOn > highBOn) | (lowBOn > highAOn);

  const double4 moveA = d4_max(zero, -d4_min(d4_min(dA[0], dA[1]), dA[2]) / lengthB);
  const double4 moveB = d4_max(zero, -d4_min(d4_min(dB[0], dB[1]), dB[2]) / lengthA);
  const long4 aMoves = moveA <= moveB;
  const double4 move = d4_pick(aMoves, moveA, moveB);

  const double4 lineSquared = v4_dot(line, line);
  const V4 u = v4_pick(lineSquared > zero, v4_divide(line, sqrt(lineSquared)), line);
  const double4 pA1 = v4_dot(u, v4_sub(a1, a0)), pA2 = v4_dot(u, v4_sub(a2, a0));
  const double4 pB0 = v4_dot(u, v4_sub(b0, a0)), pB1 = v4_dot(u, v4_sub(b1, a0)),
                pB2 = v4_dot(u, v4_sub(b2, a0));
  const double4 slide = d4_min(d4_max(d4_max(zero, pA1), pA2) - d4_min(d4_min(pB0, pB1), pB2),
                               d4_max(d4_max(pB0, pB1), pB2) - d4_min(d4_min(zero, pA1), pA2));

  Near4 r;
  const V4 low = v4_pick(lowAOn >= lowBOn, lowA, lowB);
  const V4 high = v4_pick(highAOn <= highBOn, highA, highB);
  r.point = v4(0.5 * (low.x + high.x), 0.5 * (low.y + high.y), 0.5 * (low.z + high.z));
  r.normal = v4_pick(aMoves, nB, v4(-nA.x, -nA.y, -nA.z));
  const double4 d0 = d4_pick(aMoves, dA[0], dB[0]), d1 = d4_pick(aMoves, dA[1], dB[1]),
                d2 = d4_pick(aMoves, dA[2], dB[2]);
  const long4 deepest0 = (d0 <= d1) & (d0 <= d2), deepest1 = ~(d0 <= d1) & (d1 <= d2);
  r.deepest = v4_pick(aMoves, v4_pick(deepest0, a0, v4_pick(deepest1, a1, a2)),
                      v4_pick(deepest0, b0, v4_pick(deepest1, b1, b2)));
  r.depth = zero - move;
  r.onePair = ~finite | (~rejected & coplanar);
  r.intersects = ~r.onePair & ~rejected & ~separated;
  r.contact = r.intersects & ~(slide < move);
  r.onFaceOfB = aMoves;
  r.sameFacing = v4_dot(nA, nB) > zero;
  return r;
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
  const BoolLanes apart =
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
  // The survivors four at a time through mesh_near_lanes4 (the free lanes of the last four repeat its last
  // survivor).
  for (uint group = 0u; group < survivors; group += 4u) {
    uint lane4[4];
    for (uint j = 0u; j < 4u; ++j) lane4[j] = survivor[min(group + j, survivors - 1u)];
    V4 t[6];
    for (int c = 0; c < 6; ++c) {
      double4 xyz[3];
      for (int k = 0; k < 3; ++k) {
        const int row = 3 * c + k;
        xyz[k] = (double4)((double)corners[row][lane4[0]], (double)corners[row][lane4[1]],
                           (double)corners[row][lane4[2]], (double)corners[row][lane4[3]]);
      }
      t[c] = v4(xyz[0], xyz[1], xyz[2]);
    }
    const Near4 r = mesh_near_lanes4(t);
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
