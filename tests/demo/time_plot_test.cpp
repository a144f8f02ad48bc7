// The demo's time plot and PNG output: axis ticks, the written file read back with stb_image (Debian's
// libstb), and refusals.
#include "demo/time_plot.h"

#include <gtest/gtest.h>
#include <stb_image.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "demo/plot_axis.h"
#include "demo/png_writer.h"
#include "demo/rgb_image.h"

namespace gpucol::demo {
namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("gpucol_demo_test_" + name)).string();
}

std::vector<std::string> labels(const PlotAxis& axis) {
  std::vector<std::string> out;
  for (const AxisTick& tick : axis.ticks()) {
    if (!tick.label.empty()) out.push_back(tick.label);
  }
  return out;
}

// A fall and a settle: heights decay to a rest value, energy decays and is exactly zero at the end (asleep).
TimeSeries settlingSeries() {
  TimeSeries series;
  for (int i = 0; i <= 300; ++i) {
    const double t = i / 60.0;
    series.time.push_back(t);
    series.trackedHeight.push_back(9.5 + 0.2 * std::exp(-3 * t) * std::cos(20 * t));
    series.highestHeight.push_back(series.trackedHeight.back());
    series.meanHeight.push_back(5.0);
    series.kineticEnergy.push_back(i < 200 ? 300 * std::exp(-4 * t) : 0.0);
  }
  return series;
}

TEST(PlotAxis, LinearTicksAreWholeNiceSteps) {
  // 600 steps of 1/60 s end a hair above 10 s: that must not add a step.
  const PlotAxis time = PlotAxis::linear(0, 600 * (1.0f / 60.0f));
  EXPECT_EQ(time.low(), 0);
  EXPECT_EQ(time.high(), 10);
  EXPECT_EQ(labels(time), (std::vector<std::string>{"0", "2", "4", "6", "8", "10"}));
  const PlotAxis small = PlotAxis::linear(-0.013, 0.041, 5);
  // 0.054 / 5 = 0.0108 rounds up to a step of 0.02; the labels keep the step's two decimals.
  EXPECT_EQ(labels(small), (std::vector<std::string>{"-0.02", "0.00", "0.02", "0.04", "0.06"}));
  EXPECT_DOUBLE_EQ(small.fraction(small.low()), 0);
  EXPECT_DOUBLE_EQ(small.fraction(small.high()), 1);
}

TEST(PlotAxis, LogarithmicTicksAtPowersOfTen) {
  const PlotAxis energy = PlotAxis::logarithmic(0.02, 280);
  EXPECT_DOUBLE_EQ(energy.low(), 0.01);
  EXPECT_DOUBLE_EQ(energy.high(), 1000);
  EXPECT_EQ(labels(energy), (std::vector<std::string>{"0.01", "0.1", "1", "10", "100", "1000"}));
  EXPECT_NEAR(energy.fraction(1), 0.4, 1e-12);
  EXPECT_EQ(labels(PlotAxis::logarithmic(1e-7, 2e-6)), (std::vector<std::string>{"1e-7", "1e-6", "1e-5"}));
  EXPECT_THROW(PlotAxis::logarithmic(0, 1), std::invalid_argument);
}

TEST(TimePlot, WritesAPngOfTheStatedSize) {
  PlotOptions options;
  options.width = 640;
  options.height = 480;
  options.title = "test plot";
  const RgbImage plot = drawTimePlot(settlingSeries(), options);
  ASSERT_EQ(plot.width(), 640);
  ASSERT_EQ(plot.height(), 480);
  const std::string path = tempPath("plot.png");
  writePng(plot, path);

  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load(path.c_str(), &width, &height, &channels, 3);
  ASSERT_NE(pixels, nullptr) << stbi_failure_reason();
  EXPECT_EQ(width, 640);
  EXPECT_EQ(height, 480);
  EXPECT_EQ(channels, 3);
  // PNG is lossless: the file holds exactly the drawn pixels.
  bool same = true;
  for (int y = 0; y < height && same; ++y) {
    for (int x = 0; x < width && same; ++x) {
      const Rgb p = plot.at(x, y);
      const unsigned char* q = pixels + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
      same = p.r == q[0] && p.g == q[1] && p.b == q[2];
    }
  }
  stbi_image_free(pixels);
  std::remove(path.c_str());
  EXPECT_TRUE(same);

  // Something coloured (the curves) in each half, not only the white page and grey axes.
  auto coloured = [&plot](int y0, int y1) {
    int count = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < plot.width(); ++x) {
        const Rgb p = plot.at(x, y);
        count += std::max({p.r, p.g, p.b}) - std::min({p.r, p.g, p.b}) > 80;
      }
    }
    return count;
  };
  EXPECT_GT(coloured(0, 240), 200);
  EXPECT_GT(coloured(240, 480), 200);
  // Dark text and ticks left of the panels (the numbers of the height and energy axes).
  int dark = 0;
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 90; ++x) dark += plot.at(x, y).r < 100;
  }
  EXPECT_GT(dark, 100);
}

TEST(TimePlot, RefusesWhatItCannotDraw) {
  EXPECT_THROW(drawTimePlot(TimeSeries{}), std::invalid_argument);
  PlotOptions tiny;
  tiny.width = 100;
  EXPECT_THROW(drawTimePlot(settlingSeries(), tiny), std::invalid_argument);
}

TEST(PngWriter, MissingFolderIsAClearError) {
  const std::string path = tempPath("no_such_folder/picture.png");
  try {
    writePng(RgbImage(4, 4), path);
    FAIL() << "no error for " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(RgbImage, DownsamplingAveragesBlocks) {
  RgbImage image(4, 2, Rgb{0, 0, 0});
  image.at(0, 0) = {255, 255, 255};
  image.at(1, 1) = {255, 0, 0};
  const RgbImage small = image.downsampled(2);
  ASSERT_EQ(small.width(), 2);
  ASSERT_EQ(small.height(), 1);
  EXPECT_EQ(small.at(0, 0), (Rgb{128, 64, 64}));
  EXPECT_EQ(small.at(1, 0), (Rgb{0, 0, 0}));
  EXPECT_THROW(image.downsampled(3), std::invalid_argument);
}

}  // namespace
}  // namespace gpucol::demo
