#include "demo/time_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "demo/canvas.h"
#include "demo/plot_axis.h"
#include "demo/png_writer.h"

namespace gpucol::demo {
namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kInk{40, 40, 40};
constexpr Rgb kFrame{110, 110, 110};
constexpr Rgb kGrid{228, 228, 228};
constexpr Rgb kMinorGrid{242, 242, 242};
// Colours told apart by people with the common colour-vision deficiencies (Okabe and Ito's palette).
constexpr Rgb kTrackedColour{213, 94, 0};
constexpr Rgb kMeanColour{0, 114, 178};
constexpr Rgb kStartColour{120, 120, 120};
constexpr Rgb kEnergyColour{0, 158, 115};

struct Series {
  const std::vector<double>* values;
  Rgb colour;
  std::string label;
  float dash;  // 0: solid.
};

struct Rect {
  float left, top, right, bottom;
};

// Draws one panel: grid, frame, ticks and numbers on both axes, the y label turned, the series and a legend.
void drawPanel(Canvas& canvas, const Rect& r, const std::vector<double>& time, const PlotAxis& xAxis,
               const PlotAxis& yAxis, const std::vector<Series>& series, const std::string& yLabel,
               const std::string& xLabel, float unit) {
  const float font = 2 * unit;
  auto px = [&](double t) { return r.left + float(xAxis.fraction(t)) * (r.right - r.left); };
  auto py = [&](double v) {
    const double f = std::clamp(yAxis.fraction(v), 0.0, 1.0);  // Clamped: a log axis's zeros sit on the edge.
    return r.bottom - float(f) * (r.bottom - r.top);
  };

  canvas.fillRect(r.left, r.top, r.right, r.bottom, kWhite);
  for (const AxisTick& tick : yAxis.ticks()) {
    if (tick.value < yAxis.low() || tick.value > yAxis.high()) continue;
    const float y = py(tick.value);
    canvas.line(r.left, y, r.right, y, unit, tick.label.empty() ? kMinorGrid : kGrid);
  }
  for (const AxisTick& tick : xAxis.ticks()) {
    const float x = px(tick.value);
    canvas.line(x, r.top, x, r.bottom, unit, kGrid);
  }

  float widestLabel = 0;
  for (const AxisTick& tick : yAxis.ticks()) {
    if (tick.value < yAxis.low() || tick.value > yAxis.high()) continue;
    const float y = py(tick.value);
    const float length = tick.label.empty() ? 3 * unit : 6 * unit;
    canvas.line(r.left - length, y, r.left, y, unit, kFrame);
    if (!tick.label.empty()) {
      canvas.text(r.left - 9 * unit, y, tick.label, font, kInk, Align::End, Align::Centre);
      widestLabel = std::max(widestLabel, Canvas::textWidth(tick.label, font));
    }
  }
  for (const AxisTick& tick : xAxis.ticks()) {
    const float x = px(tick.value);
    canvas.line(x, r.bottom, x, r.bottom + 6 * unit, unit, kFrame);
    canvas.text(x, r.bottom + 10 * unit, tick.label, font, kInk, Align::Centre, Align::Start);
  }
  canvas.text(r.left - 9 * unit - widestLabel - 10 * unit, 0.5f * (r.top + r.bottom), yLabel, font, kInk,
              Align::Centre, Align::End, true);
  if (!xLabel.empty()) {
    canvas.text(0.5f * (r.left + r.right), r.bottom + 10 * unit + Canvas::textHeight(font) + 9 * unit, xLabel,
                font, kInk, Align::Centre, Align::Start);
  }

  canvas.setClip(r.left, r.top, r.right, r.bottom);
  for (const Series& s : series) {
    std::vector<std::pair<float, float>> points;
    points.reserve(time.size());
    for (std::size_t i = 0; i < time.size() && i < s.values->size(); ++i)
      points.emplace_back(px(time[i]), py((*s.values)[i]));
    if (s.dash > 0 && points.size() >= 2) {
      canvas.line(points.front().first, points.front().second, points.back().first, points.back().second,
                  1.5f * unit, s.colour, s.dash * unit);
    } else {
      canvas.polyline(points, 2 * unit, s.colour);
    }
  }
  canvas.resetClip();
  canvas.line(r.left, r.top, r.right, r.top, unit, kFrame);
  canvas.line(r.left, r.bottom, r.right, r.bottom, unit, kFrame);
  canvas.line(r.left, r.top, r.left, r.bottom, unit, kFrame);
  canvas.line(r.right, r.top, r.right, r.bottom, unit, kFrame);

  // Legend in the top right corner: a sample of each line and its name.
  const float rowHeight = 16 * unit, sample = 26 * unit, pad = 8 * unit;
  float widest = 0;
  for (const Series& s : series) widest = std::max(widest, Canvas::textWidth(s.label, font));
  const float boxRight = r.right - 10 * unit, boxTop = r.top + 10 * unit;
  const float boxLeft = boxRight - (pad + sample + 8 * unit + widest + pad);
  const float boxBottom =
      boxTop + pad + rowHeight * float(series.size()) - (rowHeight - Canvas::textHeight(font)) + pad;
  canvas.fillRect(boxLeft - unit, boxTop - unit, boxRight + unit, boxBottom + unit, kFrame);
  canvas.fillRect(boxLeft, boxTop, boxRight, boxBottom, kWhite);
  for (std::size_t i = 0; i < series.size(); ++i) {
    const float y = boxTop + pad + rowHeight * float(i) + 0.5f * Canvas::textHeight(font);
    canvas.line(boxLeft + pad, y, boxLeft + pad + sample, y, 2 * unit, series[i].colour,
                series[i].dash * unit);
    canvas.text(boxLeft + pad + sample + 8 * unit, y, series[i].label, font, kInk, Align::Start,
                Align::Centre);
  }
}

}  // namespace

RgbImage drawTimePlot(const TimeSeries& series, const PlotOptions& options) {
  if (series.size() == 0) throw std::invalid_argument("time plot: no samples were recorded");
  if (options.width < 320 || options.height < 240)
    throw std::invalid_argument("time plot: smaller than 320 x 240");
  if (options.supersample < 1 || options.supersample > 8)
    throw std::invalid_argument("time plot: supersample 1 to 8");
  const float unit = float(options.supersample);
  RgbImage image(options.width * options.supersample, options.height * options.supersample, kWhite);
  Canvas canvas(image);

  const float width = float(image.width()), height = float(image.height());
  const float left = 96 * unit, right = width - 24 * unit, top = 48 * unit, bottom = height - 60 * unit;
  const float gap = 58 * unit, panel = 0.5f * (bottom - top - gap);
  const Rect upper{left, top, right, top + panel};
  const Rect lower{left, top + panel + gap, right, bottom};
  if (!options.title.empty())
    canvas.text(0.5f * width, 16 * unit, options.title, 2.5f * unit, kInk, Align::Centre);

  const PlotAxis timeAxis =
      PlotAxis::linear(series.time.front(), std::max(series.time.back(), series.time.front() + 1e-3));

  // Heights: the tracked body (or the highest), the mean, and where the first started.
  const bool tracked = series.trackedHeight.size() == series.size();
  const std::vector<double>& lead = tracked ? series.trackedHeight : series.highestHeight;
  const std::vector<double> start(series.size(), lead.front());
  // The dashed start line last, so that it shows on top of a body that stays where it started.
  std::vector<Series> heights = {
      {&lead, kTrackedColour, tracked ? options.trackedLabel : std::string("highest body"), 0},
      {&series.meanHeight, kMeanColour, "mean of all bodies", 0},
      {&start, kStartColour, "start height", 6},
  };
  double low = 0, high = 0;
  for (const Series& s : heights) {
    for (double v : *s.values) {
      if (std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
    }
  }
  const PlotAxis heightAxis = PlotAxis::linear(low, high * 1.08 + 1e-3, 5);
  drawPanel(canvas, upper, series.time, timeAxis, heightAxis, heights, "height of centre (m)", "", unit);

  // Energy on powers of ten: at least four decades under the largest value, so that a drop to zero (bodies
  // falling asleep) reads as one; lower when the smallest positive value is lower, but no more than nine
  // decades, so that round-off does not fill the panel.
  double largest = 0, smallestPositive = std::numeric_limits<double>::infinity();
  bool zeros = false;
  for (double e : series.kineticEnergy) {
    if (!std::isfinite(e)) continue;
    largest = std::max(largest, e);
    if (e > 0) smallestPositive = std::min(smallestPositive, e);
    zeros |= e <= 0;
  }
  const PlotAxis energyAxis =
      largest > 0
          ? PlotAxis::logarithmic(std::clamp(smallestPositive, largest * 1e-9, largest * 1e-4), largest)
          : PlotAxis::logarithmic(1e-6, 1);
  bool clamped = zeros;
  for (double e : series.kineticEnergy) clamped |= e > 0 && e < energyAxis.low();
  const std::vector<Series> energy = {{&series.kineticEnergy, kEnergyColour,
                                       zeros     ? "kinetic energy (0 J on the bottom edge)"
                                       : clamped ? "kinetic energy (values under the axis on its bottom edge)"
                                                 : "kinetic energy, all bodies",
                                       0}};
  drawPanel(canvas, lower, series.time, timeAxis, energyAxis, energy, "kinetic energy (J)", "time (s)", unit);
  return image.downsampled(options.supersample);
}

void writeTimePlot(const TimeSeries& series, const std::string& path, const PlotOptions& options) {
  writePng(drawTimePlot(series, options), path);
}

}  // namespace gpucol::demo
