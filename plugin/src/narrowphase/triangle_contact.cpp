#include "narrowphase/triangle_contact.h"

#include <algorithm>
#include <cmath>

#include "narrowphase/coplanar_triangles.h"
#include "narrowphase/triangle_plane.h"

namespace gpucol {

std::optional<TriangleContact> generateContact(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3]) {
  bool intersects = false;
  return detail::generateContactAndTest(a, b, intersects);
}

namespace detail {

std::optional<TriangleContact> generateContactAndTest(const Eigen::Vector3f (&af)[3],
                                                      const Eigen::Vector3f (&bf)[3], bool& intersects) {
  intersects = false;
  // Double arithmetic on the float input, as in trianglesIntersect (see triangle_plane.h).
  const Eigen::Vector3d a[3] = {af[0].cast<double>(), af[1].cast<double>(), af[2].cast<double>()};
  const Eigen::Vector3d b[3] = {bf[0].cast<double>(), bf[1].cast<double>(), bf[2].cast<double>()};

  // The intersection test first (thesis §5.3.4 runs Möller's test, §3.5, before generating contacts);
  // its signed distances are reused below.
  const TrianglePlane planeA = makePlane(a[0], a[1], a[2]);
  if (planeA.degenerate) return std::nullopt;
  double dB[3];
  signedDistances(planeA, b[0], b[1], b[2], dB);
  if (allOnOneSide(dB)) return std::nullopt;
  const TrianglePlane planeB = makePlane(b[0], b[1], b[2]);
  if (planeB.degenerate) return std::nullopt;
  double dA[3];
  signedDistances(planeB, a[0], a[1], a[2], dA);
  if (allOnOneSide(dA)) return std::nullopt;

  const double lengthA = planeA.normal.norm();
  const double lengthB = planeB.normal.norm();
  const Eigen::Vector3d nA = planeA.normal / lengthA;
  const Eigen::Vector3d nB = planeB.normal / lengthB;
  const Eigen::Vector3d* const pa[3] = {&a[0], &a[1], &a[2]};
  const Eigen::Vector3d* const pb[3] = {&b[0], &b[1], &b[2]};

  // Coplanar (after snapping, the same cases trianglesIntersect sends to the 2-D test): touching face
  // on face, so depth 0 along nB. The snapped distances are exactly 0, which is what the general rule
  // below would give too; only the point needs the 2-D overlap.
  const bool coplanarB = allInPlane(dB);
  if (coplanarB || allInPlane(dA)) {
    Eigen::Vector3d point;
    const int dropAxis = dominantAxis(coplanarB ? planeA.normal : planeB.normal);
    if (!coplanarTrianglesOverlap(pa, pb, dropAxis, &point)) return std::nullopt;
    intersects = true;
    // Flush faces side by side (the sides of two stacked boxes of one size, overlapping by a sliver when one
    // sinks a little) press on nothing: only faces that face each other rest on each other.
    if (nA.dot(nB) > 0) return std::nullopt;
    return TriangleContact{point.cast<float>(), nB.cast<float>(), 0.0f, true, false, point.cast<float>()};
  }

  // Möller's interval test on the intersection line L, with the crossing points kept in 3-D: the same
  // arithmetic as trianglesIntersect on the dominant axis, so both functions decide alike.
  const Eigen::Vector3d lineDirection = planeA.normal.cross(planeB.normal);
  const int axis = dominantAxis(lineDirection);
  Eigen::Vector3d sA[2], sB[2];
  planeCrossing(pa, dA, sA[0], sA[1]);
  planeCrossing(pb, dB, sB[0], sB[1]);
  if (sA[1][axis] < sA[0][axis]) std::swap(sA[0], sA[1]);
  if (sB[1][axis] < sB[0][axis]) std::swap(sB[0], sB[1]);
  if (sA[0][axis] > sB[1][axis] || sB[0][axis] > sA[1][axis]) return std::nullopt;
  intersects = true;


  // §5.3.4: the distance to move each triangle along the other's normal until it is out of the other's
  // plane. The distances are scaled by the plane's |normal|; a triangle that only touches the plane has
  // minimum 0 (snapping makes that exact).
  const double moveA = std::max(0.0, -std::min({dA[0], dA[1], dA[2]}) / lengthB);
  const double moveB = std::max(0.0, -std::min({dB[0], dB[1], dB[2]}) / lengthA);
  const bool aMoves = moveA <= moveB;
  const double move = aMoves ? moveA : moveB;

  // §5.3.4: drop the contact when sliding the triangles apart along L is shorter than the depth. The
  // whole triangles are projected on the unit direction of L, relative to a[0] so that a pair far from
  // the origin keeps its precision. L's direction is not zero here: parallel planes are either apart
  // (rejected above) or coplanar.
  const Eigen::Vector3d u = lineDirection.normalized();
  const double pA1 = u.dot(a[1] - a[0]), pA2 = u.dot(a[2] - a[0]);
  const double pB0 = u.dot(b[0] - a[0]), pB1 = u.dot(b[1] - a[0]), pB2 = u.dot(b[2] - a[0]);
  const double slide = std::min(std::max({0.0, pA1, pA2}) - std::min({pB0, pB1, pB2}),
                                std::max({pB0, pB1, pB2}) - std::min({0.0, pA1, pA2}));
  if (slide < move) return std::nullopt;

  // The common segment of the two crossings on L; its midpoint lies on both triangles.
  const Eigen::Vector3d& low = sA[0][axis] >= sB[0][axis] ? sA[0] : sB[0];
  const Eigen::Vector3d& high = sA[1][axis] <= sB[1][axis] ? sA[1] : sB[1];
  const Eigen::Vector3d normalOnB = aMoves ? nB : Eigen::Vector3d(-nA);
  // 0 - 0 is +0, so touching contacts do not print as -0.
  // The moving triangle's deepest vertex: the one its move is measured from.
  const double* const d = aMoves ? dA : dB;
  const int deepest = d[0] <= d[1] ? (d[0] <= d[2] ? 0 : 2) : (d[1] <= d[2] ? 1 : 2);
  const Eigen::Vector3d& deepestVertex = aMoves ? a[deepest] : b[deepest];
  return TriangleContact{(0.5 * (low + high)).cast<float>(), normalOnB.cast<float>(),
                         static_cast<float>(0.0 - move), aMoves, nA.dot(nB) > 0, deepestVertex.cast<float>()};
}

}  // namespace detail

}  // namespace gpucol
