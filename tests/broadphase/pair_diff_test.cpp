// diffSortedPairs against std::set arithmetic on random sorted lists.
#include "broadphase/pair_diff.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <iterator>
#include <random>
#include <type_traits>
#include <vector>

#include "broadphase/packed_pairs.h"

namespace {

std::vector<std::uint64_t> randomSorted(std::mt19937_64& rng, std::size_t n, std::uint64_t range) {
  std::vector<std::uint64_t> v(n);
  for (auto& x : v) x = rng() % range;
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

TEST(PairDiff, MatchesSetDifferencesAndKeepsOrder) {
  std::mt19937_64 rng(42);
  for (int t = 0; t < 200; ++t) {
    const auto before = randomSorted(rng, rng() % 300, 500);
    const auto now = randomSorted(rng, rng() % 300, 500);
    std::vector<std::uint64_t> added, removed, kept, expectAdded, expectRemoved, expectKept;
    gpucol::diffSortedPairs(
        before, now, [&](std::uint64_t k) { added.push_back(k); },
        [&](std::uint64_t k) { removed.push_back(k); }, [&](std::uint64_t k) { kept.push_back(k); });
    std::set_difference(now.begin(), now.end(), before.begin(), before.end(),
                        std::back_inserter(expectAdded));
    std::set_difference(before.begin(), before.end(), now.begin(), now.end(),
                        std::back_inserter(expectRemoved));
    std::set_intersection(before.begin(), before.end(), now.begin(), now.end(),
                          std::back_inserter(expectKept));
    ASSERT_EQ(added, expectAdded);
    ASSERT_EQ(removed, expectRemoved);
    ASSERT_EQ(kept, expectKept);
  }
}

TEST(PairDiff, CodedLastListGivesTheSameChanges) {
  // The broad phase diffs its coded last list (PackedPairs) with this step's keys: same calls, same order.
  std::mt19937_64 rng(5);
  for (int t = 0; t < 50; ++t) {
    const auto before = randomSorted(rng, rng() % 20000, 30000);
    const auto now = randomSorted(rng, rng() % 20000, 30000);
    gpucol::PackedPairs packed;
    packed.assign(before);
    std::vector<std::uint64_t> plain[3], coded[3];
    gpucol::diffSortedPairs(
        before, now, [&](std::uint64_t k) { plain[0].push_back(k); },
        [&](std::uint64_t k) { plain[1].push_back(k); }, [&](std::uint64_t k) { plain[2].push_back(k); });
    gpucol::diffSortedReaders(
        gpucol::PackedPairs::Reader(packed), gpucol::SortedKeyReader(now),
        [&](std::uint64_t k) { coded[0].push_back(k); }, [&](std::uint64_t k) { coded[1].push_back(k); },
        [&](std::uint64_t k) { coded[2].push_back(k); });
    for (int i = 0; i < 3; ++i) ASSERT_EQ(coded[i], plain[i]) << "trial " << t << " list " << i;
  }
}

TEST(PairDiff, PartsWalkedInParallelGiveTheSameChanges) {
  // Both lists coded, cut into the found list's segments and walked part by part (in parallel): the parts'
  // changes, put together in part order, are the plain diff's.
  std::mt19937_64 rng(9);
  for (int t = 0; t < 40; ++t) {
    const std::uint64_t range = t % 2 ? 30000 : 3000000;
    const auto before = randomSorted(rng, t < 3 ? 0 : rng() % 30000, range);
    const auto now = randomSorted(rng, t == 1 ? 0 : rng() % 30000, range);
    gpucol::PackedPairs packedBefore, packedNow;
    packedBefore.assign(before, t % 3 == 0);  // plain and coded lists walk alike
    packedNow.assign(now, t % 4 == 0);
    const std::size_t parts = gpucol::diffParts(packedNow);
    std::vector<std::vector<std::uint64_t>> partChanges(3 * parts);
    std::vector<std::uint64_t> begins(parts);
    gpucol::diffCodedInParts(
        packedBefore, packedNow, [&](std::size_t part, std::uint64_t begin, auto b, auto n) {
          begins[part] = begin;
          auto* c = &partChanges[3 * part];
          gpucol::diffSortedReaders(
              b, n, [&](std::uint64_t k) { c[0].push_back(k); }, [&](std::uint64_t k) { c[1].push_back(k); },
              [&](std::uint64_t k) { c[2].push_back(k); });
        });
    std::vector<std::uint64_t> plain[3], joined[3];
    gpucol::diffSortedPairs(
        before, now, [&](std::uint64_t k) { plain[0].push_back(k); },
        [&](std::uint64_t k) { plain[1].push_back(k); }, [&](std::uint64_t k) { plain[2].push_back(k); });
    for (std::size_t part = 0; part < parts; ++part)
      for (int i = 0; i < 3; ++i) {
        for (std::uint64_t k : partChanges[3 * part + i]) ASSERT_GE(k, begins[part]);
        joined[i].insert(joined[i].end(), partChanges[3 * part + i].begin(), partChanges[3 * part + i].end());
      }
    for (int i = 0; i < 3; ++i) ASSERT_EQ(joined[i], plain[i]) << "trial " << t << " list " << i;
  }
}

TEST(PairDiff, PlainListsSkipSharedRunsAndGiveTheSameChanges) {
  // Lists that share most keys, as one step's with the last: with IgnoreKept, two plain lists skip their
  // shared runs four keys at a time; the changes must be the plain walk's, on whole lists and by parts.
  std::mt19937_64 rng(21);
  for (int t = 0; t < 60; ++t) {
    const auto before = randomSorted(rng, rng() % 40000, 1u << 30);
    std::vector<std::uint64_t> now;
    const int change = 1 + int(rng() % 200);  // about one key in `change` dropped, one in `change` new
    for (std::uint64_t k : before) {
      if (rng() % change == 0) continue;
      if (rng() % change == 0 && (now.empty() || now.back() < k - 1)) now.push_back(k - 1);
      now.push_back(k);
    }
    if (t % 5 == 0) now.clear();
    std::vector<std::uint64_t> expect[2], whole[2], joined[2];
    gpucol::diffSortedPairs(
        before, now, [&](std::uint64_t k) { expect[0].push_back(k); },
        [&](std::uint64_t k) { expect[1].push_back(k); }, [](std::uint64_t) {});
    gpucol::diffSortedPairs(
        before, now, [&](std::uint64_t k) { whole[0].push_back(k); },
        [&](std::uint64_t k) { whole[1].push_back(k); }, gpucol::IgnoreKept{});
    gpucol::PackedPairs plainBefore, plainNow;
    plainBefore.assign(before, true);
    plainNow.assign(now, true);
    std::vector<std::vector<std::uint64_t>> partChanges(2 * gpucol::diffParts(plainNow));
    std::atomic<std::size_t> rawWalks{0};
    gpucol::diffCodedInParts(plainBefore, plainNow, [&](std::size_t part, std::uint64_t, auto b, auto n) {
      if constexpr (std::is_same_v<decltype(b), gpucol::SortedKeyReader>) ++rawWalks;  // not the coded walk
      auto* c = &partChanges[2 * part];
      gpucol::diffSortedReaders(
          b, n, [&](std::uint64_t k) { c[0].push_back(k); }, [&](std::uint64_t k) { c[1].push_back(k); },
          gpucol::IgnoreKept{});
    });
    ASSERT_EQ(rawWalks, partChanges.size() / 2);
    for (std::size_t j = 0; j < partChanges.size(); ++j)
      joined[j % 2].insert(joined[j % 2].end(), partChanges[j].begin(), partChanges[j].end());
    for (int i = 0; i < 2; ++i) {
      ASSERT_EQ(whole[i], expect[i]) << "trial " << t << " list " << i;
      ASSERT_EQ(joined[i], expect[i]) << "trial " << t << " list " << i;
    }
  }
}

TEST(PairDiff, EmptySides) {
  const std::vector<std::uint64_t> some{1, 5, 9}, none;
  int added = 0, removed = 0, kept = 0;
  auto count = [&](const auto& a, const auto& b) {
    added = removed = kept = 0;
    gpucol::diffSortedPairs(
        a, b, [&](std::uint64_t) { ++added; }, [&](std::uint64_t) { ++removed; },
        [&](std::uint64_t) { ++kept; });
  };
  count(none, some);
  EXPECT_EQ(added, 3);
  EXPECT_EQ(removed + kept, 0);
  count(some, none);
  EXPECT_EQ(removed, 3);
  EXPECT_EQ(added + kept, 0);
  count(some, some);
  EXPECT_EQ(kept, 3);
  EXPECT_EQ(added + removed, 0);
}

}  // namespace
