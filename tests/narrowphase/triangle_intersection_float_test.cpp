#include "narrowphase/triangle_intersection_float.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "random_triangles.h"
#include "reference_triangles.h"

namespace gpucol {
namespace {

using test::PairFamily;
using test::TriangleF;

/// Float alone decides pairs well away from touching like the double reference: a pair farther than this
/// fraction of its size from touching moves no float distance's sign (relative rounding ~1e-7 per product,
/// a few products deep).
constexpr double kFloatBand = 1e-4;

TEST(TriangleIntersectionFloat, AgreesWithDoubleReferenceAwayFromTouching) {
  constexpr int kPerFamily = 20000;
  std::mt19937_64 rng(77);
  long decided = 0;
  for (int f = 0; f < static_cast<int>(PairFamily::Count); ++f) {
    const auto family = static_cast<PairFamily>(f);
    long inBand = 0, disagreeInBand = 0;
    for (int i = 0; i < kPerFamily; ++i) {
      TriangleF a, b;
      test::randomPair(family, rng, a, b);
      const test::TriangleD da = test::toDouble(a), db = test::toDouble(b);
      const bool expected = test::referenceIntersect(da, db);
      const bool actual = trianglesIntersectFloat(a[0], a[1], a[2], b[0], b[1], b[2]);
      const double separation = test::signedSeparation(da, db) / test::pairScale(da, db);
      if (std::fabs(separation) <= kFloatBand) {
        ++inBand;
        disagreeInBand += actual != expected;
        continue;
      }
      ++decided;
      EXPECT_EQ(actual, expected) << test::familyName(family) << " pair " << i << ", relative separation "
                                  << separation;
    }
    std::cout << "  " << test::familyName(family) << ": " << inBand << " pairs within " << kFloatBand
              << " of touching, float disagrees with the reference on " << disagreeInBand << "\n";
  }
  EXPECT_GT(decided, 20000);
}

TEST(TriangleIntersectionFloat, DegenerateAndNanTrianglesDoNotIntersect) {
  const Eigen::Vector3f a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  const Eigen::Vector3f b0(0.2f, 0.2f, -1), b1(0.2f, 0.2f, 1), b2(0.3f, 0.3f, 1);
  ASSERT_TRUE(trianglesIntersectFloat(a0, a1, a2, b0, b1, b2));
  EXPECT_FALSE(trianglesIntersectFloat(a0, a1, a0, b0, b1, b2));
  const float nan = std::nanf("");
  EXPECT_FALSE(trianglesIntersectFloat(a0, a1, a2, Eigen::Vector3f(nan, 0, 0), b1, b2));
}

TEST(TriangleIntersectionFloat, ExactCoplanarOverlapAndTouching) {
  const Eigen::Vector3f a0(0, 0, 0), a1(2, 0, 0), a2(0, 2, 0);
  EXPECT_TRUE(trianglesIntersectFloat(a0, a1, a2, Eigen::Vector3f(0.5f, 0.5f, 0), Eigen::Vector3f(3, 0.5f, 0),
                                      Eigen::Vector3f(0.5f, 3, 0)));
  EXPECT_FALSE(trianglesIntersectFloat(a0, a1, a2, Eigen::Vector3f(3, 3, 0), Eigen::Vector3f(4, 3, 0),
                                       Eigen::Vector3f(3, 4, 0)));
  // A shared vertex, exact in float.
  EXPECT_TRUE(trianglesIntersectFloat(a0, a1, a2, a1, Eigen::Vector3f(3, 0, 1), Eigen::Vector3f(3, 1, -1)));
}

}  // namespace
}  // namespace gpucol
