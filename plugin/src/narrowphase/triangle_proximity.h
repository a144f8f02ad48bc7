#pragma once

#include <Eigen/Core>

#include "narrowphase/triangle_contact.h"
#include "narrowphase/triangle_plane.h"

namespace gpucol {

/// The most contacts proximityContacts gives for one pair: each of the six vertices over the other's face, and
/// one edge-edge pair.
inline constexpr int kMaxProximityContacts = 7;

/// A triangle as proximityContacts works on it, in double: its vertices, edges (edge i from v[i] to v[i + 1])
/// and their squared lengths, its unit outward normal, and per edge the normal x edge, which points into the
/// face; `valid` is false for a degenerate or non-finite one, with the same threshold as trianglesIntersect
/// (sin^2 of the angle at v0 below 1e-12). Made once per triangle, it serves every candidate pair the
/// triangle is in.
struct ProximityFace {
  Eigen::Vector3d v[3];
  Eigen::Vector3d edge[3];
  double edge2[3];
  Eigen::Vector3d normal;
  Eigen::Vector3d inward[3];
  bool valid = false;
};

ProximityFace proximityFace(const Eigen::Vector3f (&t)[3]);

/// The far vertices of the triangles across a face's edges (edge i from v[i] to v[i + 1]), in the faces'
/// frame; a non-finite one (no single triangle across) leaves its edge unchecked.
struct EdgeWings {
  Eigen::Vector3f across[3];
};

/// Contacts of two triangles that do not cross but come within `reach` of each other (the sum of the two
/// shapes' collision margins), so that bodies with margins rest `reach` apart instead of falling through the
/// gap. Written to `out`; returns how many (0 when `reach` <= 0 or either triangle is degenerate).
///
/// Triangles are counter-clockwise seen from outside, as for generateContact. The contacts are Bullet's
/// closest points between the two surfaces, each with a distance in [0, reach) in `depth`:
/// - every vertex of one triangle whose projection falls on the other's face and that lies on that face's
///   outer side (a face resting on a face gives a contact at each corner, not one arbitrary closest point);
/// - the pair's closest points when they lie on an edge of each, if each lies on the other triangle's outer
///   side.
/// A point behind the other's face is inside that body: a crossing (generateContact) answers for it, and a
/// proximity contact there would push the bodies through each other.
///
/// Contacts from `speculativeFrom` on (the margins' sum, below `reach`) are speculative: the bodies are not
/// that close yet. There, two edges closer than 1e-3 of the triangles' size (a box sliding on a floor) have
/// no reliable direction between their closest points, and a sideways one would push the box aside: their
/// contact takes the normal of the face whose plane has the other triangle wholly on its outer side, and
/// there is none when neither does.
///
/// Computed in double from the float inputs. The caller must only pass pairs that trianglesIntersect rejects.
int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom);
/// The same for triangles already made into faces (proximityFace), so that a triangle in many candidate
/// pairs is made once.
/// With the faces' edge wings, an edge-against-edge contact whose direction one of its edges' two faces does
/// not leave it (into either face, or any at a concave edge) is left out: a vertex over a face answers there.
int proximityContacts(const ProximityFace& a, const ProximityFace& b, float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom,
                      const EdgeWings* wingsA = nullptr, const EdgeWings* wingsB = nullptr);
inline int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                             TriangleContact (&out)[kMaxProximityContacts]) {
  return proximityContacts(a, b, reach, out, reach);
}

namespace detail {

/// One plane's half of proximityCertainlyEmptyBranchFree: 1 when float arithmetic proves that every q_i lies
/// in front of the plane of (v0, v0 + e1, v0 + e2) farther than sqrt(front2), or behind it farther than
/// sqrt(behind2), in unit-normal distance. The unnormalised distances (gpucol_float_plane,
/// triangle_pretest.h) carry at most its error margin and the float normal's length at most 32u E1 E2 (each
/// component within 2 gamma_4 E1 E2); squares bound sums by (x + y)^2 <= (1 + 2^-10) x^2 + 1025 y^2, and a
/// factor 1 + 2^-18 covers the roundings of the comparison. Products that could be subnormal abstain, as do
/// factors outside the interval stage's range (so the squares cannot overflow).
GPUCOL_FORCE_INLINE gpucol_mask proximityPlaneApart(GpucolLanes3 v0, GpucolLanes3 e1, GpucolLanes3 e2,
                                                    GpucolLanes3 q0, GpucolLanes3 q1, GpucolLanes3 q2,
                                                    float front2, float behind2) {
  const float u = 1.0f / 16777216.0f, tiny = 0x1p-120f;
  const GpucolFloatPlane p = gpucol_float_plane(v0, e1, e2, q0, q1, q2);
  const gpucol_mask inRange =
      gpucol_interval_factor(p.edge1) & gpucol_interval_factor(p.edge2) & gpucol_interval_factor(p.extent);
  const float normalError = 32.0f * u * p.edge1 * p.edge2;
  const float normalUpper2 =
      (1.0f + 0x1p-9f) * gpucol_lanes3_dot(p.normal, p.normal) + 1025.0f * normalError * normalError;
  const GpucolLanes3 d = p.distance;
  const float low = gpucol_lanes_min(gpucol_lanes_min(d.x, d.y), d.z) - p.margin;
  const float high = gpucol_lanes_max(gpucol_lanes_max(d.x, d.y), d.z) + p.margin;
  const float frontBound = (1.0f + 0x1p-18f) * front2 * normalUpper2;
  const float behindBound = (1.0f + 0x1p-18f) * behind2 * normalUpper2;
  const gpucol_mask inFront = (low > 0.0f) & (low * low > frontBound) & (frontBound > tiny);
  const gpucol_mask behind = (high < 0.0f) & (high * high > behindBound) & (behindBound > tiny);
  return inRange & (normalUpper2 > tiny) & (inFront | behind);
}

}  // namespace detail

/// 1 when float arithmetic proves that proximityContacts(a, b, reach, ...) returns no contact because one
/// triangle lies wholly beyond `reach` in front of the other's plane or wholly behind it (its first
/// rejection, with the same size tolerances), else 0. Branch-free, so that a loop over rows of candidates is
/// vector code: most candidates of a pair with a margin or a speculative reach end here, before the double
/// test.
GPUCOL_FORCE_INLINE unsigned proximityCertainlyEmptyBranchFree(
    const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
    const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2, float reach) {
  const GpucolLanes3 pa0 = detail::floatLanes(a0), pa1 = detail::floatLanes(a1), pa2 = detail::floatLanes(a2);
  const GpucolLanes3 pb0 = detail::floatLanes(b0), pb1 = detail::floatLanes(b1), pb2 = detail::floatLanes(b2);
  const GpucolLanes3 e1 = gpucol_lanes3_sub(pa1, pa0), e2 = gpucol_lanes3_sub(pa2, pa0);
  const GpucolLanes3 f1 = gpucol_lanes3_sub(pb1, pb0), f2 = gpucol_lanes3_sub(pb2, pb0);
  // The double test's size is the longest edge of the two; a third edge is at most the sum of the other two.
  const float longest2 =
      gpucol_lanes_max(gpucol_lanes_max(gpucol_lanes3_dot(e1, e1), gpucol_lanes3_dot(e2, e2)),
                       gpucol_lanes_max(gpucol_lanes3_dot(f1, f1), gpucol_lanes3_dot(f2, f2)));
  const float size2 = 4.0f * (1.0f + 0x1p-16f) * longest2;
  // (reach + 1e-6 size)^2 and (2e-6 reach + 1e-6 size)^2, bounded as in proximityPlaneApart.
  const float front2 = (1.0f + 0x1p-10f) * reach * reach + 1025e-12f * size2;
  const float behind2 = 2.0f * (4e-12f * reach * reach + 1e-12f * size2);
  return unsigned(detail::proximityPlaneApart(pb0, f1, f2, pa0, pa1, pa2, front2, behind2) |
                  detail::proximityPlaneApart(pa0, e1, e2, pb0, pb1, pb2, front2, behind2));
}

}  // namespace gpucol
