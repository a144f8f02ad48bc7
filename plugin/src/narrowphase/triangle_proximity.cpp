// Contacts of triangles closer than the shapes' margins: vertex over face and edge against edge, the features
// whose closest points realise the distance between two triangles that do not intersect.
#include "narrowphase/triangle_proximity.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "bvh/avx2_clones.h"
#include "shared_math/triangle_lanes.h"

namespace gpucol {
namespace {

using Vec = Eigen::Vector3d;

// Tolerance of the outer-side test: it keeps faces at right angles (a box's side against the face it stands
// on), whose contact normal is perpendicular to one of them.
constexpr double kSideTolerance = 1e-6;

using Face = ProximityFace;

// True when p's projection along the face's normal falls on the face, its edges included (a vertex on a shared
// edge belongs to both faces; the contact reduction merges what that doubles).
bool projectsOntoFace(const Face& f, const Vec& p) {
  for (int i = 0; i < 3; ++i) {
    if (f.inward[i].dot(p - f.v[i]) < -1e-9 * f.edge2[i]) return false;
  }
  return true;
}

// The longer of the two triangles' longest edges.
double pairSize(const Face& fa, const Face& fb) {
  return std::sqrt(std::max({fa.edge2[0], fa.edge2[1], fa.edge2[2], fb.edge2[0], fb.edge2[1], fb.edge2[2]}));
}

// True when one triangle lies wholly on one side of the other's plane such that no contact below can come:
// beyond `reach` in front of it or behind it (every contact is closer than reach), or behind it at all (a
// contact needs a point on the other's outer side; `behind` exceeds what the outer-side test's 1e-6 and the
// touching-edge case's 1e-7 of the size let through). The float pre-test (proximityCertainlyEmptyBranchFree)
// ends most candidates of two meshes with margins before this.
bool separatedByAPlane(const Face& fa, const Face& fb, double reach, double size) {
  const double behind = 2e-6 * reach + 1e-6 * size;
  const auto apart = [&](const Face& of, const Face& plane) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec& v : of.v) {
      const double d = plane.normal.dot(v - plane.v[0]);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    return lo > reach + 1e-6 * size || hi < -behind;
  };
  return apart(fa, fb) || apart(fb, fa);
}

// The closest points of the nearest of the nine pairs of edges (edge i of A, edge j of B): returns their
// squared distance, the first smallest in the order i, j. Per pair the squared distance of the segments
// p0 + s u and q0 + t v, s and t in [0, 1], is a convex quadratic in (s, t): take the unconstrained minimum's
// s clamped, the best t for it, and if that t must be clamped, the best s for the clamped t; parallel
// segments take s = 0. The pairs run four at a time in the lanes of shared_math/triangle_lanes.h, choices by
// masks, so the divisions of different pairs overlap instead of each pair waiting on its own and
// mispredicting its clamps.
// GCC 12 calls each lane vector below "used uninitialized" in the AVX2 clone although every one is written
// before it is read (the same code compiles without the warning for the baseline clone).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
GPUCOL_AVX2_CLONES double closestEdgePoints(const Face& fa, const Face& fb, Vec& bestA, Vec& bestB,
                                            int& edgeA, int& edgeB) {
  // Twelve lanes, the last three repeating the first pair; lane k holds edge kEdgeA[k] of A and kEdgeB[k]
  // of B. Each vector is put together from the faces' values directly: written to memory lane by lane and
  // read back as vectors, the loads waited on the stores.
  constexpr int kPairs = 9, kLanes = 12;
  constexpr int kEdgeA[kLanes] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 0, 0, 0};
  constexpr int kEdgeB[kLanes] = {0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 0, 0};
  alignas(32) double d2[kLanes], s[kLanes], t[kLanes];
  const gpucol_d4 zero = gpucol_d4_splat(0.0), one = gpucol_d4_splat(1.0);
  for (int g = 0; g < kLanes; g += 4) {
    const int a0 = kEdgeA[g], a1 = kEdgeA[g + 1], a2 = kEdgeA[g + 2], a3 = kEdgeA[g + 3];
    const int b0 = kEdgeB[g], b1 = kEdgeB[g + 1], b2 = kEdgeB[g + 2], b3 = kEdgeB[g + 3];
    gpucol_d4 p[3], u[3], q[3], v[3];
    for (int x = 0; x < 3; ++x) {
      p[x] = gpucol_d4{fa.v[a0][x], fa.v[a1][x], fa.v[a2][x], fa.v[a3][x]};
      u[x] = gpucol_d4{fa.edge[a0][x], fa.edge[a1][x], fa.edge[a2][x], fa.edge[a3][x]};
      q[x] = gpucol_d4{fb.v[b0][x], fb.v[b1][x], fb.v[b2][x], fb.v[b3][x]};
      v[x] = gpucol_d4{fb.edge[b0][x], fb.edge[b1][x], fb.edge[b2][x], fb.edge[b3][x]};
    }
    const gpucol_d4 a = {fa.edge2[a0], fa.edge2[a1], fa.edge2[a2], fa.edge2[a3]};
    const gpucol_d4 c = {fb.edge2[b0], fb.edge2[b1], fb.edge2[b2], fb.edge2[b3]};
    const gpucol_d4 w[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    const gpucol_d4 b = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    const gpucol_d4 d = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
    const gpucol_d4 e = v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
    const gpucol_d4 denominator = a * c - b * b;
    const gpucol_d4 free = gpucol_d4_min(gpucol_d4_max((b * e - c * d) / denominator, zero), one);
    const gpucol_d4 sFree = gpucol_d4_pick(denominator > 1e-12 * a * c, free, zero);
    const gpucol_d4 tFree = (b * sFree + e) / c;
    const gpucol_d4 sLow = gpucol_d4_min(gpucol_d4_max(-d / a, zero), one);
    const gpucol_d4 sHigh = gpucol_d4_min(gpucol_d4_max((b - d) / a, zero), one);
    const gpucol_d4 sk = gpucol_d4_pick(tFree < zero, sLow, gpucol_d4_pick(tFree > one, sHigh, sFree));
    const gpucol_d4 tk = gpucol_d4_min(gpucol_d4_max(tFree, zero), one);
    gpucol_d4 squared = zero;
    for (int x = 0; x < 3; ++x) {
      const gpucol_d4 gap = w[x] + sk * u[x] - tk * v[x];
      squared += gap * gap;
    }
    std::memcpy(&d2[g], &squared, sizeof(gpucol_d4));
    std::memcpy(&s[g], &sk, sizeof(gpucol_d4));
    std::memcpy(&t[g], &tk, sizeof(gpucol_d4));
  }
  int nearest = 0;
  for (int k = 1; k < kPairs; ++k) nearest = d2[k] < d2[nearest] ? k : nearest;
  const int i = nearest / 3, j = nearest % 3;
  bestA = fa.v[i] + s[nearest] * fa.edge[i];
  bestB = fb.v[j] + t[nearest] * fb.edge[j];
  edgeA = i;
  edgeB = j;
  return d2[nearest];
}
#pragma GCC diagnostic pop

// True when `away` (from the edge's side of the contact towards the other body) lies in the region edge i's
// two faces leave it: not into this face nor into the one across (whose far vertex is `wing`). None is left
// at a concave edge, only the face's normal at a flat one. An edge without a known wing is not checked.
bool withinEdgeRegion(const Face& f, int i, const Eigen::Vector3f& wing, const Vec& away) {
  if (!wing.allFinite()) return true;
  const Vec toWing = wing.cast<double>() - f.v[i];
  const Vec intoOther = toWing - f.edge[i] * (toWing.dot(f.edge[i]) / f.edge2[i]);
  return away.dot(f.inward[i]) <= kSideTolerance * f.inward[i].norm() &&
         away.dot(intoOther) <= kSideTolerance * intoOther.norm();
}

// A contact whose point on A is `onA`, on B `onA - normal * distance`. toWorld puts Bullet's point on B at
// deepestPoint - normalOnB * depth when onFaceOfB, else at deepestPoint.
TriangleContact contactFromA(const Vec& onA, const Vec& normalOnB, double distance) {
  TriangleContact c;
  c.point = (onA - 0.5 * distance * normalOnB).cast<float>();
  c.normalOnB = normalOnB.cast<float>();
  c.depth = float(distance);
  c.onFaceOfB = true;
  c.deepestPoint = onA.cast<float>();
  return c;
}

TriangleContact contactFromB(const Vec& onB, const Vec& normalOnB, double distance) {
  TriangleContact c;
  c.point = (onB + 0.5 * distance * normalOnB).cast<float>();
  c.normalOnB = normalOnB.cast<float>();
  c.depth = float(distance);
  c.onFaceOfB = false;
  c.deepestPoint = onB.cast<float>();
  return c;
}

}  // namespace

ProximityFace proximityFace(const Eigen::Vector3f (&t)[3]) {
  ProximityFace f;
  for (int i = 0; i < 3; ++i) f.v[i] = t[i].cast<double>();
  for (int i = 0; i < 3; ++i) {
    f.edge[i] = f.v[(i + 1) % 3] - f.v[i];
    f.edge2[i] = f.edge[i].squaredNorm();
  }
  const Vec n = f.edge[0].cross(f.v[2] - f.v[0]);
  const double n2 = n.squaredNorm();
  f.valid = std::isfinite(n2) && n2 > 1e-12 * f.edge2[0] * f.edge2[2];
  if (!f.valid) return f;
  f.normal = n / std::sqrt(n2);
  for (int i = 0; i < 3; ++i) f.inward[i] = f.normal.cross(f.edge[i]);
  return f;
}

int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom) {
  if (!(reach > 0)) return 0;
  return proximityContacts(proximityFace(a), proximityFace(b), reach, out, speculativeFrom);
}

int proximityContacts(const ProximityFace& fa, const ProximityFace& fb, float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom,
                      const EdgeWings* wingsA, const EdgeWings* wingsB) {
  if (!(reach > 0)) return 0;
  if (!fa.valid || !fb.valid) return 0;
  const double size = pairSize(fa, fb);
  if (separatedByAPlane(fa, fb, reach, size)) return 0;
  // Each contact's point on A on B's outer side and its point on B on A's outer side: along the contact's
  // normal n (from B to A), n.nB >= 0 and n.nA <= 0 (within kSideTolerance).
  const auto outerSides = [&](const Vec& normal) {
    return normal.dot(fb.normal) >= -kSideTolerance && normal.dot(fa.normal) <= kSideTolerance;
  };
  int count = 0;
  // The smallest distance from a vertex to the other's face over it, on either side: when an edge pair is not
  // closer than this, the closest points are a vertex over a face, already given (or refused).
  double closestOverFace = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (!projectsOntoFace(fb, fa.v[i])) continue;
    const double d = fb.normal.dot(fa.v[i] - fb.v[0]);
    closestOverFace = std::min(closestOverFace, std::fabs(d));
    if (d >= 0 && d < reach && outerSides(fb.normal)) out[count++] = contactFromA(fa.v[i], fb.normal, d);
  }
  for (int i = 0; i < 3; ++i) {
    if (!projectsOntoFace(fa, fb.v[i])) continue;
    const double d = fa.normal.dot(fb.v[i] - fa.v[0]);
    closestOverFace = std::min(closestOverFace, std::fabs(d));
    if (d >= 0 && d < reach && outerSides(-fa.normal)) out[count++] = contactFromB(fb.v[i], -fa.normal, d);
  }

  Vec bestA, bestB;
  int edgeA = 0, edgeB = 0;
  const double distance = std::sqrt(closestEdgePoints(fa, fb, bestA, bestB, edgeA, edgeB));
  if (!(distance < reach) || !(distance < closestOverFace * (1 - 1e-6))) return count;
  // Touching edges (the exact test may call a pair within about 1e-6 of its size either way) have no
  // direction between their points: B's face normal stands in. Speculative contacts of edges that nearly
  // touch take the face whose plane has the other triangle wholly on its outer side (a box's edge at a
  // floor's edge gets the floor's normal, not a sideways one), and none when neither face separates them.
  const bool apart = distance > 1e-7 * size;
  Vec normal = apart ? Vec((bestA - bestB) / distance) : fb.normal;
  // The edges' own direction only where the surface around each edge allows it (a box's edge in the inner
  // corner of an L, or over the diagonal of a flat face, would lean off the faces). Checked on a side whose
  // closest point lies inside its edge: at an end the feature is a vertex, whose region all the faces around
  // it make.
  const auto inside = [](const Face& f, int i, const Vec& p) {
    const double s = (p - f.v[i]).dot(f.edge[i]) / f.edge2[i];
    return s > 1e-6 && s < 1 - 1e-6;
  };
  if (apart && distance >= 1e-3 * size &&
      ((wingsA && inside(fa, edgeA, bestA) && !withinEdgeRegion(fa, edgeA, wingsA->across[edgeA], -normal)) ||
       (wingsB && inside(fb, edgeB, bestB) && !withinEdgeRegion(fb, edgeB, wingsB->across[edgeB], normal)))) {
    return count;
  }
  if (distance >= speculativeFrom && distance < 1e-3 * size) {
    const auto outside = [&](const Face& of, const Face& plane) {
      for (const Vec& v : of.v) {
        if (plane.normal.dot(v - plane.v[0]) < -1e-6 * size) return false;
      }
      return true;
    };
    if (outside(fb, fa)) {
      normal = -fa.normal;
    } else if (outside(fa, fb)) {
      normal = fb.normal;
    } else {
      return count;
    }
  }
  if (outerSides(normal)) out[count++] = contactFromA(bestA, normal, distance);
  return count;
}

}  // namespace gpucol
