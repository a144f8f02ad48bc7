#include "narrowphase/contact_reduction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>

namespace gpucol {
namespace {

Eigen::Vector3f randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<float> n(0.0f, 1.0f);
  return Eigen::Vector3f(n(rng), n(rng), n(rng)).normalized();
}

std::vector<ReductionInput> randomContacts(std::mt19937_64& rng, int count) {
  std::uniform_real_distribution<float> u(-3.0f, 5.0f), depth(-0.1f, 0.0f);
  std::vector<ReductionInput> contacts(count);
  for (ReductionInput& c : contacts)
    c = {Eigen::Vector3f(u(rng), u(rng), u(rng)), randomUnit(rng), depth(rng)};
  return contacts;
}

/// Brute-force binning in double with a std::map over explicit 6-D cells: the same rule (deepest per
/// bin, lowest index on ties) by another route. `nearBoundary` reports a coordinate within 1e-4 of a bin
/// boundary (other than the box's own faces), where float and double may bin differently.
std::vector<std::uint32_t> referenceReduce(const std::vector<ReductionInput>& contacts, int resolution,
                                           bool& nearBoundary) {
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(1e300), upper = Eigen::Vector3d::Constant(-1e300);
  for (const ReductionInput& c : contacts) {
    lower = lower.cwiseMin(c.point.cast<double>());
    upper = upper.cwiseMax(c.point.cast<double>());
  }
  std::map<std::array<int, 6>, std::uint32_t> best;
  nearBoundary = false;
  for (std::uint32_t i = 0; i < contacts.size(); ++i) {
    std::array<int, 6> cell;
    for (int k = 0; k < 6; ++k) {
      const double x =
          k < 3 ? (upper[k] > lower[k] ? (contacts[i].point[k] - lower[k]) / (upper[k] - lower[k]) : 0.0)
                : (contacts[i].normal[k - 3] + 1.0) / 2.0;
      const double scaled = x * resolution;
      const double fraction = scaled - std::floor(scaled);
      if (scaled > 1e-9 && scaled < resolution - 1e-9 && (fraction < 1e-4 || fraction > 1 - 1e-4))
        nearBoundary = true;
      cell[k] = std::clamp(static_cast<int>(std::floor(scaled)), 0, resolution - 1);
    }
    auto [it, inserted] = best.try_emplace(cell, i);
    if (!inserted && contacts[i].depth < contacts[it->second].depth) it->second = i;
  }
  std::vector<std::uint32_t> kept;
  for (const auto& entry : best) kept.push_back(entry.second);
  std::sort(kept.begin(), kept.end());
  return kept;
}

TEST(ContactReduction, ResolutionZeroKeepsAll) {
  std::mt19937_64 rng(1);
  const std::vector<ReductionInput> contacts = randomContacts(rng, 57);
  std::vector<std::uint32_t> all(57);
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(reduceContacts(contacts, 0), all);
  EXPECT_TRUE(reduceContacts({}, 4).empty());
}

TEST(ContactReduction, MatchesBruteForceBinning) {
  std::mt19937_64 rng(2);
  int trials = 0;
  for (int attempt = 0; attempt < 400 && trials < 100; ++attempt) {
    const int resolution = 1 + attempt % 6;
    const std::vector<ReductionInput> contacts = randomContacts(rng, 1 + attempt % 300);
    bool nearBoundary = false;
    const std::vector<std::uint32_t> expected = referenceReduce(contacts, resolution, nearBoundary);
    if (nearBoundary) continue;
    ++trials;
    EXPECT_EQ(reduceContacts(contacts, resolution), expected) << "resolution " << resolution;
  }
  EXPECT_GE(trials, 100);
}

TEST(ContactReduction, MatchesBruteForceAroundThePackedKeyLimit) {
  // Up to resolution 1024 the six bins are packed into one 64-bit key, above it six-element keys are compared:
  // both routes must keep what the brute force keeps. Each contact gets two copies at other depths, so that
  // every bin holds several contacts however fine the bins are, and only the deepest may stay.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> depth(-0.1f, 0.0f);
  int trials = 0;
  for (int resolution : {1023, 1024, 1025, 4096}) {
    for (int attempt = 0; attempt < 40; ++attempt) {
      std::vector<ReductionInput> contacts = randomContacts(rng, 40);
      for (std::size_t i = 0; i < 40; ++i) {
        for (int copy = 0; copy < 2; ++copy) {
          ReductionInput c = contacts[i];
          c.depth = depth(rng);
          contacts.push_back(c);
        }
      }
      bool nearBoundary = false;
      const std::vector<std::uint32_t> expected = referenceReduce(contacts, resolution, nearBoundary);
      if (nearBoundary) continue;
      ++trials;
      const std::vector<std::uint32_t> kept = reduceContacts(contacts, resolution);
      EXPECT_EQ(kept, expected) << "resolution " << resolution;
      EXPECT_LE(kept.size(), 40u) << "resolution " << resolution;
    }
  }
  EXPECT_GE(trials, 100);
}

TEST(ContactReduction, NearDuplicatesCollapseToTheDeepest) {
  // Two clusters at opposite corners of the patch, each of 50 contacts that differ by 1e-4 in position
  // and normal: one contact per cluster survives, the deepest of it.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> jitter(-1e-4f, 1e-4f);
  const Eigen::Vector3f normal = Eigen::Vector3f(0.3f, -0.2f, 0.9f).normalized();
  std::vector<ReductionInput> contacts;
  for (int cluster = 0; cluster < 2; ++cluster) {
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3f centre = Eigen::Vector3f::Constant(cluster == 0 ? 0.0f : 1.0f);
      const Eigen::Vector3f j(jitter(rng), jitter(rng), jitter(rng));
      contacts.push_back(
          {centre + j, (normal + j).normalized(), -0.01f * static_cast<float>((i * 7 + cluster) % 50)});
    }
  }
  const std::vector<std::uint32_t> kept = reduceContacts(contacts, 5);
  ASSERT_EQ(kept.size(), 2u);
  for (std::uint32_t k : kept) {
    const int cluster = k / 50;
    for (int i = cluster * 50; i < cluster * 50 + 50; ++i) EXPECT_LE(contacts[k].depth, contacts[i].depth);
  }
}

TEST(ContactReduction, DistinctBinsAreAllKept) {
  for (int resolution : {2, 3, 4, 7}) {
    std::vector<ReductionInput> contacts;
    for (int i = 0; i < resolution; ++i) {
      for (int j = 0; j < resolution; ++j) {
        for (int k = 0; k < resolution; ++k) {
          const Eigen::Vector3f p = (Eigen::Vector3f(i, j, k) + Eigen::Vector3f::Constant(0.5f)) / resolution;
          contacts.push_back({p, Eigen::Vector3f(0, 0, 1), -0.01f});
        }
      }
    }
    EXPECT_EQ(reduceContacts(contacts, resolution).size(), contacts.size()) << "resolution " << resolution;
    // The six axis normals at one point are six bins from resolution 3 on (at 2, a component 0 maps to
    // 0.5, the upper bin, the same as +1).
    if (resolution < 3) continue;
    std::vector<ReductionInput> normals;
    for (int axis = 0; axis < 3; ++axis) {
      for (float sign : {-1.0f, 1.0f})
        normals.push_back({Eigen::Vector3f::Zero(), sign * Eigen::Vector3f::Unit(axis), 0.0f});
    }
    EXPECT_EQ(reduceContacts(normals, resolution).size(), 6u);
  }
}

TEST(ContactReduction, SortedDeterministicBoundedAndKeepsTheDeepest) {
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 50; ++trial) {
    const int resolution = 1 + trial % 3;
    std::vector<ReductionInput> contacts = randomContacts(rng, 2000);
    const std::vector<std::uint32_t> kept = reduceContacts(contacts, resolution);
    EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
    EXPECT_TRUE(std::adjacent_find(kept.begin(), kept.end()) == kept.end());
    EXPECT_LE(kept.size(), static_cast<std::size_t>(std::pow(resolution, 6)));
    EXPECT_EQ(reduceContacts(contacts, resolution), kept);
    const auto deepest = std::min_element(contacts.begin(), contacts.end(),
                                          [](const auto& l, const auto& r) { return l.depth < r.depth; });
    EXPECT_TRUE(std::binary_search(kept.begin(), kept.end(), std::uint32_t(deepest - contacts.begin())));

    // Shuffling the input keeps the same contacts (depths are distinct, so no tie decides).
    std::vector<std::uint32_t> permutation(contacts.size());
    std::iota(permutation.begin(), permutation.end(), 0u);
    std::shuffle(permutation.begin(), permutation.end(), rng);
    std::vector<ReductionInput> shuffled(contacts.size());
    for (std::size_t i = 0; i < contacts.size(); ++i) shuffled[i] = contacts[permutation[i]];
    std::vector<std::uint32_t> back;
    for (std::uint32_t k : reduceContacts(shuffled, resolution)) back.push_back(permutation[k]);
    std::sort(back.begin(), back.end());
    EXPECT_EQ(back, kept);
  }
  // Equal depths in one bin: the lowest index wins.
  const std::vector<ReductionInput> twins = {{Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), -1.0f},
                                             {Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), -1.0f}};
  EXPECT_EQ(reduceContacts(twins, 3), std::vector<std::uint32_t>{0});
}

TEST(ContactReduction, BadInputThrows) {
  std::vector<ReductionInput> contacts = {{Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), -1.0f},
                                          {Eigen::Vector3f::Ones(), Eigen::Vector3f::UnitZ(), -1.0f}};
  EXPECT_THROW(reduceContacts(contacts, -1), std::invalid_argument);
  contacts[1].point.x() = std::numeric_limits<float>::quiet_NaN();
  try {
    reduceContacts(contacts, 4);
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 1"), std::string::npos) << e.what();
  }
  // A huge resolution is fine: no resolution^6 key or array.
  contacts[1].point.x() = 1.0f;
  EXPECT_EQ(reduceContacts(contacts, 1 << 20).size(), 2u);
}

}  // namespace
}  // namespace gpucol
