#include "narrowphase/triangle_intersection.h"

#include "narrowphase/coplanar_triangles.h"
#include "narrowphase/triangle_plane.h"

namespace gpucol {

bool trianglesIntersect(const Eigen::Vector3f& a0f, const Eigen::Vector3f& a1f, const Eigen::Vector3f& a2f,
                        const Eigen::Vector3f& b0f, const Eigen::Vector3f& b1f, const Eigen::Vector3f& b2f) {
  // Most candidates of the middle phase fail Möller's first plane tests by a wide margin; float proves that
  // for them at a fraction of the cost, and says nothing otherwise, so the answer is always the double
  // test's.
  if (detail::floatCertainlyApart(a0f, a1f, a2f, b0f, b1f, b2f)) return false;
  return detail::trianglesIntersectDouble(a0f, a1f, a2f, b0f, b1f, b2f);
}

namespace detail {

bool trianglesIntersectDouble(const Eigen::Vector3f& a0f, const Eigen::Vector3f& a1f,
                              const Eigen::Vector3f& a2f, const Eigen::Vector3f& b0f,
                              const Eigen::Vector3f& b1f, const Eigen::Vector3f& b2f) {
  // Double arithmetic on the float input: see triangle_plane.h for why.
  const Eigen::Vector3d a0 = a0f.cast<double>(), a1 = a1f.cast<double>(), a2 = a2f.cast<double>();
  const Eigen::Vector3d b0 = b0f.cast<double>(), b1 = b1f.cast<double>(), b2 = b2f.cast<double>();

  // Möller 1997, step 1: B's vertices against A's plane; all strictly on one side rejects.
  // B's plane is only built after this first early-out (a degenerate B is rejected either way).
  const TrianglePlane planeA = makePlane(a0, a1, a2);
  if (planeA.degenerate) return false;
  double dB[3];
  signedDistances(planeA, b0, b1, b2, dB);
  if (allOnOneSide(dB)) return false;
  const TrianglePlane planeB = makePlane(b0, b1, b2);
  if (planeB.degenerate) return false;

  const Eigen::Vector3d* const a[3] = {&a0, &a1, &a2};
  const Eigen::Vector3d* const b[3] = {&b0, &b1, &b2};
  if (allInPlane(dB)) {
    return coplanarTrianglesOverlap(a, b, dominantAxis(planeA.normal), nullptr);
  }

  // Step 2: A's vertices against B's plane.
  double dA[3];
  signedDistances(planeB, a0, a1, a2, dA);
  if (allOnOneSide(dA)) return false;
  if (allInPlane(dA)) {
    return coplanarTrianglesOverlap(a, b, dominantAxis(planeB.normal), nullptr);
  }

  // Step 3: both triangles cross the line L where the planes meet; they intersect iff their intervals
  // on L overlap. Möller's simplification: the coordinate along L's dominant axis orders points on L
  // like the true line parameter, so no dot products are needed.
  const int axis = dominantAxis(planeA.normal.cross(planeB.normal));
  const double pA[3] = {a0[axis], a1[axis], a2[axis]};
  const double pB[3] = {b0[axis], b1[axis], b2[axis]};
  double loA, hiA, loB, hiB;
  lineInterval(pA, dA, loA, hiA);
  lineInterval(pB, dB, loB, hiB);
  return loA <= hiB && loB <= hiA;
}

}  // namespace detail

}  // namespace gpucol
