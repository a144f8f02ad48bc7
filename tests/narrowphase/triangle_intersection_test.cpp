#include "narrowphase/triangle_intersection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>

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
