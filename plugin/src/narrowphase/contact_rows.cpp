#include "narrowphase/contact_rows.h"

#include <algorithm>
#include <cmath>

#include "bvh/avx2_clones.h"
#include "narrowphase/triangle_plane.h"

namespace gpucol::detail {
namespace {

// The helpers below are generateContactAndTest's steps on plain doubles, with selections by value, never by
// index.

struct Vec {
  double x, y, z;
};

GPUCOL_FORCE_INLINE Vec operator-(const Vec& a, const Vec& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

/// Eigen's dot product of 3-vectors: (x + y) + z.
GPUCOL_FORCE_INLINE double dot(const Vec& a, const Vec& b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}

/// Eigen's cross product.
GPUCOL_FORCE_INLINE Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Largest absolute component (Eigen's cwiseAbs().maxCoeff(); a maximum is exact in any order).
GPUCOL_FORCE_INLINE double maxAbs(const Vec& v) {
  return std::max(std::max(std::fabs(v.x), std::fabs(v.y)), std::fabs(v.z));
}

GPUCOL_FORCE_INLINE Vec select(bool c, const Vec& a, const Vec& b) {
  return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z};
}

/// std::min({x, y, z}) and std::max({x, y, z}): the first of equal values, as the initializer-list forms.
GPUCOL_FORCE_INLINE double min3(double x, double y, double z) {
  return std::min(std::min(x, y), z);
}
GPUCOL_FORCE_INLINE double max3(double x, double y, double z) {
  return std::max(std::max(x, y), z);
}

/// sameStrictSign of triangle_plane.h without a branch.
GPUCOL_FORCE_INLINE bool sameSign(double x, double y) {
  return ((x > 0.0) & (y > 0.0)) | ((x < 0.0) & (y < 0.0));
}

/// makePlane and signedDistances: the unnormalised normal of triangle (p0, p1, p2), whether it is degenerate,
/// and the snapped signed distances of q0, q1, q2 to its plane.
struct PlaneDistances {
  Vec normal;
  bool degenerate;
  double d[3];
};

GPUCOL_FORCE_INLINE PlaneDistances planeDistances(const Vec& p0, const Vec& p1, const Vec& p2, const Vec& q0,
                                                  const Vec& q1, const Vec& q2) {
  const Vec e1 = p1 - p0, e2 = p2 - p0;
  PlaneDistances r;
  r.normal = cross(e1, e2);
  const double errorScale = maxAbs(e1) * maxAbs(e2);
  r.degenerate = !(dot(r.normal, r.normal) > kDegenerateSin2 * dot(e1, e1) * dot(e2, e2));
  const Vec r0 = q0 - p0, r1 = q1 - p0, r2 = q2 - p0;
  r.d[0] = dot(r.normal, r0);
  r.d[1] = dot(r.normal, r1);
  r.d[2] = dot(r.normal, r2);
  const double extent = max3(maxAbs(r0), maxAbs(r1), maxAbs(r2));
  const double tolerance = kSnapRelative * errorScale * extent;
  for (double& d : r.d) d = std::fabs(d) <= tolerance ? 0.0 : d;
  return r;
}

/// planeCrossing: the segment where triangle (v0, v1, v2) meets the other plane, from its vertices'
/// distances d to it; the lone vertex as loneVertex() picks it.
GPUCOL_FORCE_INLINE void planeCrossing(const Vec& v0, const Vec& v1, const Vec& v2, const double (&d)[3],
                                       Vec& s0, Vec& s1) {
  const bool s01 = sameSign(d[0], d[1]), s02 = sameSign(d[0], d[2]);
  const bool firstAlone = sameSign(d[1], d[2]) | (d[0] != 0.0);
  const bool zero = (!s01) & (!s02) & firstAlone;
  const bool one = (!s01) & (s02 | ((!firstAlone) & (d[1] != 0.0)));
  // The lone vertex a and the next two in cyclic order, b and c.
  const Vec va = select(zero, v0, select(one, v1, v2));
  const Vec vb = select(zero, v1, select(one, v2, v0));
  const Vec vc = select(zero, v2, select(one, v0, v1));
  const double da = zero ? d[0] : (one ? d[1] : d[2]);
  const double db = zero ? d[1] : (one ? d[2] : d[0]);
  const double dc = zero ? d[2] : (one ? d[0] : d[1]);
  const double t0 = da / (da - db), t1 = da / (da - dc);
  const Vec ab = vb - va, ac = vc - va;
  s0 = {va.x + ab.x * t0, va.y + ab.y * t0, va.z + ab.z * t0};
  s1 = {va.x + ac.x * t1, va.y + ac.y * t1, va.z + ac.z * t1};
}

}  // namespace

GPUCOL_AVX2_CLONES void generateContactRows(const float* triangles, std::size_t stride, std::size_t count,
                                            float* contacts, std::uint32_t* outcome) {
  for (std::size_t t = 0; t < count; ++t) {
    const auto vertex = [&](int v) -> Vec {
      const float* p = triangles + 3 * v * stride + t;
      return {double(p[0]), double(p[stride]), double(p[2 * stride])};
    };
    const Vec a0 = vertex(0), a1 = vertex(1), a2 = vertex(2);
    const Vec b0 = vertex(3), b1 = vertex(4), b2 = vertex(5);

    // Möller's early rejections: a degenerate triangle, or one triangle wholly on one side of the other's
    // plane.
    const PlaneDistances onA = planeDistances(a0, a1, a2, b0, b1, b2);  // B's distances to A's plane
    const PlaneDistances onB = planeDistances(b0, b1, b2, a0, a1, a2);  // A's distances to B's plane
    const double(&dB)[3] = onA.d;
    const double(&dA)[3] = onB.d;
    const bool rejected = onA.degenerate | (sameSign(dB[0], dB[1]) & sameSign(dB[0], dB[2])) |
                          onB.degenerate | (sameSign(dA[0], dA[1]) & sameSign(dA[0], dA[2]));
    const bool coplanar = ((dB[0] == 0.0) & (dB[1] == 0.0) & (dB[2] == 0.0)) |
                          ((dA[0] == 0.0) & (dA[1] == 0.0) & (dA[2] == 0.0));
    // x - x is 0 for a finite x and NaN otherwise. A non-finite coordinate goes to the one-pair function,
    // whose early returns decide which of its NaN comparisons count.
    const Vec zeros[6] = {a0 - a0, a1 - a1, a2 - a2, b0 - b0, b1 - b1, b2 - b2};
    double sum = 0.0;
    for (const Vec& z : zeros) sum += (z.x + z.y) + z.z;
    const bool finite = sum == 0.0;

    const double lengthA = std::sqrt(dot(onA.normal, onA.normal));
    const double lengthB = std::sqrt(dot(onB.normal, onB.normal));
    const Vec nA = {onA.normal.x / lengthA, onA.normal.y / lengthA, onA.normal.z / lengthA};
    const Vec nB = {onB.normal.x / lengthB, onB.normal.y / lengthB, onB.normal.z / lengthB};

    // Möller's interval test on the intersection line, on its dominant axis, with the crossings in 3-D.
    const Vec line = cross(onA.normal, onB.normal);
    const double fx = std::fabs(line.x), fy = std::fabs(line.y), fz = std::fabs(line.z);
    const bool onX = (fx >= fy) & (fx >= fz), onY = !(fx >= fy) & (fy >= fz);
    const auto onAxis = [&](const Vec& v) { return onX ? v.x : (onY ? v.y : v.z); };
    Vec sA0, sA1, sB0, sB1;
    planeCrossing(a0, a1, a2, dA, sA0, sA1);
    planeCrossing(b0, b1, b2, dB, sB0, sB1);
    const bool swapA = onAxis(sA1) < onAxis(sA0), swapB = onAxis(sB1) < onAxis(sB0);
    const Vec lowA = select(swapA, sA1, sA0), highA = select(swapA, sA0, sA1);
    const Vec lowB = select(swapB, sB1, sB0), highB = select(swapB, sB0, sB1);
    const double lowAOn = onAxis(lowA), highAOn = onAxis(highA), lowBOn = onAxis(lowB),
                 highBOn = onAxis(highB);
    const bool separated = (lowAOn > highBOn) | (lowBOn > highAOn);

    // §5.3.4: the smaller move of a triangle along the other's normal out of its plane.
    const double moveA = std::max(0.0, -min3(dA[0], dA[1], dA[2]) / lengthB);
    const double moveB = std::max(0.0, -min3(dB[0], dB[1], dB[2]) / lengthA);
    const bool aMoves = moveA <= moveB;
    const double move = aMoves ? moveA : moveB;

    // §5.3.4: dropped when sliding apart along the line is shorter than the depth (Eigen's normalized():
    // the vector itself when its squared norm is not positive).
    const double lineSquared = dot(line, line);
    const double lineLength = std::sqrt(lineSquared);
    const Vec u =
        lineSquared > 0.0 ? Vec{line.x / lineLength, line.y / lineLength, line.z / lineLength} : line;
    const double pA1 = dot(u, a1 - a0), pA2 = dot(u, a2 - a0);
    const double pB0 = dot(u, b0 - a0), pB1 = dot(u, b1 - a0), pB2 = dot(u, b2 - a0);
    const double slide =
        std::min(max3(0.0, pA1, pA2) - min3(pB0, pB1, pB2), max3(pB0, pB1, pB2) - min3(0.0, pA1, pA2));

    // The contact: the middle of the common segment, the winning normal, the moving triangle's deepest
    // vertex.
    const Vec low = select(lowAOn >= lowBOn, lowA, lowB);
    const Vec high = select(highAOn <= highBOn, highA, highB);
    const Vec normal = select(aMoves, nB, Vec{-nA.x, -nA.y, -nA.z});
    const double d0 = aMoves ? dA[0] : dB[0], d1 = aMoves ? dA[1] : dB[1], d2 = aMoves ? dA[2] : dB[2];
    const bool deepest0 = (d0 <= d1) & (d0 <= d2), deepest1 = !(d0 <= d1) & (d1 <= d2);
    const Vec deepestVertex = select(aMoves, select(deepest0, a0, select(deepest1, a1, a2)),
                                     select(deepest0, b0, select(deepest1, b1, b2)));
    float* const c = contacts + t;
    c[0] = float(0.5 * (low.x + high.x));
    c[stride] = float(0.5 * (low.y + high.y));
    c[2 * stride] = float(0.5 * (low.z + high.z));
    c[3 * stride] = float(normal.x);
    c[4 * stride] = float(normal.y);
    c[5 * stride] = float(normal.z);
    c[6 * stride] = float(0.0 - move);
    c[7 * stride] = float(deepestVertex.x);
    c[8 * stride] = float(deepestVertex.y);
    c[9 * stride] = float(deepestVertex.z);

    // The outcome as arithmetic on the conditions: GCC's if-conversion does not take a chain of selections
    // that joins five values.
    const bool onePair = (!finite) | ((!rejected) & coplanar);
    const bool intersects = (!onePair) & (!rejected) & (!separated);
    const std::uint32_t found =
        std::uint32_t(onePair) * kRowOnePair +
        std::uint32_t(intersects) * (slide < move ? kRowIntersectsNoContact : kRowContact);
    outcome[t] = found | (aMoves ? kRowOnFaceOfB : 0u) | (dot(nA, nB) > 0.0 ? kRowSameFacing : 0u);
  }
}

}  // namespace gpucol::detail
