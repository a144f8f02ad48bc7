#pragma once

#include <string>

#include "demo/rgb_image.h"
#include "demo/time_series.h"

namespace gpucol::demo {

/// How drawTimePlot lays out a plot.
struct PlotOptions {
  int width = 1000;   ///< Pixels.
  int height = 720;   ///< Pixels.
  std::string title;  ///< Written above the panels (the scene, backend and steps).
  /// Legend name of TimeSeries::trackedHeight (the scene's tracked body).
  std::string trackedLabel = "tracked body";
  /// Samples per pixel along each axis: drawn this many times larger and shrunk (anti-aliasing).
  int supersample = 2;
};

/// Two panels over a shared time axis: above, the height of the tracked body (or, without one, of the highest
/// body) and the mean height of all bodies, with the tracked body's start height dashed; below, the kinetic
/// energy on a logarithmic axis (exact zeros, when every body sleeps, lie on the bottom edge). Axes with
/// numbered ticks, grid lines, axis labels and a legend per panel. Throws std::invalid_argument for an empty
/// series or a size under 320 × 240.
RgbImage drawTimePlot(const TimeSeries& series, const PlotOptions& options = {});

/// drawTimePlot written as a PNG at `path` (throws std::runtime_error when it cannot be written).
void writeTimePlot(const TimeSeries& series, const std::string& path, const PlotOptions& options = {});

}  // namespace gpucol::demo
