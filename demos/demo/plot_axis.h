#pragma once

#include <string>
#include <vector>

namespace gpucol::demo {

/// A tick on a plot axis.
struct AxisTick {
  double value = 0;   ///< Where the tick is, in data units.
  std::string label;  ///< The number written beside it; empty for a minor tick.
};

/// The range of one plot axis and its ticks: linear with "nice" steps (1, 2 or 5 times a power of ten) or
/// logarithmic with a tick at every power of ten and minor ticks at 2..9 times it.
class PlotAxis {
 public:
  /// A linear axis covering [low, high], widened outwards to whole steps, with about `ticks` steps.
  static PlotAxis linear(double low, double high, int ticks = 6);
  /// A logarithmic axis over whole powers of ten covering [low, high] (both > 0; throws std::invalid_argument
  /// otherwise).
  static PlotAxis logarithmic(double low, double high);

  /// Lowest value on the axis.
  double low() const { return m_low; }
  /// Highest value on the axis.
  double high() const { return m_high; }
  /// True for a logarithmic axis.
  bool isLogarithmic() const { return m_logarithmic; }
  /// Where `value` lies along the axis, 0 at low() and 1 at high(); on a logarithmic axis a value at or below
  /// 0 maps to 0's side (minus infinity), so the caller clamps.
  double fraction(double value) const;
  /// Labelled (major) ticks and unlabelled (minor) ones, in increasing order.
  const std::vector<AxisTick>& ticks() const { return m_ticks; }

 private:
  double m_low = 0;
  double m_high = 1;
  bool m_logarithmic = false;
  std::vector<AxisTick> m_ticks;
};

}  // namespace gpucol::demo
