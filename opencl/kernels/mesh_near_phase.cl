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
// With -DGPUCOL_NEAR_PREFILTER the float plane test of triangle_plane.h (floatCertainlyApartBranchFree, its
// error bound proven there) runs first and skips the double test for pairs it proves apart; without it every
// candidate takes the double path, as the thesis's GPU kernel took every candidate through contact generation.
#include "opencl/shared/mesh_pipeline_types.h"

#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

#define GPUCOL_HIT_INTERSECTS 0x80000000u

// triangle_plane.h: kDegenerateSin2, kSnapRelative, kFloatSideMargin and its factor range.
#define DEGENERATE_SIN2 1e-12
#define SNAP_RELATIVE 1e-12
#define FLOAT_SIDE_MARGIN (64.0f / 16777216.0f)
#define FLOAT_SIDE_MIN_FACTOR 0x1p-40f
#define FLOAT_SIDE_MAX_FACTOR 0x1p40f

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
double v3_dot(V3 a, V3 b) { return (a.x[0] * b.x[0] + a.x[1] * b.x[1]) + a.x[2] * b.x[2]; }

double v3_max_abs(V3 a) { return fmax(fmax(fabs(a.x[0]), fabs(a.x[1])), fabs(a.x[2])); }

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
  plane.degenerate = !(v3_dot(plane.normal, plane.normal) > DEGENERATE_SIN2 * v3_dot(e1, e1) * v3_dot(e2, e2));
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

bool same_strict_sign(double x, double y) { return (x > 0.0 && y > 0.0) || (x < 0.0 && y < 0.0); }
bool all_on_one_side(const double* d) { return same_strict_sign(d[0], d[1]) && same_strict_sign(d[0], d[2]); }
bool all_in_plane(const double* d) { return d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0; }

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

bool straddles(double x, double y) { return (x <= 0.0 && y >= 0.0) || (x >= 0.0 && y <= 0.0); }

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
      if (!straddles(o3, o4)) continue;
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

// triangle_plane.h floatPlaneSide: bit 1 all on one side, bit 2 some off the plane, by a proven margin.
uint float_plane_side(const float* v0, const float* v1, const float* v2, const float* q0, const float* q1,
                      const float* q2) {
  float e1[3], e2[3], n[3], r[3][3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = v1[i] - v0[i];
    e2[i] = v2[i] - v0[i];
    r[0][i] = q0[i] - v0[i];
    r[1][i] = q1[i] - v0[i];
    r[2][i] = q2[i] - v0[i];
  }
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const float edge1 = fmax(fmax(fabs(e1[0]), fabs(e1[1])), fabs(e1[2]));
  const float edge2 = fmax(fmax(fabs(e2[0]), fabs(e2[1])), fabs(e2[2]));
  float d[3];
  float extent = 0.0f;
  for (int k = 0; k < 3; ++k) {
    d[k] = (n[0] * r[k][0] + n[1] * r[k][1]) + n[2] * r[k][2];
    extent = fmax(extent, fmax(fmax(fabs(r[k][0]), fabs(r[k][1])), fabs(r[k][2])));
  }
  const bool inRange = (edge1 >= FLOAT_SIDE_MIN_FACTOR) & (edge1 <= FLOAT_SIDE_MAX_FACTOR) &
                       (edge2 >= FLOAT_SIDE_MIN_FACTOR) & (edge2 <= FLOAT_SIDE_MAX_FACTOR) &
                       (extent >= FLOAT_SIDE_MIN_FACTOR) & (extent <= FLOAT_SIDE_MAX_FACTOR);
  const float m = FLOAT_SIDE_MARGIN * edge1 * edge2 * extent;
  const bool above = (d[0] > m) & (d[1] > m) & (d[2] > m);
  const bool below = (d[0] < -m) & (d[1] < -m) & (d[2] < -m);
  const bool off = (fabs(d[0]) > m) | (fabs(d[1]) > m) | (fabs(d[2]) > m);
  return (inRange & (above | below) ? 1u : 0u) | (inRange & off ? 2u : 0u);
}

// Vertex of a mesh from the arena.
void mesh_vertex(__global const float* vertices, uint firstVertex, uint vertex, float* out) {
  __global const float* p = vertices + 3u * (firstVertex + vertex);
  out[0] = p[0];
  out[1] = p[1];
  out[2] = p[2];
}

// One candidate: the hit record (flags with GPUCOL_HIT_INTERSECTS when the triangles intersect). The
// candidate index is written by the compaction.
__kernel void mesh_near_test(__global const GpucolMeshPair* pairs, __global const float* vertices,
                             __global const uint* indices, __global const ulong* keys, const uint n,
                             const uint bitsA, const uint bitsB, __global GpucolNearHit* hits) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  const ulong key = keys[i];
  const uint pair = (uint)(key >> (bitsA + bitsB));
  const uint triangleA = (uint)((key >> bitsB) & ((1ul << bitsA) - 1ul));
  const uint triangleB = (uint)(key & ((1ul << bitsB) - 1ul));
  __global const GpucolMeshPair* p = pairs + pair;

  // The triangles in A's scaled frame, in float, as collide_meshes.cpp builds them.
  float af[3][3], bf[3][3];
  __global const uint* cornerA = indices + 3u * (p->trianglesA + triangleA);
  __global const uint* cornerB = indices + 3u * (p->trianglesB + triangleB);
  for (int c = 0; c < 3; ++c) {
    float v[3];
    mesh_vertex(vertices, p->verticesA, cornerA[c], v);
    for (int k = 0; k < 3; ++k) af[c][k] = p->scaleA[k] * v[k];
    mesh_vertex(vertices, p->verticesB, cornerB[c], v);
    for (int k = 0; k < 3; ++k) {
      // Eigen's order for a 3x3 float matrix times a vector (its unrolled sum pairs the last two terms first).
      bf[c][k] = (p->bLinear[3 * k] * v[0] + (p->bLinear[3 * k + 1] * v[1] + p->bLinear[3 * k + 2] * v[2])) +
                 p->bTranslation[k];
    }
  }
  if (p->flipA) {
    for (int k = 0; k < 3; ++k) {
      const float t = af[1][k];
      af[1][k] = af[2][k];
      af[2][k] = t;
    }
  }
  if (p->flipB) {
    for (int k = 0; k < 3; ++k) {
      const float t = bf[1][k];
      bf[1][k] = bf[2][k];
      bf[2][k] = t;
    }
  }

  GpucolNearHit hit;
  hit.candidate = i;
  hit.flags = 0u;
  for (int k = 0; k < 3; ++k) hit.point[k] = hit.normal[k] = hit.deepest[k] = 0.0f;
  hit.depth = 0.0f;

#ifdef GPUCOL_NEAR_PREFILTER
  {
    const uint sideB = float_plane_side(af[0], af[1], af[2], bf[0], bf[1], bf[2]);
    const uint sideA = float_plane_side(bf[0], bf[1], bf[2], af[0], af[1], af[2]);
    if (((sideB | ((sideB >> 1) & sideA)) & 1u) != 0u) {
      hits[i] = hit;
      return;
    }
  }
#endif

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
  hits[i] = hit;
}

// Writes the intersecting candidates' hits in candidate order; `offsets` is the exclusive scan of the
// intersect flags (mesh_near_flags).
__kernel void mesh_near_flags(__global const GpucolNearHit* hits, const uint n, __global uint* flags) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  flags[i] = (hits[i].flags & GPUCOL_HIT_INTERSECTS) != 0u ? 1u : 0u;
}

__kernel void mesh_near_compact(__global const GpucolNearHit* hits, const uint n, __global const uint* offsets,
                                __global GpucolNearHit* out) {
  const uint i = get_global_id(0);
  if (i >= n) return;
  if ((hits[i].flags & GPUCOL_HIT_INTERSECTS) == 0u) return;
  GpucolNearHit hit = hits[i];
  hit.flags &= ~GPUCOL_HIT_INTERSECTS;
  out[offsets[i]] = hit;
}
