#include "narrowphase/contact_rows.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "narrowphase/triangle_plane.h"
#include "random_triangles.h"

namespace gpucol {
namespace {

using test::PairFamily;
using test::TriangleF;

/// Pairs laid out as generateContactRows reads them, with a row stride that is not the count.
struct Columns {
  explicit Columns(const std::vector<std::pair<TriangleF, TriangleF>>& pairs)
      : stride(pairs.size() + 7),
        triangles(18 * stride, 0.0f),
        contacts(detail::kContactRowValues * stride),
        outcome(pairs.size()) {
    for (std::size_t t = 0; t < pairs.size(); ++t) {
      for (int v = 0; v < 3; ++v) {
        for (int c = 0; c < 3; ++c) {
          triangles[(3 * v + c) * stride + t] = pairs[t].first[v][c];
          triangles[(9 + 3 * v + c) * stride + t] = pairs[t].second[v][c];
        }
      }
    }
    detail::generateContactRows(triangles.data(), stride, pairs.size(), contacts.data(), outcome.data());
  }
  float contact(std::size_t k, std::size_t t) const { return contacts[k * stride + t]; }

  std::size_t stride;
  std::vector<float> triangles, contacts;
  std::vector<std::uint32_t> outcome;
};

bool sameBits(float x, float y) {
  return std::memcmp(&x, &y, sizeof x) == 0;
}

/// Every vertex of one triangle in the other's plane, by the snapped double distances of the one-pair test.
bool coplanar(const TriangleF& a, const TriangleF& b) {
  const Eigen::Vector3d da[3] = {a[0].cast<double>(), a[1].cast<double>(), a[2].cast<double>()};
  const Eigen::Vector3d db[3] = {b[0].cast<double>(), b[1].cast<double>(), b[2].cast<double>()};
  double dB[3], dA[3];
  detail::signedDistances(detail::makePlane(da[0], da[1], da[2]), db[0], db[1], db[2], dB);
  detail::signedDistances(detail::makePlane(db[0], db[1], db[2]), da[0], da[1], da[2], dA);
  return detail::allInPlane(dB) || detail::allInPlane(dA);
}

/// The rows (generateContactRows run on `pairs`) must give generateContactAndTest's answer on every pair, and
/// its contact bit for bit; only coplanar pairs and pairs with a non-finite coordinate may be left to it.
void expectSameAsOnePair(const std::vector<std::pair<TriangleF, TriangleF>>& pairs, const Columns& rows,
                         const char* what, long counts[4]) {
  for (std::size_t t = 0; t < pairs.size(); ++t) {
    const TriangleF& a = pairs[t].first;
    const TriangleF& b = pairs[t].second;
    const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]};
    const Eigen::Vector3f pb[3] = {b[0], b[1], b[2]};
    bool intersects = false;
    const std::optional<TriangleContact> expected = detail::generateContactAndTest(pa, pb, intersects);
    const std::uint32_t outcome = rows.outcome[t] & detail::kRowOutcomeMask;
    ++counts[outcome];
    if (outcome == detail::kRowOnePair) {
      bool finite = true;
      for (int v = 0; v < 3; ++v) finite &= a[v].allFinite() && b[v].allFinite();
      EXPECT_TRUE(!finite || coplanar(a, b)) << what << " pair " << t << " left to the one-pair test";
      continue;
    }
    ASSERT_EQ(outcome != detail::kRowApart, intersects) << what << " pair " << t;
    ASSERT_EQ(outcome == detail::kRowContact, expected.has_value()) << what << " pair " << t;
    if (!expected) continue;
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(sameBits(rows.contact(c, t), expected->point[c])) << what << " pair " << t;
      EXPECT_TRUE(sameBits(rows.contact(3 + c, t), expected->normalOnB[c])) << what << " pair " << t;
      EXPECT_TRUE(sameBits(rows.contact(7 + c, t), expected->deepestPoint[c])) << what << " pair " << t;
    }
    EXPECT_TRUE(sameBits(rows.contact(6, t), expected->depth)) << what << " pair " << t;
    EXPECT_EQ((rows.outcome[t] & detail::kRowOnFaceOfB) != 0, expected->onFaceOfB) << what << " pair " << t;
    EXPECT_EQ((rows.outcome[t] & detail::kRowSameFacing) != 0, expected->sameFacing) << what << " pair " << t;
  }
}

TEST(ContactRows, SameAsTheOnePairTestOnEveryFamily) {
  std::mt19937_64 rng(29);
  long total[4] = {0, 0, 0, 0};
  for (int f = 0; f < static_cast<int>(PairFamily::Count); ++f) {
    std::vector<std::pair<TriangleF, TriangleF>> pairs(20000);
    for (auto& [a, b] : pairs) test::randomPair(static_cast<PairFamily>(f), rng, a, b);
    long counts[4] = {0, 0, 0, 0};
    expectSameAsOnePair(pairs, Columns(pairs), test::familyName(static_cast<PairFamily>(f)).c_str(), counts);
    for (int k = 0; k < 4; ++k) total[k] += counts[k];
    if (static_cast<PairFamily>(f) == PairFamily::ExactCoplanar) {
      EXPECT_GT(counts[detail::kRowOnePair], 1000);
    }
  }
  // Every outcome occurred, so each was compared.
  EXPECT_GT(total[detail::kRowApart], 10000);
  EXPECT_GT(total[detail::kRowIntersectsNoContact], 1000);
  EXPECT_GT(total[detail::kRowContact], 10000);
}

/// The pairs go four to a vector, and a count that is not a multiple of four leaves one to three pairs to a
/// last, partly filled vector: every count up to 13, with the results of those pairs right and nothing
/// written past the last pair.
TEST(ContactRows, EveryCountUpToThirteen) {
  std::mt19937_64 rng(37);
  for (std::size_t count = 1; count <= 13; ++count) {
    std::vector<std::pair<TriangleF, TriangleF>> pairs(count);
    for (std::size_t t = 0; t < count; ++t) {
      // Mostly intersecting families, so that the last pairs carry contacts.
      const auto family = static_cast<PairFamily>((t + count) % static_cast<int>(PairFamily::Count));
      test::randomPair(family, rng, pairs[t].first, pairs[t].second);
    }
    long counts[4] = {0, 0, 0, 0};
    const std::string what = "count " + std::to_string(count);
    const Columns rows(pairs);
    expectSameAsOnePair(pairs, rows, what.c_str(), counts);
    for (std::size_t k = 0; k < detail::kContactRowValues; ++k) {
      for (std::size_t t = count; t < rows.stride; ++t) {
        EXPECT_TRUE(sameBits(rows.contact(k, t), 0.0f)) << what << ": value " << k << " written at " << t;
      }
    }
  }
}

/// Degenerate triangles, pairs that share a whole edge, and non-finite coordinates, between ordinary pairs
/// in the same columns.
TEST(ContactRows, DegenerateSharedEdgeAndNonFinitePairs) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<float> coordinate(-1.0f, 1.0f);
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<std::pair<TriangleF, TriangleF>> pairs;
  for (int i = 0; i < 3000; ++i) {
    TriangleF a, b;
    for (int v = 0; v < 3; ++v) {
      a[v] = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
      b[v] = Eigen::Vector3f(coordinate(rng), coordinate(rng), coordinate(rng));
    }
    switch (i % 6) {
      case 0:  // a point
        a[1] = a[0], a[2] = a[0];
        break;
      case 1:  // collinear
        b[2] = b[0] + 0.5f * (b[1] - b[0]);
        break;
      case 2:  // B shares A's edge 0-1
        b[0] = a[1], b[1] = a[0];
        break;
      case 3:
        a[i % 3][i % 2] = (i / 6) % 2 ? inf : nan;
        break;
      case 4:
        b[1][2] = -inf;
        break;
      default:
        break;
    }
    pairs.emplace_back(a, b);
  }
  long counts[4] = {0, 0, 0, 0};
  expectSameAsOnePair(pairs, Columns(pairs), "degenerate, shared edge or non-finite", counts);
  EXPECT_GE(counts[detail::kRowOnePair], 1000);  // every non-finite pair
  EXPECT_GT(counts[detail::kRowContact], 100);
}

}  // namespace
}  // namespace gpucol
