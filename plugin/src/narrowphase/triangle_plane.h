#pragma once

// Internal helpers shared by the triangle test and the contact generation: the plane of a triangle,
// the signed distances of another triangle's vertices to it (with Möller's snapping of near-zero
// distances), the interval of a triangle on the planes' intersection line, and the 2-D tests of the
// coplanar case. Everything is inline and allocation-free: it is the inner loop of the near phase.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace gpucol::detail {

/// A triangle is degenerate when sin^2 of the angle between its edges v1-v0 and v2-v0 is below this.
/// 1e-12 is an angle of 1e-6 rad, below float's resolution of a direction (2^-23 ~ 1.2e-7 per component
/// is already the noise of a unit normal), so such a triangle has no meaningful plane. Needles and slivers
/// above it keep working. The test is written as !(a > b) so that NaN input is also called degenerate.
inline constexpr float kDegenerateSin2 = 1e-12f;

/// Relative tolerance under which a signed distance is snapped to exactly zero (Möller 1997 uses an
/// absolute EPSILON; ours is relative, so it does not depend on the units of the mesh). The float error of
/// d = n.(q - p0), with n = e1 x e2 rounded per component, is a few ulps of |e1||e2||q - p0|; 2^-20
/// (~9.5e-7, eight ulps) covers it. Snapping makes "on the plane" exact: a shared vertex, or a vertex
/// lying on the other face up to rounding, is touching (which counts as intersecting) rather than a coin
/// toss, and a pair whose every vertex is that close to the other plane goes to the 2-D coplanar test,
/// where the line of intersection would be ill-conditioned.
inline constexpr float kSnapRelative = 9.5367431640625e-7f;

/// The plane of a triangle: a point on it, the unnormalised normal e1 x e2 (counter-clockwise seen from
/// outside means it points outwards), and the product of the edges' largest components, the scale of
/// the normal's rounding error.
struct TrianglePlane {
  Eigen::Vector3f origin;  ///< v0.
  Eigen::Vector3f normal;  ///< (v1 - v0) x (v2 - v0), not normalised.
  float errorScale;        ///< max|e1| * max|e2| (infinity norms): bounds |normal|'s rounding error.
  bool degenerate;         ///< Zero area (or NaN): no plane.
};

/// The plane of triangle (v0, v1, v2).
inline TrianglePlane makePlane(const Eigen::Vector3f& v0, const Eigen::Vector3f& v1, const Eigen::Vector3f& v2) {
  const Eigen::Vector3f e1 = v1 - v0;
  const Eigen::Vector3f e2 = v2 - v0;
  TrianglePlane plane;
  plane.origin = v0;
  plane.normal = e1.cross(e2);
  plane.errorScale = e1.cwiseAbs().maxCoeff() * e2.cwiseAbs().maxCoeff();
  plane.degenerate = !(plane.normal.squaredNorm() > kDegenerateSin2 * e1.squaredNorm() * e2.squaredNorm());
  return plane;
}

/// Signed distances (times |normal|) of q0, q1, q2 to `plane`, those within the rounding tolerance
/// snapped to exactly 0. Positive is on the outer side.
inline void signedDistances(const TrianglePlane& plane, const Eigen::Vector3f& q0, const Eigen::Vector3f& q1,
                            const Eigen::Vector3f& q2, float d[3]) {
  const Eigen::Vector3f r0 = q0 - plane.origin;
  const Eigen::Vector3f r1 = q1 - plane.origin;
  const Eigen::Vector3f r2 = q2 - plane.origin;
  d[0] = plane.normal.dot(r0);
  d[1] = plane.normal.dot(r1);
  d[2] = plane.normal.dot(r2);
  const float extent = std::max({r0.cwiseAbs().maxCoeff(), r1.cwiseAbs().maxCoeff(), r2.cwiseAbs().maxCoeff()});
  const float tolerance = kSnapRelative * plane.errorScale * extent;
  for (int i = 0; i < 3; ++i) d[i] = std::fabs(d[i]) <= tolerance ? 0.0f : d[i];
}

/// True when x and y are both strictly positive or both strictly negative. Compared by sign rather than by
/// x * y > 0, which underflows to 0 for tiny meshes (the distances scale with length cubed).
inline bool sameStrictSign(float x, float y) { return (x > 0.0f && y > 0.0f) || (x < 0.0f && y < 0.0f); }

/// True when all three distances are non-zero with one sign: the triangle misses the plane (Möller's
/// early rejection).
inline bool allOnOneSide(const float d[3]) { return sameStrictSign(d[0], d[1]) && sameStrictSign(d[0], d[2]); }

/// True when all three distances are zero: the triangle lies in the plane.
inline bool allInPlane(const float d[3]) { return d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f; }

/// The vertex on its own side of the other plane (Möller 1997, "compute intervals"), for distances that
/// are neither all on one side nor all zero. The two edges from it cross the plane; when the lone vertex
/// lies in the plane both crossings are that vertex, and the formula below never divides by zero.
inline int loneVertex(const float d[3]) {
  if (sameStrictSign(d[0], d[1])) return 2;
  if (sameStrictSign(d[0], d[2])) return 1;
  if (sameStrictSign(d[1], d[2]) || d[0] != 0.0f) return 0;
  if (d[1] != 0.0f) return 1;
  return 2;
}

/// Interval [lo, hi] of a triangle on the intersection line, from the vertices' coordinates `p` along
/// the line's dominant axis and their distances `d` to the other plane.
inline void lineInterval(const float p[3], const float d[3], float& lo, float& hi) {
  const int a = loneVertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  const float t0 = p[a] + (p[b] - p[a]) * (d[a] / (d[a] - d[b]));
  const float t1 = p[a] + (p[c] - p[a]) * (d[a] / (d[a] - d[c]));
  lo = std::min(t0, t1);
  hi = std::max(t0, t1);
}

/// The same crossing points in 3-D: the segment where triangle v meets the other plane.
inline void planeCrossing(const Eigen::Vector3f* const v[3], const float d[3], Eigen::Vector3f& s0,
                          Eigen::Vector3f& s1) {
  const int a = loneVertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  s0 = *v[a] + (*v[b] - *v[a]) * (d[a] / (d[a] - d[b]));
  s1 = *v[a] + (*v[c] - *v[a]) * (d[a] / (d[a] - d[c]));
}

/// Index of the largest absolute component.
inline int dominantAxis(const Eigen::Vector3f& v) {
  const float x = std::fabs(v.x()), y = std::fabs(v.y()), z = std::fabs(v.z());
  return x >= y ? (x >= z ? 0 : 2) : (y >= z ? 1 : 2);
}

/// Twice the signed area of the 2-D triangle (a, b, c): positive when counter-clockwise.
inline float orient2d(float ax, float ay, float bx, float by, float cx, float cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

}  // namespace gpucol::detail
