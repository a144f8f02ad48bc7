#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace gpucol::bench {

/// Median of a set of samples (the mean of the two middle ones for an even count); 0 for none.
inline double median(std::vector<double> samples) {
  if (samples.empty()) return 0;
  std::sort(samples.begin(), samples.end());
  const std::size_t mid = samples.size() / 2;
  return samples.size() % 2 ? samples[mid] : 0.5 * (samples[mid - 1] + samples[mid]);
}

/// Milliseconds that `work` takes, run once.
template <typename Work>
double millisecondsOf(Work&& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// Two ways of doing the same work, timed taking turns in blocks (see takeTurns).
struct TurnTimes {
  double firstMs = 0;    ///< Median over the blocks of the first's block median.
  double secondMs = 0;   ///< The same for the second.
  double ratio = 0;      ///< Median over the blocks of second / first.
  double ratioLow = 0;   ///< Smallest block ratio.
  double ratioHigh = 0;  ///< Largest block ratio.
};

/// Calls per block of takeTurns, and how many of a block's first calls are not counted: after a switch each
/// way ran slow for several calls (caches and threads warming up; measurement history, "Figures moved from
/// code comments"), and calls alternating one by one measure only that.
constexpr int kTurnCalls = 14;
constexpr int kTurnWarmCalls = 6;

/// Runs `first` and `second` in `blocks` turns of kTurnCalls calls each, so that both meet the same load on a
/// shared machine, and times each call; the first kTurnWarmCalls of a block are not counted. `afterFirst()`
/// is called after each counted call of `first`, to collect that call's own figures.
template <typename First, typename Second, typename AfterFirst>
TurnTimes takeTurns(int blocks, First&& first, Second&& second, AfterFirst&& afterFirst) {
  std::vector<double> firstMs, secondMs, ratio;
  for (int i = 0; i < blocks; ++i) {
    std::vector<double> firstBlock, secondBlock;
    for (int k = 0; k < kTurnCalls; ++k) {
      const double ms = millisecondsOf(first);
      if (k < kTurnWarmCalls) continue;
      firstBlock.push_back(ms);
      afterFirst();
    }
    for (int k = 0; k < kTurnCalls; ++k) {
      const double ms = millisecondsOf(second);
      if (k >= kTurnWarmCalls) secondBlock.push_back(ms);
    }
    firstMs.push_back(median(firstBlock));
    secondMs.push_back(median(secondBlock));
    ratio.push_back(secondMs.back() / firstMs.back());
  }
  TurnTimes t;
  t.firstMs = median(firstMs);
  t.secondMs = median(secondMs);
  t.ratio = median(ratio);
  if (!ratio.empty()) {
    t.ratioLow = *std::min_element(ratio.begin(), ratio.end());
    t.ratioHigh = *std::max_element(ratio.begin(), ratio.end());
  }
  return t;
}

}  // namespace gpucol::bench
