#pragma once

// The C++ face of the triangle tests whose mathematics lives in shared_math/ (one source for the CPU and the
// OpenCL kernels): the double test's plane and signed distances (triangle_test.h) and the float pre-tests
// (triangle_pretest.h), as the near phase and the tests call them. Inline and allocation-free: it is the
// inner loop of the near phase.
//
// Precision: the inputs are float, the arithmetic is double. A product of two floats is exact in
// double and a difference of two nearby floats too, so the normal e1 x e2 and the signed distances
// carry about 1e-16 relative error instead of float's 1e-7. That matters for nearly parallel planes:
// an error delta in a distance moves the intersection line sideways by delta / sin(angle), and in
// float a pair of faces 2e-6 rad apart was reported intersecting while 11% of its size apart (found by
// the random near-coplanar tests). On a CPU double costs the same as float for this scalar code.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "narrowphase/triangle_contact.h"
#include "shared_math/triangle_pretest.h"
#include "shared_math/triangle_test.h"

namespace gpucol::detail {

/// Inlines a function into its callers even where the compiler's estimate says no: the batched loops of the
/// near phase are vector code only when the pair tests they call are inlined into them.
#if defined(__GNUC__)
#define GPUCOL_FORCE_INLINE inline __attribute__((always_inline))
#else
#define GPUCOL_FORCE_INLINE inline
#endif

/// The plane of a triangle (gpucol_make_plane): v0, the unnormalised normal e1 x e2, the scale of its
/// rounding error, and whether it is degenerate.
using TrianglePlane = GpucolPlane;

/// The plane of triangle (v0, v1, v2).
inline TrianglePlane makePlane(const Eigen::Vector3d& v0, const Eigen::Vector3d& v1,
                               const Eigen::Vector3d& v2) {
  return gpucol_make_plane(v0.data(), v1.data(), v2.data());
}

/// Signed distances (times |normal|) of q0, q1, q2 to `plane`, those within the rounding tolerance
/// snapped to exactly 0 (gpucol_signed_distances).
inline void signedDistances(const TrianglePlane& plane, const Eigen::Vector3d& q0, const Eigen::Vector3d& q1,
                            const Eigen::Vector3d& q2, double d[3]) {
  gpucol_signed_distances(&plane, q0.data(), q1.data(), q2.data(), d);
}

/// True when all three distances are non-zero with one sign (gpucol_all_on_one_side).
inline bool allOnOneSide(const double d[3]) {
  return gpucol_all_on_one_side(d);
}

/// True when all three distances are zero (gpucol_all_in_plane).
inline bool allInPlane(const double d[3]) {
  return gpucol_all_in_plane(d);
}

/// A triangle's corner as the float pre-tests of shared_math/triangle_pretest.h take it (one candidate per
/// lane on the CPU).
inline GpucolLanes3 floatLanes(const Eigen::Vector3f& v) {
  return gpucol_lanes3(v.x(), v.y(), v.z());
}

/// gpucol_float_certainly_apart on one pair: 1 when float arithmetic proves that trianglesIntersect's double
/// test answers "no" at one of Möller's two plane rejections, else 0 (an integer: a conversion to bool stops
/// the vectoriser). Both plane tests always run, so loops over many pairs become vector code.
GPUCOL_FORCE_INLINE unsigned floatCertainlyApartBranchFree(
    const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
    const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  return unsigned(gpucol_float_certainly_apart(floatLanes(a0), floatLanes(a1), floatLanes(a2), floatLanes(b0),
                                               floatLanes(b1), floatLanes(b2)));
}

/// gpucol_float_intervals_apart on one pair: 1 when float arithmetic proves that Möller's interval step
/// rejects the pair in double, else 0. Run on the pairs floatCertainlyApartBranchFree could not reject.
GPUCOL_FORCE_INLINE unsigned floatIntervalsApartBranchFree(
    const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
    const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  return unsigned(gpucol_float_intervals_apart(floatLanes(a0), floatLanes(a1), floatLanes(a2), floatLanes(b0),
                                               floatLanes(b1), floatLanes(b2)));
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

/// floatCertainlyApartBranchFree's answer as a bool, for one pair.
inline bool floatCertainlyApart(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1,
                                const Eigen::Vector3f& a2, const Eigen::Vector3f& b0,
                                const Eigen::Vector3f& b1, const Eigen::Vector3f& b2) {
  return floatCertainlyApartBranchFree(a0, a1, a2, b0, b1, b2) != 0;
}

}  // namespace gpucol::detail
