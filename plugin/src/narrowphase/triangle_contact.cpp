#include "narrowphase/triangle_contact.h"

#include <algorithm>
#include <cmath>

#include "narrowphase/coplanar_triangles.h"
#include "narrowphase/triangle_plane.h"

namespace gpucol {

std::optional<TriangleContact> generateContact(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3]) {
  // The intersection test first (thesis §5.3.4 runs Möller's test, §3.5, before generating contacts);
  // its signed distances are reused below.
  const detail::TrianglePlane planeA = detail::makePlane(a[0], a[1], a[2]);
  const detail::TrianglePlane planeB = detail::makePlane(b[0], b[1], b[2]);
  if (planeA.degenerate || planeB.degenerate) return std::nullopt;
  float dB[3];
  detail::signedDistances(planeA, b[0], b[1], b[2], dB);
  if (detail::allOnOneSide(dB)) return std::nullopt;
  float dA[3];
  detail::signedDistances(planeB, a[0], a[1], a[2], dA);
  if (detail::allOnOneSide(dA)) return std::nullopt;

  const float lengthA = planeA.normal.norm();
  const float lengthB = planeB.normal.norm();
  const Eigen::Vector3f nA = planeA.normal / lengthA;
  const Eigen::Vector3f nB = planeB.normal / lengthB;
  const Eigen::Vector3f* const pa[3] = {&a[0], &a[1], &a[2]};
  const Eigen::Vector3f* const pb[3] = {&b[0], &b[1], &b[2]};

  // Coplanar (after snapping, the same cases trianglesIntersect sends to the 2-D test): touching
  // face on face, so depth 0 along nB. The snapped distances are exactly 0, which is what the general
  // rule below would give too; only the point needs the 2-D overlap.
  const bool coplanarB = detail::allInPlane(dB);
  if (coplanarB || detail::allInPlane(dA)) {
    TriangleContact contact;
    const int dropAxis = detail::dominantAxis(coplanarB ? planeA.normal : planeB.normal);
    if (!detail::coplanarTrianglesOverlap(pa, pb, dropAxis, &contact.point)) return std::nullopt;
    contact.normalOnB = nB;
    contact.depth = 0.0f;
    return contact;
  }

  // Möller's interval test on the intersection line L, with the crossing points kept in 3-D: the same
  // arithmetic as trianglesIntersect on the dominant axis, so both functions decide alike.
  const Eigen::Vector3f lineDirection = planeA.normal.cross(planeB.normal);
  const int axis = detail::dominantAxis(lineDirection);
  Eigen::Vector3f sA[2], sB[2];
  detail::planeCrossing(pa, dA, sA[0], sA[1]);
  detail::planeCrossing(pb, dB, sB[0], sB[1]);
  if (sA[1][axis] < sA[0][axis]) std::swap(sA[0], sA[1]);
  if (sB[1][axis] < sB[0][axis]) std::swap(sB[0], sB[1]);
  if (sA[0][axis] > sB[1][axis] || sB[0][axis] > sA[1][axis]) return std::nullopt;

  // §5.3.4: the distance to move each triangle along the other's normal until it is out of the other's
  // plane. The distances are scaled by the plane's |normal|; a triangle that only touches the plane has
  // minimum 0 (snapping makes that exact).
  const float moveA = std::max(0.0f, -std::min({dA[0], dA[1], dA[2]}) / lengthB);
  const float moveB = std::max(0.0f, -std::min({dB[0], dB[1], dB[2]}) / lengthA);
  TriangleContact contact;
  float move;
  if (moveA <= moveB) {
    contact.normalOnB = nB;
    move = moveA;
  } else {
    contact.normalOnB = -nA;
    move = moveB;
  }
  contact.depth = 0.0f - move;  // 0 - 0 is +0, so touching contacts do not print as -0.

  // §5.3.4: drop the contact when sliding the triangles apart along L is shorter than the depth. The
  // whole triangles are projected on the unit direction of L. A zero direction (planes parallel to
  // rounding but not snapped coplanar) has no such slide, and the contact is kept.
  const float directionLength = lineDirection.norm();
  if (directionLength > 0.0f) {
    const Eigen::Vector3f u = lineDirection / directionLength;
    // Relative to a[0], so that a pair far from the origin keeps its precision.
    const float a0 = 0.0f, a1 = u.dot(a[1] - a[0]), a2 = u.dot(a[2] - a[0]);
    const float b0 = u.dot(b[0] - a[0]), b1 = u.dot(b[1] - a[0]), b2 = u.dot(b[2] - a[0]);
    const float slide = std::min(std::max({a0, a1, a2}) - std::min({b0, b1, b2}),
                                 std::max({b0, b1, b2}) - std::min({a0, a1, a2}));
    if (slide < move) return std::nullopt;
  }

  // The common segment of the two crossings on L; its midpoint lies on both triangles.
  const Eigen::Vector3f& low = sA[0][axis] >= sB[0][axis] ? sA[0] : sB[0];
  const Eigen::Vector3f& high = sA[1][axis] <= sB[1][axis] ? sA[1] : sB[1];
  contact.point = 0.5f * (low + high);
  return contact;
}

}  // namespace gpucol
