#pragma once

// Internal helpers shared by the triangle test and the contact generation: the plane of a triangle,
// the signed distances of another triangle's vertices to it (with Möller's snapping of near-zero
// distances), the interval of a triangle on the planes' intersection line, and the 2-D tests of the
// coplanar case. Everything is inline and allocation-free: it is the inner loop of the near phase.
//
// Precision: the inputs are float, the arithmetic is double. A product of two floats is exact in
// double and a difference of two nearby floats too, so the normal e1 x e2 and the signed distances
// carry about 1e-16 relative error instead of float's 1e-7. That matters for nearly parallel planes:
// an error delta in a distance moves the intersection line sideways by delta / sin(angle), and in
// float a pair of faces 2e-6 rad apart was reported intersecting while 11% of its size apart (found by
// the random near-coplanar tests). On a CPU double costs the same as float for this scalar code.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>

#include "narrowphase/triangle_contact.h"

namespace gpucol::detail {

/// Inlines a function into its callers even where the compiler's estimate says no: the batched loops of the
/// near phase are vector code only when the pair tests they call are inlined into them.
#if defined(__GNUC__)
#define GPUCOL_FORCE_INLINE inline __attribute__((always_inline))
#else
#define GPUCOL_FORCE_INLINE inline
#endif

/// A triangle is degenerate when sin^2 of the angle between its edges v1-v0 and v2-v0 is below this.
/// 1e-12 is an angle of 1e-6 rad: moving one vertex by a float ulp (1.2e-7 relative) would tilt such a
/// triangle's plane by a tenth of a radian, so its plane means nothing. Needles and slivers above it
/// keep working. The test is written as !(a > b) so that NaN input is also called degenerate.
inline constexpr double kDegenerateSin2 = 1e-12;

/// Relative tolerance under which a signed distance is snapped to exactly zero (Möller 1997 uses an
/// absolute EPSILON; ours is relative, so it does not depend on the units of the mesh). The double error
/// of d = n.(q - p0) is a few units of 1e-16 of |e1||e2||q - p0|; 1e-12 covers it with a wide margin and
/// stays far below float's resolution (1.2e-7), so only configurations that are exact in the float input
/// (a shared vertex, a vertex on the other plane, coplanar faces) are snapped. Snapping makes those exact:
/// touching counts as intersecting instead of a coin toss, and a pair whose every vertex is in the other
/// plane goes to the 2-D coplanar test. The side effect, the intersection line moving sideways by
/// 1e-12 / sin(angle), stays below 1e-6 of the pair's size at every angle once the coplanar case is
/// taken out (it is at most min(angle, 1e-12 / angle)).
inline constexpr double kSnapRelative = 1e-12;

/// The plane of a triangle: a point on it, the unnormalised normal e1 x e2 (counter-clockwise seen from
/// outside means it points outwards), and the product of the edges' largest components, the scale of
/// the normal's rounding error.
struct TrianglePlane {
  Eigen::Vector3d origin;  ///< v0.
  Eigen::Vector3d normal;  ///< (v1 - v0) x (v2 - v0), not normalised.
  double errorScale;       ///< max|e1| * max|e2| (infinity norms): bounds |normal|'s rounding error.
  bool degenerate;         ///< Zero area (or NaN): no plane.
};

/// The plane of triangle (v0, v1, v2).
inline TrianglePlane makePlane(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1,
                               const Eigen::Vector3d& v2) {
  const Eigen::Vector3d e1 = v1 - v0;
  const Eigen::Vector3d e2 = v2 - v0;
  TrianglePlane plane;
  plane.origin = v0;
  plane.normal = e1.cross(e2);
  plane.errorScale = e1.cwiseAbs().maxCoeff() * e2.cwiseAbs().maxCoeff();
  plane.degenerate = !(plane.normal.squaredNorm() > kDegenerateSin2 * e1.squaredNorm() * e2.squaredNorm());
  return plane;
}

/// Signed distances (times |normal|) of q0, q1, q2 to `plane`, those within the rounding tolerance
/// snapped to exactly 0. Positive is on the outer side.
inline void signedDistances(const TrianglePlane& plane, const Eigen::Vector3d& q0, const Eigen::Vector3d& q1,
                            const Eigen::Vector3d& q2, double d[3]) {
  const Eigen::Vector3d r0 = q0 - plane.origin;
  const Eigen::Vector3d r1 = q1 - plane.origin;
  const Eigen::Vector3d r2 = q2 - plane.origin;
  d[0] = plane.normal.dot(r0);
  d[1] = plane.normal.dot(r1);
  d[2] = plane.normal.dot(r2);
  const double extent =
      std::max({r0.cwiseAbs().maxCoeff(), r1.cwiseAbs().maxCoeff(), r2.cwiseAbs().maxCoeff()});
  const double tolerance = kSnapRelative * plane.errorScale * extent;
  for (int i = 0; i < 3; ++i) d[i] = std::fabs(d[i]) <= tolerance ? 0.0 : d[i];
}

/// True when x and y are both strictly positive or both strictly negative. Compared by sign rather than by
/// x * y > 0, which underflows to 0 for tiny meshes (the distances scale with length cubed).
inline bool sameStrictSign(double x, double y) {
  return (x > 0.0 && y > 0.0) || (x < 0.0 && y < 0.0);
}

/// True when all three distances are non-zero with one sign: the triangle misses the plane (Möller's
/// early rejection).
inline bool allOnOneSide(const double d[3]) {
  return sameStrictSign(d[0], d[1]) && sameStrictSign(d[0], d[2]);
}

/// True when all three distances are zero: the triangle lies in the plane.
inline bool allInPlane(const double d[3]) {
  return d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0;
}

/// The vertex on its own side of the other plane (Möller 1997, "compute intervals"), for distances that
/// are neither all on one side nor all zero. The two edges from it cross the plane; when the lone vertex
/// lies in the plane both crossings are that vertex, and the formula below never divides by zero.
inline int loneVertex(const double d[3]) {
  if (sameStrictSign(d[0], d[1])) return 2;
  if (sameStrictSign(d[0], d[2])) return 1;
  if (sameStrictSign(d[1], d[2]) || d[0] != 0.0) return 0;
  if (d[1] != 0.0) return 1;
  return 2;
}

/// Interval [lo, hi] of a triangle on the intersection line, from the vertices' coordinates `p` along
/// the line's dominant axis and their distances `d` to the other plane.
inline void lineInterval(const double p[3], const double d[3], double& lo, double& hi) {
  const int a = loneVertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  const double t0 = p[a] + (p[b] - p[a]) * (d[a] / (d[a] - d[b]));
  const double t1 = p[a] + (p[c] - p[a]) * (d[a] / (d[a] - d[c]));
  lo = std::min(t0, t1);
  hi = std::max(t0, t1);
}

/// The same crossing points in 3-D: the segment where triangle v meets the other plane.
inline void planeCrossing(const Eigen::Vector3d* const v[3], const double d[3], Eigen::Vector3d& s0,
                          Eigen::Vector3d& s1) {
  const int a = loneVertex(d);
  const int b = a == 2 ? 0 : a + 1;
  const int c = b == 2 ? 0 : b + 1;
  s0 = *v[a] + (*v[b] - *v[a]) * (d[a] / (d[a] - d[b]));
  s1 = *v[a] + (*v[c] - *v[a]) * (d[a] / (d[a] - d[c]));
}

/// Index of the largest absolute component.
inline int dominantAxis(const Eigen::Vector3d& v) {
  const double x = std::fabs(v.x()), y = std::fabs(v.y()), z = std::fabs(v.z());
  return x >= y ? (x >= z ? 0 : 2) : (y >= z ? 1 : 2);
}

/// Twice the signed area of the 2-D triangle (a, b, c): positive when counter-clockwise.
inline double orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}

/// Margin of the float pre-test below, in units of the scale max|e1| * max|e2| * max_i max|q_i - v0|
/// (infinity norms of the plane triangle's edges and of the other triangle's vertices taken from v0): 64
/// float ulps.
///
/// Why it is enough (u = 2^-24; gamma_k = k u / (1 - k u); E1, E2, R the three factors of the scale, exact):
/// the float edges e = fl(v - v0) and offsets r = fl(q - v0) have relative error u per component; a normal
/// component fl(fl(x y) - fl(z w)) of rounded edges is within gamma_4 (|x y| + |z w|) <= 2 gamma_4 E1 E2 of
/// the exact one; the dot product adds a rounding per product and per sum (gamma_3). Summed over the three
/// terms, |d_float - d_exact| <= (gamma_4 * 6 + gamma_4 (1 + gamma_4) * 6) E1 E2 R < 48.1 u E1 E2 R. The
/// double test computes the same distance to within 1e-15 E1 E2 R and snaps it to 0 when within kSnapRelative
/// (1e-12) of errorScale * extent = E1 E2 R. So |d_float| > 48.2 u E1 E2 R (48.2 u = 2.9e-6 >> 1e-12) proves
/// that the double distance is non-zero after snapping and has d_float's sign. The margin is computed in
/// float from the rounded factors, which costs at most five more roundings of 64 u: still above 63.9 u, with
/// room to spare.
inline constexpr float kFloatSideMargin = 64.0f / 16777216.0f;

/// Range of each factor E1, E2, R inside which the float pre-test is valid: no intermediate overflows
/// (6 E1 E2 R < 2^123), and the absolute error of underflowing products (2^-149 each) stays below 2^-10 of
/// the margin (which is at least 2^-138). Outside it the pre-test abstains and the double test decides.
inline constexpr float kFloatSideMinFactor = 0x1p-40f;
/// Upper end of that range.
inline constexpr float kFloatSideMaxFactor = 0x1p40f;

/// The plane of a triangle in float, for floatPlaneSide: computed once and tested against many triangles.
struct FloatPlane {
  Eigen::Vector3f origin;  ///< v0.
  Eigen::Vector3f normal;  ///< fl((v1 - v0) x (v2 - v0)).
  float marginScale;       ///< kFloatSideMargin * max|e1| * max|e2|: the margin per unit of extent.
  bool inRange;  ///< Both edge factors within [kFloatSideMinFactor, kFloatSideMaxFactor] (false for NaN).
};

/// The float plane of triangle (v0, v1, v2).
inline FloatPlane makeFloatPlane(const Eigen::Vector3f& v0, const Eigen::Vector3f& v1,
                                 const Eigen::Vector3f& v2) {
  const Eigen::Vector3f e1 = v1 - v0;
  const Eigen::Vector3f e2 = v2 - v0;
  const float edge1 = e1.cwiseAbs().maxCoeff();
  const float edge2 = e2.cwiseAbs().maxCoeff();
  FloatPlane plane;
  plane.origin = v0;
  plane.normal = e1.cross(e2);
  plane.marginScale = kFloatSideMargin * edge1 * edge2;
  // `&` rather than `&&`: comparisons are cheaper than the branches; NaN fails every one of them.
  plane.inRange = (edge1 >= kFloatSideMinFactor) & (edge1 <= kFloatSideMaxFactor) &
                  (edge2 >= kFloatSideMinFactor) & (edge2 <= kFloatSideMaxFactor);
  return plane;
}

/// What float arithmetic can prove about the signed distances of q0, q1, q2 to a triangle's plane as
/// signedDistances computes them in double: bits of floatPlaneSide's result. (Bits rather than a struct of
/// two bools: the compiler keeps such a struct in memory, which stops it from making vector code of the
/// loops.)
enum FloatSideBits : unsigned {
  kAllOneSide = 1,  ///< All three are non-zero with one sign: allOnOneSide() will hold.
  kSomeOff = 2,     ///< At least one is non-zero: allInPlane() will not hold.
};

/// Float pre-test of q0, q1, q2 against `plane`, conservative by kFloatSideMargin: it only reports what the
/// double test is certain to find (FloatSideBits). NaN, infinite or out-of-range input reports nothing.
/// Branch-free: in the near phase the outcome is close to a coin toss, so a branch would be mispredicted half
/// the time.
inline unsigned floatPlaneSide(const FloatPlane& plane, const Eigen::Vector3f& q0, const Eigen::Vector3f& q1,
                               const Eigen::Vector3f& q2) {
  const Eigen::Vector3f r0 = q0 - plane.origin, r1 = q1 - plane.origin, r2 = q2 - plane.origin;
  const float d0 = plane.normal.dot(r0), d1 = plane.normal.dot(r1), d2 = plane.normal.dot(r2);
  const float extent = r0.cwiseAbs().cwiseMax(r1.cwiseAbs()).cwiseMax(r2.cwiseAbs()).maxCoeff();
  const bool inRange = plane.inRange & (extent >= kFloatSideMinFactor) & (extent <= kFloatSideMaxFactor);
  const float m = plane.marginScale * extent;
  const bool above = (d0 > m) & (d1 > m) & (d2 > m);
  const bool below = (d0 < -m) & (d1 < -m) & (d2 < -m);
  const bool off = (std::fabs(d0) > m) | (std::fabs(d1) > m) | (std::fabs(d2) > m);
  return (unsigned(inRange & (above | below)) * kAllOneSide) | (unsigned(inRange & off) * kSomeOff);
}

/// True when float arithmetic proves that trianglesIntersect's double test answers "no" at one of Möller's
/// two plane rejections: all of b on one side of a's plane, or (b certainly not in a's plane, so the coplanar
/// branch is not taken) all of a on one side of b's plane. A degenerate triangle is rejected by the double
/// test before or instead of these steps, so it answers "no" in every branch this function can prove.
/// `planeA` is makeFloatPlane(a[0], a[1], a[2]), so a caller can reuse it for many b.
/// Several times cheaper than the double test, and most candidate pairs of the middle phase end here.
inline bool floatCertainlyApart(const FloatPlane& planeA, const Eigen::Vector3f& a0,
                                const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                                const Eigen::Vector3f& b0, const Eigen::Vector3f& b1,
                                const Eigen::Vector3f& b2) {
  const unsigned sideB = floatPlaneSide(planeA, b0, b1, b2);
  if (sideB & kAllOneSide) return true;
  if (!(sideB & kSomeOff)) return false;
  return floatPlaneSide(makeFloatPlane(b0, b1, b2), a0, a1, a2) & kAllOneSide;
}

/// floatCertainlyApart computed without branches (both plane tests always run), for loops over many pairs
/// that the compiler can turn into vector code: a data-dependent branch per pair is mispredicted about half
/// the time. Returns 1 for "certainly apart", else 0 (an integer: a conversion to bool also stops the
/// vectoriser).
inline unsigned floatCertainlyApartBranchFree(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1,
                                              const Eigen::Vector3f& a2, const Eigen::Vector3f& b0,
                                              const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  const unsigned sideB = floatPlaneSide(makeFloatPlane(a0, a1, a2), b0, b1, b2);
  const unsigned sideA = floatPlaneSide(makeFloatPlane(b0, b1, b2), a0, a1, a2);
  return (sideB | ((sideB >> 1) & sideA)) & kAllOneSide;
}

/// `c ? x : y` on the bits, for the branch-free tests: written as a plain conditional, the compiler moves the
/// arithmetic that uses the result into the branches, which it may then not run unconditionally (float
/// operations can trap), so the loop stops being vector code.
inline float selectFloat(bool c, float x, float y) {
  std::uint32_t xBits, yBits;
  std::memcpy(&xBits, &x, sizeof x);
  std::memcpy(&yBits, &y, sizeof y);
  const std::uint32_t mask = 0u - static_cast<std::uint32_t>(c);
  const std::uint32_t bits = (xBits & mask) | (yBits & ~mask);
  float out;
  std::memcpy(&out, &bits, sizeof out);
  return out;
}

/// Range of every factor (E1, E2, R of both planes) inside which floatIntervalsApartBranchFree is valid:
/// narrower than the plane test's, because it multiplies four factors (the line direction nA x nB), which
/// must neither overflow nor lose precision to underflow. Outside it the interval stage abstains.
inline constexpr float kFloatIntervalMinFactor = 0x1p-20f;
/// Upper end of that range.
inline constexpr float kFloatIntervalMaxFactor = 0x1p20f;

/// The interval stage needs the planes' intersection line to be well defined: its float direction must have
/// a component of at least this times EA1 EA2 EB1 EB2 (about sin 1e-3 for well-shaped triangles), so that
/// the direction's rounding (below 2^-17 of that product in float, 2^-46 in double) cannot matter.
inline constexpr float kFloatLineMinimum = 0x1p-10f;

/// Float proof that Möller's interval step (step 3) rejects the pair in double: both triangles cross the
/// other's plane, and their intervals on the planes' intersection line L are disjoint by more than float and
/// double rounding could explain. Run on the pairs that floatCertainlyApartBranchFree could not reject (a
/// third of the candidates of the thesis scene; two thirds of those are rejected here), it leaves the double
/// test to the pairs that intersect or nearly do. Returns 1 for "certainly apart", else 0; branch-free.
///
/// Why the answer is the double test's (u = 2^-24; m the plane test's margin, which bounds the float error of
/// every distance, see kFloatSideMargin):
/// - Every distance is |d| > 2m, so float and double agree on every sign, the double snaps none of them to 0
///   (so its coplanar branch is not taken) and both pick the same lone vertex and the same two edges per
///   triangle. The exact crossing points of those edges with the other plane lie on L.
/// - A crossing point is p_a + (p_b - p_a) r, r = d_a / (d_a - d_b) in [0, 1]. With both distances off by at
///   most m, and |d_a| + |d_b| = S >= 4m, r is off by at most 2m / (S - 2m) <= 4m / S, plus 3.1u for the
///   float division; the crossing's coordinate is then off by at most W (4m / S + 5.2u) + u |t| on any axis,
///   W the infinity norm of the edge: the bound errA / errB below, with room to spare (W (4m/S + 8u) + 4u P,
///   P the largest coordinate magnitude of the six vertices).
/// - Float tests on its own axis k, the largest component of its direction D; the double on k', the largest
///   of its own. Two points of L differ along axis x by (their distance along L) |D_x| / |D|, so a gap on k
///   is at most the gap on k' times |D_k| / |D_k'|, which is below 1 + 2^-34 when |D_k| >= kFloatLineMinimum
///   EA1 EA2 EB1 EB2 (the double's direction is within 2^-46 of that product).
/// - The intervals are called apart when their float gap exceeds 2 (errA + errB): the true gap on k then
///   exceeds errA + errB less the comparison's own rounding (>= 7u P and 7u W), which covers the double's
///   rounding of its crossing points on k' (below 2^-50 (W + P) and W 1e-15 E1 E2 R / S).
/// A degenerate triangle is rejected by the double test anyway, so "apart" is its answer for those too.
GPUCOL_FORCE_INLINE unsigned floatIntervalsApartBranchFree(
    const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
    const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  constexpr float u = 1.0f / 16777216.0f;
  const Eigen::Vector3f e1 = a1 - a0, e2 = a2 - a0, f1 = b1 - b0, f2 = b2 - b0;
  const Eigen::Vector3f nA = e1.cross(e2), nB = f1.cross(f2);
  const float ea1 = e1.cwiseAbs().maxCoeff(), ea2 = e2.cwiseAbs().maxCoeff();
  const float eb1 = f1.cwiseAbs().maxCoeff(), eb2 = f2.cwiseAbs().maxCoeff();
  // Distances as floatPlaneSide computes them (same expressions, so kFloatSideMargin's bound holds).
  const Eigen::Vector3f rb0 = b0 - a0, rb1 = b1 - a0, rb2 = b2 - a0;
  const Eigen::Vector3f ra0 = a0 - b0, ra1 = a1 - b0, ra2 = a2 - b0;
  const float dB[3] = {nA.dot(rb0), nA.dot(rb1), nA.dot(rb2)};
  const float dA[3] = {nB.dot(ra0), nB.dot(ra1), nB.dot(ra2)};
  const float extentB = rb0.cwiseAbs().cwiseMax(rb1.cwiseAbs()).cwiseMax(rb2.cwiseAbs()).maxCoeff();
  const float extentA = ra0.cwiseAbs().cwiseMax(ra1.cwiseAbs()).cwiseMax(ra2.cwiseAbs()).maxCoeff();
  const float mB = kFloatSideMargin * ea1 * ea2 * extentB;
  const float mA = kFloatSideMargin * eb1 * eb2 * extentA;
  auto inRange = [](float x) { return (x >= kFloatIntervalMinFactor) & (x <= kFloatIntervalMaxFactor); };
  bool valid =
      inRange(ea1) & inRange(ea2) & inRange(eb1) & inRange(eb2) & inRange(extentA) & inRange(extentB);
  for (int i = 0; i < 3; ++i) valid &= (std::fabs(dB[i]) > 2.0f * mB) & (std::fabs(dA[i]) > 2.0f * mA);
  // Both triangles cross the other's plane: neither all above nor all below.
  valid &= !((dB[0] > 0) & (dB[1] > 0) & (dB[2] > 0)) & !((dB[0] < 0) & (dB[1] < 0) & (dB[2] < 0));
  valid &= !((dA[0] > 0) & (dA[1] > 0) & (dA[2] > 0)) & !((dA[0] < 0) & (dA[1] < 0) & (dA[2] < 0));

  const Eigen::Vector3f direction = nA.cross(nB);
  const float dx = std::fabs(direction.x()), dy = std::fabs(direction.y()), dz = std::fabs(direction.z());
  // Selections by value rather than by index, so that a loop over pairs stays vector code.
  const bool useX = (dx >= dy) & (dx >= dz), useY = !useX & (dy >= dz);
  valid &= std::max(std::max(dx, dy), dz) >= kFloatLineMinimum * (ea1 * ea2) * (eb1 * eb2);
  auto onAxis = [&](const Eigen::Vector3f& v) {
    return selectFloat(useX, v.x(), selectFloat(useY, v.y(), v.z()));
  };

  const float largest =
      std::max({a0.cwiseAbs().maxCoeff(), a1.cwiseAbs().maxCoeff(), a2.cwiseAbs().maxCoeff(),
                b0.cwiseAbs().maxCoeff(), b1.cwiseAbs().maxCoeff(), b2.cwiseAbs().maxCoeff()});
  // One triangle's interval on the axis and the bound on its endpoints' error.
  auto interval = [&](const Eigen::Vector3f& v0, const Eigen::Vector3f& v1, const Eigen::Vector3f& v2,
                      const float(&d)[3], float m, float edges, float& lo, float& hi, float& error) {
    const float p0 = onAxis(v0), p1 = onAxis(v1), p2 = onAxis(v2);
    // The lone vertex as loneVertex() picks it for non-zero distances, then the next two in cyclic order.
    const bool lone2 = (d[0] > 0) == (d[1] > 0), lone1 = !lone2 & ((d[0] > 0) == (d[2] > 0));
    const float dLone = selectFloat(lone2, d[2], selectFloat(lone1, d[1], d[0]));
    const float pLone = selectFloat(lone2, p2, selectFloat(lone1, p1, p0));
    const float dNext = selectFloat(lone2, d[0], selectFloat(lone1, d[2], d[1]));
    const float pNext = selectFloat(lone2, p0, selectFloat(lone1, p2, p1));
    const float dLast = selectFloat(lone2, d[1], selectFloat(lone1, d[0], d[2]));
    const float pLast = selectFloat(lone2, p1, selectFloat(lone1, p0, p2));
    const float inverse1 = 1.0f / (dLone - dNext), inverse2 = 1.0f / (dLone - dLast);
    const float t1 = pLone + (pNext - pLone) * (dLone * inverse1);
    const float t2 = pLone + (pLast - pLone) * (dLone * inverse2);
    lo = std::min(t1, t2);
    hi = std::max(t1, t2);
    const float inverseSmallest = std::max(std::fabs(inverse1), std::fabs(inverse2));
    error = edges * (4.0f * m * inverseSmallest + 8.0f * u) + 4.0f * u * largest;
  };
  const float edgesA = std::max(std::max(ea1, ea2), (a2 - a1).cwiseAbs().maxCoeff());
  const float edgesB = std::max(std::max(eb1, eb2), (b2 - b1).cwiseAbs().maxCoeff());
  float loA, hiA, errorA, loB, hiB, errorB;
  interval(a0, a1, a2, dA, mA, edgesA, loA, hiA, errorA);
  interval(b0, b1, b2, dB, mB, edgesB, loB, hiB, errorB);
  const float tolerance = 2.0f * (errorA + errorB);
  return unsigned(valid & ((loA > hiB + tolerance) | (loB > hiA + tolerance)));
}

/// trianglesIntersect without its float pre-test (defined in triangle_intersection.cpp), for callers that
/// have run floatCertainlyApart themselves: Möller's test in double, as documented there.
bool trianglesIntersectDouble(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                              const Eigen::Vector3f& b0, const Eigen::Vector3f& b1,
                              const Eigen::Vector3f& b2);

/// generateContact that also says whether the pair intersects (defined in triangle_contact.cpp).
/// generateContact runs Möller's test in the same arithmetic as trianglesIntersectDouble before it makes a
/// contact, so `intersects` is exactly trianglesIntersectDouble's answer, and a caller that needs both (the
/// near phase keeps intersecting pairs whose contact is dropped) runs the test once instead of twice.
std::optional<TriangleContact> generateContactAndTest(const Eigen::Vector3f (&a)[3],
                                                      const Eigen::Vector3f (&b)[3], bool& intersects);

/// floatCertainlyApart for one pair.
inline bool floatCertainlyApart(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1,
                                const Eigen::Vector3f& a2, const Eigen::Vector3f& b0,
                                const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  return floatCertainlyApart(makeFloatPlane(a0, a1, a2), a0, a1, a2, b0, b1, b2);
}

}  // namespace gpucol::detail
