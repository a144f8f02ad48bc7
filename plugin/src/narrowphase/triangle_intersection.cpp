#include "narrowphase/triangle_intersection.h"

#include "narrowphase/triangle_plane.h"
#include "shared_math/triangle_test.h"

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

bool trianglesIntersectDouble(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                              const Eigen::Vector3f& b0, const Eigen::Vector3f& b1,
                              const Eigen::Vector3f& b2) {
  // Double arithmetic on the float input (see triangle_plane.h): Möller 1997 as gpucol_triangles_intersect.
  const double a[3][3] = {{a0.x(), a0.y(), a0.z()}, {a1.x(), a1.y(), a1.z()}, {a2.x(), a2.y(), a2.z()}};
  const double b[3][3] = {{b0.x(), b0.y(), b0.z()}, {b1.x(), b1.y(), b1.z()}, {b2.x(), b2.y(), b2.z()}};
  return gpucol_triangles_intersect(a, b) != 0;
}

}  // namespace detail

}  // namespace gpucol
