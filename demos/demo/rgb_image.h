#pragma once

#include <cstdint>
#include <vector>

namespace gpucol::demo {

/// One 8-bit sRGB pixel, laid out as three bytes so that an image's pixels are the array a PNG writer takes.
struct Rgb {
  std::uint8_t r = 0;  ///< Red.
  std::uint8_t g = 0;  ///< Green.
  std::uint8_t b = 0;  ///< Blue.

  /// Exact equality of the three channels.
  friend bool operator==(const Rgb& a, const Rgb& b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
  /// Inequality.
  friend bool operator!=(const Rgb& a, const Rgb& b) { return !(a == b); }
};
static_assert(sizeof(Rgb) == 3, "an RgbImage's pixels must be tightly packed bytes");

/// `colour` with each channel multiplied by `factor` (clamped to 0..255, rounded).
Rgb scaled(Rgb colour, float factor);
/// `a` moved towards `b` by `t` in 0..1 (per channel, rounded).
Rgb mixed(Rgb a, Rgb b, float t);

/// A width × height picture of Rgb pixels, rows top to bottom.
class RgbImage {
 public:
  /// An empty image (0 × 0).
  RgbImage() = default;
  /// A width × height image filled with `fill`; throws std::invalid_argument for a non-positive size.
  RgbImage(int width, int height, Rgb fill = {});

  /// Pixels per row.
  int width() const { return m_width; }
  /// Rows.
  int height() const { return m_height; }
  /// The pixel in column x, row y (0, 0 is the top left); unchecked.
  Rgb& at(int x, int y) { return m_pixels[std::size_t(y) * std::size_t(m_width) + std::size_t(x)]; }
  /// See the other at().
  const Rgb& at(int x, int y) const {
    return m_pixels[std::size_t(y) * std::size_t(m_width) + std::size_t(x)];
  }
  /// True when (x, y) is inside the image.
  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < m_width && y < m_height; }
  /// The pixels, row by row, three bytes each.
  const std::uint8_t* bytes() const { return reinterpret_cast<const std::uint8_t*>(m_pixels.data()); }

  /// This image shrunk by an integer `factor` (width and height must be multiples of it), each pixel the mean
  /// of a factor × factor block: how the pictures are anti-aliased (drawn at factor × the size, then shrunk).
  RgbImage downsampled(int factor) const;

 private:
  int m_width = 0;
  int m_height = 0;
  std::vector<Rgb> m_pixels;
};

}  // namespace gpucol::demo
