// The mapping function k → (a, b) of Avril et al. 2012 §3.2, checked exhaustively against the row-major
// enumeration (the definition) and on random k for n up to 10^7 against the inverse k = S(a) + b - a - 1.
#include <gtest/gtest.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <cstdint>
#include <random>

#include "shared_math/pair_mapping.h"

namespace {

using MapFn = void (*)(gpucol_u64, gpucol_u64, gpucol_u64*, gpucol_u64*);

/// Walks every k of n objects beside the nested-loop enumeration; returns the number of mismatches.
std::uint64_t mismatchesAllK(std::uint64_t n, MapFn map) {
  std::uint64_t bad = 0, k = 0;
  for (std::uint64_t a = 0; a + 1 < n; ++a)
    for (std::uint64_t b = a + 1; b < n; ++b, ++k) {
      gpucol_u64 ra = 0, rb = 0;
      map(n, k, &ra, &rb);
      bad += (ra != a || rb != b);
    }
  return bad;
}

TEST(PairMapping, CountAndRowStartMatchTheSeries) {
  for (std::uint64_t n = 2; n < 200; ++n) {
    std::uint64_t s = 0;
    for (std::uint64_t a = 0; a + 1 < n; ++a) {
      EXPECT_EQ(gpucol_pair_row_start(n, a), s) << "n=" << n << " a=" << a;
      s += n - 1 - a;
    }
    EXPECT_EQ(gpucol_pair_count(n), s);
  }
}

TEST(PairMapping, EveryKForEveryNUpTo300BothRoots) {
  for (std::uint64_t n = 2; n <= 300; ++n) {
    ASSERT_EQ(mismatchesAllK(n, gpucol_pair_from_index), 0u) << "double, n=" << n;
    ASSERT_EQ(mismatchesAllK(n, gpucol_pair_from_index_newton), 0u) << "newton, n=" << n;
  }
}

/// Every k of n objects, rows in parallel; returns mismatches of both roots.
std::uint64_t mismatchesAllKParallel(std::uint64_t n) {
  std::atomic<std::uint64_t> bad{0};
  tbb::parallel_for(std::uint64_t(0), n - 1, [&](std::uint64_t a) {
    std::uint64_t localBad = 0;
    const std::uint64_t s = gpucol_pair_row_start(n, a);
    for (std::uint64_t b = a + 1; b < n; ++b) {
      const std::uint64_t k = s + (b - a - 1);
      gpucol_u64 ra = 0, rb = 0, na = 0, nb = 0;
      gpucol_pair_from_index(n, k, &ra, &rb);
      gpucol_pair_from_index_newton(n, k, &na, &nb);
      localBad += (ra != a || rb != b) + (na != a || nb != b);
    }
    bad += localBad;
  });
  return bad.load();
}

TEST(PairMapping, EveryKForNEquals4096And4097BothRoots) {
  EXPECT_EQ(mismatchesAllKParallel(4096), 0u);
  EXPECT_EQ(mismatchesAllKParallel(4097), 0u);
}

// n = 2^16: all 2^31 - 2^15 pairs with both roots, the largest n checked exhaustively (16 s on both cores
// of the 2-core machine, so it stays in the default run).
TEST(PairMapping, EveryKForNEquals65536BothRoots) { EXPECT_EQ(mismatchesAllKParallel(65536), 0u); }

TEST(PairMapping, RowBoundariesForManyNUpTo65536) {
  // The square root goes wrong first at row starts (k = S(a) and S(a) - 1), so check those for a spread of n.
  std::uint64_t bad = 0;
  for (std::uint64_t n = 2; n <= 65536; n = n < 4096 ? n + 1 : n + 977) {
    for (std::uint64_t a = 0; a + 1 < n; ++a) {
      const std::uint64_t s = gpucol_pair_row_start(n, a);
      gpucol_u64 ra = 0, rb = 0;
      gpucol_pair_from_index_newton(n, s, &ra, &rb);
      bad += (ra != a || rb != a + 1);
      gpucol_pair_from_index(n, s, &ra, &rb);
      bad += (ra != a || rb != a + 1);
      if (a > 0) {
        gpucol_pair_from_index_newton(n, s - 1, &ra, &rb);
        bad += (ra != a - 1 || rb != n - 1);
      }
    }
  }
  EXPECT_EQ(bad, 0u);
}

TEST(PairMapping, RandomKForNUpTo1e7) {
  std::mt19937_64 rng(20120521);
  std::uint64_t bad = 0;
  for (int t = 0; t < 2'000'000; ++t) {
    const std::uint64_t n = 2 + rng() % (10'000'000 - 1);
    const std::uint64_t total = gpucol_pair_count(n);
    // Half uniform k, half near a row start, where rounding of the root matters most.
    std::uint64_t k = rng() % total;
    if (t & 1) {
      const std::uint64_t a = rng() % (n - 1);
      k = gpucol_pair_row_start(n, a) - (a > 0 && (rng() & 1) ? 1 : 0);
    }
    gpucol_u64 a = 0, b = 0, na = 0, nb = 0;
    gpucol_pair_from_index(n, k, &a, &b);
    gpucol_pair_from_index_newton(n, k, &na, &nb);
    const bool ok = a < b && b < n && gpucol_pair_index(n, a, b) == k && na == a && nb == b;
    if (!ok && bad < 5) ADD_FAILURE() << "n=" << n << " k=" << k << " -> (" << a << "," << b << ") newton ("
                                      << na << "," << nb << ")";
    bad += !ok;
  }
  EXPECT_EQ(bad, 0u);
}

TEST(PairMapping, NewtonGuessAloneIsNotExactButFixUpIs) {
  // The paper's point (§3.3, Table 3): the float/Newton root alone gives wrong rows for large n. Show
  // that this test would catch an unfixed guess, so the exactness above is the fix-up's doing.
  const std::uint64_t n = 10'000'000;
  std::mt19937_64 rng(7);
  int wrongGuesses = 0;
  for (int t = 0; t < 100000; ++t) {
    const std::uint64_t a = rng() % (n - 1);
    const std::uint64_t k = gpucol_pair_row_start(n, a);
    wrongGuesses += gpucol_pair_row_guess_newton(n, k) != a;
    EXPECT_EQ(gpucol_pair_fix_row(n, k, gpucol_pair_row_guess_newton(n, k)), a);
  }
  EXPECT_GT(wrongGuesses, 0);
}

}  // namespace
