#include "demo/plot_axis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace gpucol::demo {
namespace {

// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
double niceStep(double raw) {
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw * (1 - 1e-9)) return m * power;
  }
  return 10 * power;
}

std::string formatFixed(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  std::string out = buffer;
  // "-0" and "-0.0" read as a different number from 0.
  if (out.find_first_not_of("-0.") == std::string::npos && out[0] == '-') out.erase(0, 1);
  return out;
}

std::string formatPowerOfTen(int exponent) {
  if (exponent >= -3 && exponent <= 3) return formatFixed(std::pow(10.0, exponent), std::max(0, -exponent));
  return "1e" + std::to_string(exponent);
}

}  // namespace

PlotAxis PlotAxis::linear(double low, double high, int ticks) {
  if (!std::isfinite(low) || !std::isfinite(high)) low = 0, high = 1;
  if (high < low) std::swap(low, high);
  if (high - low <= std::numeric_limits<double>::epsilon() * std::max(1.0, std::fabs(high))) {
    // A flat series: a range around it, so that the line sits mid-axis.
    const double half = std::max(1e-3, 0.1 * std::fabs(high));
    low -= half;
    high += half;
  }
  const double step = niceStep((high - low) / std::max(1, ticks));
  PlotAxis axis;
  // A millionth of a step of slack: 600 steps of 1/60 s end at 10.0000002 s, which should not add a step.
  axis.m_low = std::floor(low / step + 1e-6) * step;
  axis.m_high = std::ceil(high / step - 1e-6) * step;
  const int decimals = std::max(0, -int(std::floor(std::log10(step) + 1e-9)));
  const long first = std::lround(axis.m_low / step), last = std::lround(axis.m_high / step);
  for (long k = first; k <= last; ++k)
    axis.m_ticks.push_back({double(k) * step, formatFixed(double(k) * step, decimals)});
  return axis;
}

PlotAxis PlotAxis::logarithmic(double low, double high) {
  if (!(low > 0) || !(high > 0) || !std::isfinite(low) || !std::isfinite(high)) {
    throw std::invalid_argument("a logarithmic axis needs a positive, finite range");
  }
  if (high < low) std::swap(low, high);
  int bottom = int(std::floor(std::log10(low) + 1e-9));
  int top = int(std::ceil(std::log10(high) - 1e-9));
  if (top <= bottom) top = bottom + 1;
  PlotAxis axis;
  axis.m_logarithmic = true;
  axis.m_low = std::pow(10.0, bottom);
  axis.m_high = std::pow(10.0, top);
  // Over many decades, label every second or third one so the numbers do not run into each other.
  const int labelEvery = (top - bottom + 7) / 8;
  for (int e = bottom; e <= top; ++e) {
    axis.m_ticks.push_back({std::pow(10.0, e), (e - bottom) % labelEvery == 0 ? formatPowerOfTen(e) : ""});
    if (e == top || top - bottom > 12) continue;  // Minor ticks only while there is room for them.
    for (int m = 2; m <= 9; ++m) axis.m_ticks.push_back({m * std::pow(10.0, e), ""});
  }
  return axis;
}

double PlotAxis::fraction(double value) const {
  if (!m_logarithmic) return (value - m_low) / (m_high - m_low);
  if (!(value > 0)) return -std::numeric_limits<double>::infinity();
  return (std::log10(value) - std::log10(m_low)) / (std::log10(m_high) - std::log10(m_low));
}

}  // namespace gpucol::demo
