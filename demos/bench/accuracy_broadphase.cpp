// The broad phase's studies of `gpucol-bench accuracy`: the square root behind the mapping function's first guess
// (paper §3.3) and the grid's cell size (§4.1).
#include <cstdint>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "accuracy_row.h"
#include "bench_stats.h"
#include "broadphase/pair_mapping.h"

namespace gpucol::bench {
namespace {

// A guess of the row of pair index k: the double square root (-1 steps here) or the magic-constant root with
// `steps` Newton steps.
gpucol_u64 rowGuess(gpucol_u64 n, gpucol_u64 k, int steps) {
  return steps < 0 ? gpucol_pair_row_guess_double(n, k) : gpucol_pair_row_guess_newton_steps(n, k, steps);
}

std::string sqrtName(int steps) {
  return steps < 0 ? std::string("double") : "newton " + std::to_string(steps);
}

void mappingStudy(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  const std::uint64_t mappings = context.quick ? 1000000 : 10000000;
  for (const gpucol_u64 n : {gpucol_u64(100000), gpucol_u64(10000000)}) {
    const gpucol_u64 pairs = gpucol_pair_count(n);
    std::mt19937_64 rng(99);
    std::uniform_int_distribution<gpucol_u64> pick(0, pairs - 1);
    std::vector<gpucol_u64> ks(mappings);
    for (gpucol_u64& k : ks) k = pick(rng);
    for (int steps : {-1, 1, 2, 3}) {
      // How often the guess is not the row: the integer fix-up then moves it (the answer is exact either way).
      std::uint64_t wrong = 0;
      for (gpucol_u64 k : ks) wrong += rowGuess(n, k, steps) != gpucol_pair_fix_row(n, k, rowGuess(n, k, -1));
      // Time of guess + fix-up, one thread; the sum keeps the work from being optimised away. A guess that is
      // mostly wrong leaves the fix-up walking many rows per index, so it is timed on a hundredth of them.
      const std::size_t timed = wrong * 2 > mappings ? ks.size() / 100 : ks.size();
      volatile gpucol_u64 sink = 0;
      std::vector<double> samples;
      for (int run = 0; run < context.runs; ++run) {
        samples.push_back(millisecondsOf([&] {
          gpucol_u64 sum = 0;
          for (std::size_t i = 0; i < timed; ++i) sum += gpucol_pair_fix_row(n, ks[i], rowGuess(n, ks[i], steps));
          sink = sink + sum;
        }));
      }
      AccuracyRow row;
      row.study = "mapping_sqrt";
      row.scene = "n = " + std::to_string(n);
      row.setting = sqrtName(steps);
      row.isDefault = steps < 0;  // PairFinderOptions::mappingSqrt defaults to the double root.
      row.timeMs = median(samples) * (1e7 / double(timed));
      row.guessErrorRate = double(wrong) / double(mappings);
      row.mappingSqrt = row.setting;
      printAccuracyRow(row);
      rows.push_back(std::move(row));
    }
  }
}

}  // namespace

void runBroadphaseAccuracyStudies(const AccuracyContext& context, std::vector<AccuracyRow>& rows) {
  std::cout << "mapping_sqrt: share of first guesses off the row (fixed exactly afterwards), ms per 10^7 indices\n";
  mappingStudy(context, rows);
}

}  // namespace gpucol::bench
