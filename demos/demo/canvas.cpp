#include "demo/canvas.h"

#include <algorithm>
#include <cmath>
#include <cstring>

// stb_easy_font is header-only and all static; the functions this file does not call would warn.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

namespace gpucol::demo {
namespace {

// Font units from the top of a line to the baseline of digits and capitals.
constexpr float kCapHeight = 7;

// Characters stb_easy_font has glyphs for (it indexes a table by code - 32).
std::string printable(const std::string& text) {
  std::string out = text;
  for (char& c : out) {
    if (c < 32 || c > 126) c = '?';
  }
  return out;
}

// The quads stb_easy_font_print makes of `text` at the origin: each is an axis-aligned rectangle in font
// units.
struct Quad {
  float x0, y0, x1, y1;
};

std::vector<Quad> glyphQuads(const std::string& text) {
  std::string copy = printable(text);
  // stb's documentation: about 270 bytes per character on average; 64 bytes per quad, at most ~20 per glyph.
  std::vector<char> buffer(copy.size() * 1400 + 64);
  const int quads = stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(), int(buffer.size()));
  std::vector<Quad> out;
  out.reserve(std::size_t(quads));
  for (int q = 0; q < quads; ++q) {
    // Four vertices of 16 bytes: x, y, z floats and a colour. Copied out, not read through a float pointer:
    // the buffer is char storage, which a float lvalue may not alias.
    float v0[2], v2[2];
    std::memcpy(v0, buffer.data() + std::size_t(q) * 64, sizeof v0);
    std::memcpy(v2, buffer.data() + std::size_t(q) * 64 + 32, sizeof v2);
    out.push_back(
        {std::min(v0[0], v2[0]), std::min(v0[1], v2[1]), std::max(v0[0], v2[0]), std::max(v0[1], v2[1])});
  }
  return out;
}

float alignOffset(Align align, float size) {
  return align == Align::Start ? 0.0f : align == Align::Centre ? -0.5f * size : -size;
}

}  // namespace

Canvas::Canvas(RgbImage& image) : m_image(image) {
  resetClip();
}

void Canvas::setClip(float x0, float y0, float x1, float y1) {
  m_clip[0] = std::max(0.0f, x0);
  m_clip[1] = std::max(0.0f, y0);
  m_clip[2] = std::min(float(m_image.width()), x1);
  m_clip[3] = std::min(float(m_image.height()), y1);
}

void Canvas::resetClip() {
  setClip(0, 0, float(m_image.width()), float(m_image.height()));
}

void Canvas::fillRect(float x0, float y0, float x1, float y1, Rgb colour) {
  x0 = std::max(x0, m_clip[0]);
  y0 = std::max(y0, m_clip[1]);
  x1 = std::min(x1, m_clip[2]);
  y1 = std::min(y1, m_clip[3]);
  // Pixel i's centre i + 0.5 is in [x0, x1) when ceil(x0 - 0.5) <= i < ceil(x1 - 0.5).
  const int i0 = int(std::ceil(x0 - 0.5f)), i1 = int(std::ceil(x1 - 0.5f));
  const int j0 = int(std::ceil(y0 - 0.5f)), j1 = int(std::ceil(y1 - 0.5f));
  for (int j = j0; j < j1; ++j) {
    for (int i = i0; i < i1; ++i) m_image.at(i, j) = colour;
  }
}

void Canvas::line(float x0, float y0, float x1, float y1, float thickness, Rgb colour, float dash) {
  const float radius = 0.5f * thickness;
  const float dx = x1 - x0, dy = y1 - y0;
  const float length2 = dx * dx + dy * dy;
  const int i0 = std::max(int(std::floor(std::min(x0, x1) - radius)), int(std::ceil(m_clip[0] - 0.5f)));
  const int i1 = std::min(int(std::ceil(std::max(x0, x1) + radius)), int(std::ceil(m_clip[2] - 0.5f)) - 1);
  const int j0 = std::max(int(std::floor(std::min(y0, y1) - radius)), int(std::ceil(m_clip[1] - 0.5f)));
  const int j1 = std::min(int(std::ceil(std::max(y0, y1) + radius)), int(std::ceil(m_clip[3] - 0.5f)) - 1);
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const float px = float(i) + 0.5f - x0, py = float(j) + 0.5f - y0;
      // Distance from the pixel centre to the nearest point of the segment.
      const float t = length2 > 0 ? std::clamp((px * dx + py * dy) / length2, 0.0f, 1.0f) : 0.0f;
      const float ex = px - t * dx, ey = py - t * dy;
      if (ex * ex + ey * ey > radius * radius) continue;
      if (dash > 0 && std::fmod(t * std::sqrt(length2), 2 * dash) >= dash) continue;
      m_image.at(i, j) = colour;
    }
  }
}

void Canvas::polyline(const std::vector<std::pair<float, float>>& points, float thickness, Rgb colour) {
  for (std::size_t i = 1; i < points.size(); ++i) {
    line(points[i - 1].first, points[i - 1].second, points[i].first, points[i].second, thickness, colour);
  }
  if (points.size() == 1)
    line(points[0].first, points[0].second, points[0].first, points[0].second, thickness, colour);
}

void Canvas::text(float x, float y, const std::string& text, float scale, Rgb colour, Align horizontal,
                  Align vertical, bool turned) {
  const float along = alignOffset(horizontal, textWidth(text, scale));
  const float across = alignOffset(vertical, textHeight(scale));
  for (const Quad& q : glyphQuads(text)) {
    const float ux0 = along + q.x0 * scale, ux1 = along + q.x1 * scale;
    const float uy0 = across + q.y0 * scale, uy1 = across + q.y1 * scale;
    if (!turned) {
      fillRect(x + ux0, y + uy0, x + ux1, y + uy1, colour);
    } else {
      // A quarter turn anticlockwise: the text's right is the image's up, its down is the image's right.
      fillRect(x + uy0, y - ux1, x + uy1, y - ux0, colour);
    }
  }
}

float Canvas::textWidth(const std::string& text, float scale) {
  std::string copy = printable(text);
  // The last glyph's advance includes one unit of spacing after it.
  return std::max(0.0f, float(stb_easy_font_width(copy.data())) - 1.0f) * scale;
}

float Canvas::textHeight(float scale) {
  return kCapHeight * scale;
}

}  // namespace gpucol::demo
