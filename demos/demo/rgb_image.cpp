#include "demo/rgb_image.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace gpucol::demo {
namespace {

std::uint8_t toByte(float value) {
  return std::uint8_t(std::clamp(std::lround(value), 0L, 255L));
}

}  // namespace

Rgb scaled(Rgb colour, float factor) {
  return {toByte(float(colour.r) * factor), toByte(float(colour.g) * factor),
          toByte(float(colour.b) * factor)};
}

Rgb mixed(Rgb a, Rgb b, float t) {
  auto mix = [t](std::uint8_t x, std::uint8_t y) { return toByte(float(x) + (float(y) - float(x)) * t); };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

RgbImage::RgbImage(int width, int height, Rgb fill) : m_width(width), m_height(height) {
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("image size must be positive, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  m_pixels.assign(std::size_t(width) * std::size_t(height), fill);
}

RgbImage RgbImage::downsampled(int factor) const {
  if (factor == 1) return *this;
  if (factor < 1 || m_width % factor != 0 || m_height % factor != 0) {
    throw std::invalid_argument("cannot shrink a " + std::to_string(m_width) + " x " +
                                std::to_string(m_height) + " image by " + std::to_string(factor));
  }
  RgbImage out(m_width / factor, m_height / factor);
  const float inverse = 1.0f / float(factor * factor);
  for (int y = 0; y < out.m_height; ++y) {
    for (int x = 0; x < out.m_width; ++x) {
      int r = 0, g = 0, b = 0;
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) {
          const Rgb& p = at(x * factor + dx, y * factor + dy);
          r += p.r;
          g += p.g;
          b += p.b;
        }
      }
      out.at(x, y) = {toByte(float(r) * inverse), toByte(float(g) * inverse), toByte(float(b) * inverse)};
    }
  }
  return out;
}

}  // namespace gpucol::demo
