#include "narrowphase/triangle_intersection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>

#include "narrowphase/triangle_plane.h"
#include "random_triangles.h"
#include "reference_triangles.h"

namespace gpucol {
namespace {

using test::PairFamily;
using test::TriangleF;

bool intersect(const TriangleF& a, const TriangleF& b) {
  return trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
}

/// Pairs closer to touching than this fraction of their size may be classified either way: the test
/// snaps vertex-plane distances within 1e-12 of the triangle scales, which moves the intersection line of
/// nearly parallel planes by at most 1e-6 of the size (see triangle_plane.h). Measured: no disagreement
/// at all on these pairs even with a band of 1e-10.
constexpr double kBand = 1e-6;

/// The float test against the double separating-axis reference over every random family.
TEST(TriangleIntersection, AgreesWithDoubleReferenceOnRandomFamilies) {
  constexpr int kPerFamily = 30000;
  std::mt19937_64 rng(20240611);
  long total = 0, intersecting = 0, disagreements = 0, outsideBand = 0;
  for (int f = 0; f < static_cast<int>(PairFamily::Count); ++f) {
    const auto family = static_cast<PairFamily>(f);
    long familyDisagreements = 0, familyIntersecting = 0, familyFalsePositives = 0,
         familyOutsideBandPairs = 0;
    for (int i = 0; i < kPerFamily; ++i) {
      TriangleF a, b;
      test::randomPair(family, rng, a, b);
      const test::TriangleD da = test::toDouble(a), db = test::toDouble(b);
      const bool expected = test::referenceIntersect(da, db);
      const bool actual = intersect(a, b);
      // Symmetry: the test does not depend on the order of the triangles (up to the tolerance band).
      const bool swapped = intersect(b, a);
      familyIntersecting += expected;
      const double separation = test::signedSeparation(da, db) / test::pairScale(da, db);
      const bool inBand = std::fabs(separation) <= kBand;
      familyOutsideBandPairs += !inBand;
      if (actual == expected && swapped == expected) continue;
      ++familyDisagreements;
      familyFalsePositives += actual && !expected;
      if (!inBand) {
        ++outsideBand;
        ADD_FAILURE() << test::familyName(family) << " pair " << i << ": reference " << expected << ", float "
                      << actual << " (swapped " << swapped << "), relative separation " << separation;
      }
    }
    std::cout << "  " << test::familyName(family) << ": " << kPerFamily << " pairs ("
              << familyOutsideBandPairs << " outside the band), " << familyIntersecting << " intersecting, "
              << familyDisagreements << " disagreements in the band (" << familyFalsePositives
              << " float true / reference false)\n";
    total += kPerFamily;
    intersecting += familyIntersecting;
    disagreements += familyDisagreements;
  }
  std::cout << "  total " << total << " pairs, " << intersecting << " intersecting, " << disagreements
            << " disagreements within |separation| <= " << kBand << " x size, " << outsideBand
            << " outside\n";
  EXPECT_EQ(outsideBand, 0);
  EXPECT_GE(total, 100000);
}

/// What the double test of trianglesIntersect decides at Möller's two plane rejections (the same helpers, the
/// same order): true when it answers "no" there or earlier, false when it goes on to the coplanar or interval
/// test.
bool doublePlaneStepsReject(const TriangleF& a, const TriangleF& b) {
  const test::TriangleD da = test::toDouble(a), db = test::toDouble(b);
  const detail::TrianglePlane planeA = detail::makePlane(da[0], da[1], da[2]);
  if (planeA.degenerate) return true;
  double dB[3];
  detail::signedDistances(planeA, db[0], db[1], db[2], dB);
  if (detail::allOnOneSide(dB)) return true;
  const detail::TrianglePlane planeB = detail::makePlane(db[0], db[1], db[2]);
  if (planeB.degenerate) return true;
  if (detail::allInPlane(dB)) return false;
  double dA[3];
  detail::signedDistances(planeB, da[0], da[1], da[2], dA);
  return detail::allOnOneSide(dA);
}

/// What a float pre-test did in one test: the pairs it saw and rejected, and how the pairs built to sit at
/// its margin went. Both outcomes must be common there, or the test never reached the pre-test's edge.
struct PreTestTally {
  long checked = 0, rejected = 0, keptNearMargin = 0, rejectedNearMargin = 0;

  void count(bool rejectedPair, bool nearMargin) {
    ++checked;
    rejected += rejectedPair;
    (rejectedPair ? rejectedNearMargin : keptNearMargin) += nearMargin;
  }

  void expectMarginReached() const {
    std::cout << "  " << checked << " pairs, " << rejected << " rejected in float; at the margin "
              << rejectedNearMargin << " rejected, " << keptNearMargin << " left to the double test\n";
    EXPECT_GT(rejectedNearMargin, 1000);
    EXPECT_GT(keptNearMargin, 1000);
  }
};

/// Runs check(a, b, false) and check(b, a, false) on 20,000 pairs of every random family.
template <class Check>
void checkBothWaysOnEveryFamily(std::mt19937_64& rng, Check&& check) {
  for (int f = 0; f < static_cast<int>(PairFamily::Count); ++f) {
    for (int i = 0; i < 20000; ++i) {
      TriangleF a, b;
      test::randomPair(static_cast<PairFamily>(f), rng, a, b);
      check(a, b, false);
      check(b, a, false);
    }
  }
}

/// The float pre-test may only reject a pair the double test rejects too, so the answers stay the double
/// test's; its branch-free form must agree with it exactly. Checked on every random family and on pairs built
/// to sit at the pre-test's margin: B's vertices lifted off A's plane by 1e-9..1e-3 of the size (the margin
/// is about 3e-6), at scales from 1e-6 to 1e6.
TEST(TriangleIntersection, FloatPreTestRejectsOnlyWhatTheDoubleTestRejects) {
  std::mt19937_64 rng(20240612);
  PreTestTally tally;
  auto check = [&](const TriangleF& a, const TriangleF& b, bool nearMargin) {
    const bool apart = detail::floatCertainlyApart(a[0], a[1], a[2], b[0], b[1], b[2]);
    EXPECT_EQ(detail::floatCertainlyApartBranchFree(a[0], a[1], a[2], b[0], b[1], b[2]) != 0u, apart);
    tally.count(apart, nearMargin);
    if (!apart) return;
    EXPECT_TRUE(doublePlaneStepsReject(a, b))
        << "float rejected a pair the double test does not reject: " << a[0].transpose() << " / "
        << b[0].transpose();
  };
  checkBothWaysOnEveryFamily(rng, check);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), logLift(-9.0, -3.0), logScale(-6.0, 6.0);
  for (int i = 0; i < 100000; ++i) {
    const double scale = std::pow(10.0, logScale(rng));
    const Eigen::Vector3d offset(unit(rng), unit(rng), unit(rng));
    const Eigen::Matrix3d rotation = test::randomRotation(rng);
    TriangleF a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = (scale * (rotation * Eigen::Vector3d(unit(rng), unit(rng), 0) + offset)).cast<float>();
      // In A's plane (z = 0 before the rotation), lifted to one side by a tiny fraction of the size.
      const double lift = std::pow(10.0, logLift(rng));
      b[k] = (scale * (rotation * Eigen::Vector3d(unit(rng), unit(rng), lift) + offset)).cast<float>();
    }
    if (!test::wellShaped(a) || !test::wellShaped(b)) continue;
    check(a, b, true);
    check(b, a, true);
  }
  tally.expectMarginReached();
}

/// The float interval stage may only reject a pair the double test rejects (trianglesIntersectDouble and
/// generateContactAndTest both answer "no intersection"). Checked on every random family, and at the stage's
/// margin: pairs that cross each other's planes with their intervals on the common line 1e-7..1e-1 of the
/// size apart or overlapping by as much, the planes 1e-3 rad to a right angle apart (the margin grows as the
/// angle shrinks: about 1e-4 of the size at a right angle, 1e-1 at 1e-3 rad), at scales from 1e-3 to 1e3 and
/// a third of them 1000 sizes from the origin.
TEST(TriangleIntersection, FloatIntervalStageRejectsOnlyWhatTheDoubleTestRejects) {
  std::mt19937_64 rng(20261121);
  PreTestTally tally;
  auto check = [&](const TriangleF& a, const TriangleF& b, bool nearMargin) {
    const bool apart = detail::floatIntervalsApartBranchFree(a[0], a[1], a[2], b[0], b[1], b[2]) != 0u;
    tally.count(apart, nearMargin);
    if (!apart) return;
    bool intersects = true;
    detail::generateContactAndTest({a[0], a[1], a[2]}, {b[0], b[1], b[2]}, intersects);
    EXPECT_FALSE(detail::trianglesIntersectDouble(a[0], a[1], a[2], b[0], b[1], b[2]))
        << "float interval stage rejected an intersecting pair: " << a[0].transpose() << " / "
        << b[0].transpose();
    EXPECT_FALSE(intersects);
  };
  checkBothWaysOnEveryFamily(rng, check);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), beyond(1.2, 3.0), logGap(-7.0, -1.0),
      logAngle(-3.0, std::log10(M_PI / 2)), logScale(-3.0, 3.0);
  for (int i = 0; i < 100000; ++i) {
    // In a local frame, the common line is the x axis. A lies in z = 0 and meets y = 0 on [s0, s1]; B lies in
    // a plane through the x axis at `angle` from A's and meets it on [s1 + gap, s1 + gap + length]: each
    // triangle is a lone vertex and two vertices beyond the crossing points seen from it.
    const double s0 = unit(rng), s1 = s0 + 0.2 + std::fabs(unit(rng));
    const double gap = (i % 2 == 0 ? 1.0 : -1.0) * std::pow(10.0, logGap(rng));
    const double t0 = s1 + gap, t1 = t0 + 0.2 + std::fabs(unit(rng));
    const double angle = std::pow(10.0, logAngle(rng));
    const Eigen::Vector3d lineA(unit(rng), 0.3 + std::fabs(unit(rng)), 0.0);
    const Eigen::Vector3d loneB(unit(rng), 0.0, 0.3 + std::fabs(unit(rng)));
    const Eigen::Vector3d c0(s0, 0, 0), c1(s1, 0, 0), d0(t0, 0, 0), d1(t1, 0, 0);
    const test::TriangleD localA = {lineA, lineA + beyond(rng) * (c0 - lineA),
                                    lineA + beyond(rng) * (c1 - lineA)};
    test::TriangleD localB = {loneB, loneB + beyond(rng) * (d0 - loneB), loneB + beyond(rng) * (d1 - loneB)};
    // Turn B about the common line: its plane goes from y = 0 (a right angle to A's) to `angle` from A's.
    const Eigen::Matrix3d tilt =
        Eigen::AngleAxisd(M_PI / 2 - angle, Eigen::Vector3d::UnitX()).toRotationMatrix();
    for (Eigen::Vector3d& v : localB) v = tilt * v;
    const double scale = std::pow(10.0, logScale(rng));
    const Eigen::Matrix3d rotation = test::randomRotation(rng);
    const Eigen::Vector3d offset =
        (i % 3 == 0 ? 1000.0 : 1.0) * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    TriangleF a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = (scale * (rotation * localA[k] + offset)).cast<float>();
      b[k] = (scale * (rotation * localB[k] + offset)).cast<float>();
    }
    if (!test::wellShaped(a) || !test::wellShaped(b)) continue;
    check(a, b, true);
    check(b, a, true);
  }
  tally.expectMarginReached();
}

/// Touching configurations built from coordinates that float represents exactly must count as
/// intersecting: the contract says touching counts, and here rounding cannot blur it.
TEST(TriangleIntersection, ExactTouchingCountsAsIntersecting) {
  const Eigen::Vector3f a0(-1, 0, 0), a1(1, 0, 0), a2(0, -1, 0);  // in z = 0, y <= 0
  // Shared vertex, B above the plane.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(2, 1, 1),
                                 Eigen::Vector3f(2, -1, 1)));
  // Vertex of B on A's face, B above.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0, -0.25f, 0), Eigen::Vector3f(1, 0, 1),
                                 Eigen::Vector3f(-1, 0, 1)));
  // Edge of B crossing A's edge at the origin, B only on the y >= 0 side of the line they share.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(-1, -1, 1), Eigen::Vector3f(1, 1, -1),
                                 Eigen::Vector3f(1, 1, 1)));
  // Edge of B lying on A's edge (B vertical above it).
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(-0.5f, 0, 0), Eigen::Vector3f(0.5f, 0, 0),
                                 Eigen::Vector3f(0, 0, 1)));
  // Coplanar, sharing only an edge (B on the other side of it).
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(-1, 0, 0),
                                 Eigen::Vector3f(0, 1, 0)));
  // Coplanar, sharing only a vertex.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(2, 0, 0),
                                 Eigen::Vector3f(2, 1, 0)));
  // The same pairs moved apart by one part in 10^4 are separated.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1, 0, 1e-4f), Eigen::Vector3f(2, 1, 1),
                                  Eigen::Vector3f(2, -1, 1)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1.0001f, 0, 0), Eigen::Vector3f(2, 0, 0),
                                  Eigen::Vector3f(2, 1, 0)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(-1, -0.999f, 1), Eigen::Vector3f(1, 1.001f, -1),
                                  Eigen::Vector3f(1, 1.001f, 1)));
}

/// Möller's early rejection and the interval test on hand-made cases with known answers.
TEST(TriangleIntersection, KnownCases) {
  const Eigen::Vector3f a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  // B pierces A's interior.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0.2f, 0.2f, -1), Eigen::Vector3f(0.3f, 0.2f, 1),
                                 Eigen::Vector3f(0.2f, 0.3f, 1)));
  // B entirely above A's plane.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0, 0, 0.1f), Eigen::Vector3f(1, 0, 0.2f),
                                  Eigen::Vector3f(0, 1, 0.3f)));
  // B crosses A's plane but beside A (intervals on the line miss).
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(2, 2, -1), Eigen::Vector3f(3, 2, 1),
                                  Eigen::Vector3f(2, 3, 1)));
  // Coplanar overlapping, coplanar disjoint, one inside the other.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0.5f, 0.5f, 0), Eigen::Vector3f(-0.5f, 0.2f, 0),
                                 Eigen::Vector3f(0.2f, -0.5f, 0)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(1, 1, 0), Eigen::Vector3f(2, 1, 0),
                                  Eigen::Vector3f(1, 2, 0)));
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0.1f, 0.1f, 0), Eigen::Vector3f(0.2f, 0.1f, 0),
                                 Eigen::Vector3f(0.1f, 0.2f, 0)));
  EXPECT_TRUE(trianglesIntersect(Eigen::Vector3f(0.1f, 0.1f, 0), Eigen::Vector3f(0.2f, 0.1f, 0),
                                 Eigen::Vector3f(0.1f, 0.2f, 0), a0, a1, a2));
}

/// Zero-area triangles have no plane: they never intersect, never crash, and give no NaN-based answer.
TEST(TriangleIntersection, DegenerateTrianglesReturnFalse) {
  const Eigen::Vector3f a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::Vector3f p(0.2f, 0.2f, 0);
  // A point, a segment through A, collinear points through A, a NaN vertex.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, p, p, p));
  EXPECT_FALSE(trianglesIntersect(p, p, p, a0, a1, a2));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0.2f, 0.2f, -1), Eigen::Vector3f(0.2f, 0.2f, 1),
                                  Eigen::Vector3f(0.2f, 0.2f, 1)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(0.2f, 0.2f, -1), Eigen::Vector3f(0.2f, 0.2f, 0),
                                  Eigen::Vector3f(0.2f, 0.2f, 1)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, Eigen::Vector3f(nan, 0, 0), Eigen::Vector3f(0.2f, 0.2f, 0),
                                  Eigen::Vector3f(0.2f, 0.2f, 1)));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, a0, a0, a1));
}

}  // namespace
}  // namespace gpucol
