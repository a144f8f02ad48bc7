#include "narrowphase/contact_rows.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "bvh/avx2_clones.h"
#include "narrowphase/triangle_plane.h"

// The helpers below take and return 32-byte vectors, and all are always inlined (GPUCOL_FORCE_INLINE, also at
// -O0; no lambdas, which would not be): a helper called rather than inlined would be compiled once, for the
// baseline target, and the AVX2 clone would pass it its vectors in other registers (a debug build with a lambda
// crashed so). So no call ever passes one, and the compiler's note about that ABI does not apply.
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace gpucol::detail {
namespace {

// generateContactAndTest's steps on four pairs at once, one per lane of a vector of doubles (GCC/Clang vector
// extensions: one AVX instruction per step in the AVX2 clone, two SSE ones in the baseline clone). Each lane
// sees the same IEEE operations in the same order as the one-pair function, so the same bits; choices are
// made by masks (a lane where a comparison holds has all bits set), never by branches.

constexpr std::size_t kLanes = 4;
using Doubles = double __attribute__((vector_size(32)));
using Mask = std::int64_t __attribute__((vector_size(32)));
using Floats = float __attribute__((vector_size(16)));
using Words = std::uint32_t __attribute__((vector_size(16)));

GPUCOL_FORCE_INLINE Doubles splat(double v) {
  return Doubles{v, v, v, v};
}

/// c ? a : b lane by lane, by bits (so no arithmetic can change a value).
GPUCOL_FORCE_INLINE Doubles pick(Mask c, Doubles a, Doubles b) {
  return reinterpret_cast<Doubles>((c & reinterpret_cast<Mask>(a)) | (~c & reinterpret_cast<Mask>(b)));
}

/// std::fabs: the sign bit cleared.
GPUCOL_FORCE_INLINE Doubles abs(Doubles v) {
  const Mask noSign = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
  return reinterpret_cast<Doubles>(reinterpret_cast<Mask>(v) & noSign);
}

/// std::min and std::max, with their choice where the comparison fails (equal values, NaN): the first.
GPUCOL_FORCE_INLINE Doubles min(Doubles a, Doubles b) {
  return pick(b < a, b, a);
}
GPUCOL_FORCE_INLINE Doubles max(Doubles a, Doubles b) {
  return pick(a < b, b, a);
}
GPUCOL_FORCE_INLINE Doubles min3(Doubles x, Doubles y, Doubles z) {
  return min(min(x, y), z);
}
GPUCOL_FORCE_INLINE Doubles max3(Doubles x, Doubles y, Doubles z) {
  return max(max(x, y), z);
}

/// std::sqrt of each lane (correctly rounded, so the same bits whichever instruction the compiler picks).
GPUCOL_FORCE_INLINE Doubles sqrt(Doubles v) {
  return Doubles{std::sqrt(v[0]), std::sqrt(v[1]), std::sqrt(v[2]), std::sqrt(v[3])};
}

struct Vec {
  Doubles x, y, z;
};

GPUCOL_FORCE_INLINE Vec operator-(const Vec& a, const Vec& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

GPUCOL_FORCE_INLINE Vec divide(const Vec& v, Doubles s) {
  return {v.x / s, v.y / s, v.z / s};
}

/// Eigen's dot product of 3-vectors: (x + y) + z.
GPUCOL_FORCE_INLINE Doubles dot(const Vec& a, const Vec& b) {
  return (a.x * b.x + a.y * b.y) + a.z * b.z;
}

/// Eigen's cross product.
GPUCOL_FORCE_INLINE Vec cross(const Vec& a, const Vec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Largest absolute component (Eigen's cwiseAbs().maxCoeff(); a maximum is exact in any order).
GPUCOL_FORCE_INLINE Doubles maxAbs(const Vec& v) {
  return max(max(abs(v.x), abs(v.y)), abs(v.z));
}

GPUCOL_FORCE_INLINE Vec pick(Mask c, const Vec& a, const Vec& b) {
  return {pick(c, a.x, b.x), pick(c, a.y, b.y), pick(c, a.z, b.z)};
}

/// sameStrictSign of triangle_plane.h.
GPUCOL_FORCE_INLINE Mask sameSign(Doubles x, Doubles y) {
  const Doubles zero = splat(0.0);
  return ((x > zero) & (y > zero)) | ((x < zero) & (y < zero));
}

/// makePlane and signedDistances: the unnormalised normal of triangle (p0, p1, p2), whether it is degenerate,
/// and the snapped signed distances of q0, q1, q2 to its plane.
struct PlaneDistances {
  Vec normal;
  Mask degenerate;
  Doubles d[3];
};

GPUCOL_FORCE_INLINE PlaneDistances planeDistances(const Vec& p0, const Vec& p1, const Vec& p2, const Vec& q0,
                                                  const Vec& q1, const Vec& q2) {
  const Vec e1 = p1 - p0, e2 = p2 - p0;
  PlaneDistances r;
  r.normal = cross(e1, e2);
  const Doubles errorScale = maxAbs(e1) * maxAbs(e2);
  r.degenerate = ~(dot(r.normal, r.normal) > splat(kDegenerateSin2) * dot(e1, e1) * dot(e2, e2));
  const Vec r0 = q0 - p0, r1 = q1 - p0, r2 = q2 - p0;
  r.d[0] = dot(r.normal, r0);
  r.d[1] = dot(r.normal, r1);
  r.d[2] = dot(r.normal, r2);
  const Doubles extent = max3(maxAbs(r0), maxAbs(r1), maxAbs(r2));
  const Doubles tolerance = splat(kSnapRelative) * errorScale * extent;
  for (Doubles& d : r.d) d = pick(abs(d) <= tolerance, splat(0.0), d);
  return r;
}

/// planeCrossing: the segment where triangle (v0, v1, v2) meets the other plane, from its vertices'
/// distances d to it; the lone vertex as loneVertex() picks it.
GPUCOL_FORCE_INLINE void planeCrossing(const Vec& v0, const Vec& v1, const Vec& v2, const Doubles (&d)[3],
                                       Vec& s0, Vec& s1) {
  const Doubles zeroes = splat(0.0);
  const Mask s01 = sameSign(d[0], d[1]), s02 = sameSign(d[0], d[2]);
  const Mask firstAlone = sameSign(d[1], d[2]) | (d[0] != zeroes);
  const Mask zero = ~s01 & ~s02 & firstAlone;
  const Mask one = ~s01 & (s02 | (~firstAlone & (d[1] != zeroes)));
  // The lone vertex a and the next two in cyclic order, b and c.
  const Vec va = pick(zero, v0, pick(one, v1, v2));
  const Vec vb = pick(zero, v1, pick(one, v2, v0));
  const Vec vc = pick(zero, v2, pick(one, v0, v1));
  const Doubles da = pick(zero, d[0], pick(one, d[1], d[2]));
  const Doubles db = pick(zero, d[1], pick(one, d[2], d[0]));
  const Doubles dc = pick(zero, d[2], pick(one, d[0], d[1]));
  const Doubles t0 = da / (da - db), t1 = da / (da - dc);
  const Vec ab = vb - va, ac = vc - va;
  s0 = {va.x + ab.x * t0, va.y + ab.y * t0, va.z + ab.z * t0};
  s1 = {va.x + ac.x * t1, va.y + ac.y * t1, va.z + ac.z * t1};
}

/// One row's values of four neighbouring pairs, read as doubles; and four results written back as floats.
GPUCOL_FORCE_INLINE Doubles loadLanes(const float* p) {
  Floats v;
  std::memcpy(&v, p, sizeof v);
  return __builtin_convertvector(v, Doubles);
}
GPUCOL_FORCE_INLINE void storeLanes(float* p, Doubles v) {
  const Floats f = __builtin_convertvector(v, Floats);
  std::memcpy(p, &f, sizeof f);
}

/// A pair's vertex v (0-2 A's, 3-5 B's) from the rows, four pairs from `triangles` on.
GPUCOL_FORCE_INLINE Vec loadVertex(const float* triangles, std::size_t stride, int v) {
  const float* p = triangles + 3 * v * stride;
  return {loadLanes(p), loadLanes(p + stride), loadLanes(p + 2 * stride)};
}

/// The intersection line's dominant axis, per lane: x where |x| is largest, else y where |y| >= |z|, else z.
struct DominantAxis {
  Mask onX, onY;
  /// The coordinate of v on that axis.
  GPUCOL_FORCE_INLINE Doubles of(const Vec& v) const { return pick(onX, v.x, pick(onY, v.y, v.z)); }
};

/// `word` in the lanes where m holds, 0 elsewhere.
GPUCOL_FORCE_INLINE Mask wordWhere(Mask m, std::uint32_t word) {
  return m & Mask{word, word, word, word};
}

/// The four pairs whose values start at `triangles` (generateContactRows' layout); results at `contacts` and
/// `outcome`.
GPUCOL_FORCE_INLINE void fourPairs(const float* triangles, std::size_t stride, float* contacts,
                                   std::uint32_t* outcome) {
  const Vec a0 = loadVertex(triangles, stride, 0), a1 = loadVertex(triangles, stride, 1),
            a2 = loadVertex(triangles, stride, 2);
  const Vec b0 = loadVertex(triangles, stride, 3), b1 = loadVertex(triangles, stride, 4),
            b2 = loadVertex(triangles, stride, 5);
  const Doubles zero = splat(0.0);

  // Möller's early rejections: a degenerate triangle, or one triangle wholly on one side of the other's
  // plane.
  const PlaneDistances onA = planeDistances(a0, a1, a2, b0, b1, b2);  // B's distances to A's plane
  const PlaneDistances onB = planeDistances(b0, b1, b2, a0, a1, a2);  // A's distances to B's plane
  const Doubles(&dB)[3] = onA.d;
  const Doubles(&dA)[3] = onB.d;
  const Mask rejected = onA.degenerate | (sameSign(dB[0], dB[1]) & sameSign(dB[0], dB[2])) | onB.degenerate |
                        (sameSign(dA[0], dA[1]) & sameSign(dA[0], dA[2]));
  const Mask coplanar = ((dB[0] == zero) & (dB[1] == zero) & (dB[2] == zero)) |
                        ((dA[0] == zero) & (dA[1] == zero) & (dA[2] == zero));
  // x - x is 0 for a finite x and NaN otherwise. A non-finite coordinate goes to the one-pair function,
  // whose early returns decide which of its NaN comparisons count.
  const Vec zeros[6] = {a0 - a0, a1 - a1, a2 - a2, b0 - b0, b1 - b1, b2 - b2};
  Doubles sum = zero;
  for (const Vec& z : zeros) sum += (z.x + z.y) + z.z;
  const Mask finite = sum == zero;

  const Doubles lengthA = sqrt(dot(onA.normal, onA.normal));
  const Doubles lengthB = sqrt(dot(onB.normal, onB.normal));
  const Vec nA = divide(onA.normal, lengthA);
  const Vec nB = divide(onB.normal, lengthB);

  // Möller's interval test on the intersection line, on its dominant axis, with the crossings in 3-D.
  const Vec line = cross(onA.normal, onB.normal);
  const Doubles fx = abs(line.x), fy = abs(line.y), fz = abs(line.z);
  const DominantAxis axis{(fx >= fy) & (fx >= fz), ~(fx >= fy) & (fy >= fz)};
  Vec sA0, sA1, sB0, sB1;
  planeCrossing(a0, a1, a2, dA, sA0, sA1);
  planeCrossing(b0, b1, b2, dB, sB0, sB1);
  const Mask swapA = axis.of(sA1) < axis.of(sA0), swapB = axis.of(sB1) < axis.of(sB0);
  const Vec lowA = pick(swapA, sA1, sA0), highA = pick(swapA, sA0, sA1);
  const Vec lowB = pick(swapB, sB1, sB0), highB = pick(swapB, sB0, sB1);
  const Doubles lowAOn = axis.of(lowA), highAOn = axis.of(highA), lowBOn = axis.of(lowB),
                highBOn = axis.of(highB);
  const Mask separated = (lowAOn > highBOn) | (lowBOn > highAOn);

  // §5.3.4: the smaller move of a triangle along the other's normal out of its plane.
  const Doubles moveA = max(zero, -min3(dA[0], dA[1], dA[2]) / lengthB);
  const Doubles moveB = max(zero, -min3(dB[0], dB[1], dB[2]) / lengthA);
  const Mask aMoves = moveA <= moveB;
  const Doubles move = pick(aMoves, moveA, moveB);

  // §5.3.4: dropped when sliding apart along the line is shorter than the depth (Eigen's normalized():
  // the vector itself when its squared norm is not positive).
  const Doubles lineSquared = dot(line, line);
  const Vec u = pick(lineSquared > zero, divide(line, sqrt(lineSquared)), line);
  const Doubles pA1 = dot(u, a1 - a0), pA2 = dot(u, a2 - a0);
  const Doubles pB0 = dot(u, b0 - a0), pB1 = dot(u, b1 - a0), pB2 = dot(u, b2 - a0);
  const Doubles slide =
      min(max3(zero, pA1, pA2) - min3(pB0, pB1, pB2), max3(pB0, pB1, pB2) - min3(zero, pA1, pA2));

  // The contact: the middle of the common segment, the winning normal, the moving triangle's deepest
  // vertex.
  const Vec low = pick(lowAOn >= lowBOn, lowA, lowB);
  const Vec high = pick(highAOn <= highBOn, highA, highB);
  const Vec normal = pick(aMoves, nB, Vec{-nA.x, -nA.y, -nA.z});
  const Doubles d0 = pick(aMoves, dA[0], dB[0]), d1 = pick(aMoves, dA[1], dB[1]),
                d2 = pick(aMoves, dA[2], dB[2]);
  const Mask deepest0 = (d0 <= d1) & (d0 <= d2), deepest1 = ~(d0 <= d1) & (d1 <= d2);
  const Vec deepestVertex =
      pick(aMoves, pick(deepest0, a0, pick(deepest1, a1, a2)), pick(deepest0, b0, pick(deepest1, b1, b2)));
  const Doubles half = splat(0.5);
  storeLanes(contacts, half * (low.x + high.x));
  storeLanes(contacts + stride, half * (low.y + high.y));
  storeLanes(contacts + 2 * stride, half * (low.z + high.z));
  storeLanes(contacts + 3 * stride, normal.x);
  storeLanes(contacts + 4 * stride, normal.y);
  storeLanes(contacts + 5 * stride, normal.z);
  storeLanes(contacts + 6 * stride, zero - move);
  storeLanes(contacts + 7 * stride, deepestVertex.x);
  storeLanes(contacts + 8 * stride, deepestVertex.y);
  storeLanes(contacts + 9 * stride, deepestVertex.z);

  // The outcome word, from the masks (all bits set where true).
  const Mask onePair = ~finite | (~rejected & coplanar);
  const Mask intersects = ~onePair & ~rejected & ~separated;
  const Mask found = wordWhere(onePair, kRowOnePair) |
                     wordWhere(intersects & (slide < move), kRowIntersectsNoContact) |
                     wordWhere(intersects & ~(slide < move), kRowContact) | wordWhere(aMoves, kRowOnFaceOfB) |
                     wordWhere(dot(nA, nB) > zero, kRowSameFacing);
  const Words words = __builtin_convertvector(found, Words);
  std::memcpy(outcome, &words, sizeof words);
}

}  // namespace

GPUCOL_AVX2_CLONES void generateContactRows(const float* triangles, std::size_t stride, std::size_t count,
                                            float* contacts, std::uint32_t* outcome) {
  std::size_t t = 0;
  for (; t + kLanes <= count; t += kLanes) fourPairs(triangles + t, stride, contacts + t, outcome + t);
  if (t == count) return;
  // The last one to three pairs: copied into columns of their own, the free lanes filled with the last pair
  // (a real pair, so no lane computes on garbage), and only their own results copied back.
  float tail[18 * kLanes];
  float tailContacts[kContactRowValues * kLanes];
  std::uint32_t tailOutcome[kLanes];
  for (std::size_t k = 0; k < 18; ++k) {
    for (std::size_t lane = 0; lane < kLanes; ++lane) {
      tail[k * kLanes + lane] = triangles[k * stride + std::min(t + lane, count - 1)];
    }
  }
  fourPairs(tail, kLanes, tailContacts, tailOutcome);
  for (std::size_t lane = 0; t + lane < count; ++lane) {
    for (std::size_t k = 0; k < kContactRowValues; ++k) {
      contacts[k * stride + t + lane] = tailContacts[k * kLanes + lane];
    }
    outcome[t + lane] = tailOutcome[lane];
  }
}

}  // namespace gpucol::detail
