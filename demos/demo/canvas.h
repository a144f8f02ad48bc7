#pragma once

#include <string>
#include <utility>
#include <vector>

#include "demo/rgb_image.h"

namespace gpucol::demo {

/// Where text or a box sits relative to the point it is drawn at.
enum class Align {
  Start,   ///< Left of the text at the point (or its top, vertically).
  Centre,  ///< Centred on the point.
  End      ///< Right (or bottom) at the point.
};

/// 2-D drawing on an RgbImage in pixel coordinates (x right, y down; the centre of pixel (i, j) is at
/// (i + 0.5, j + 0.5)): filled rectangles, thick and dashed lines, and text in stb_easy_font's segment font.
/// Shapes are hard-edged; pictures are drawn at a multiple of their size and shrunk for smooth edges.
/// Everything is clipped to the clip rectangle (the whole image unless set).
class Canvas {
 public:
  /// Draws on `image`, which must outlive the canvas.
  explicit Canvas(RgbImage& image);

  /// Restricts drawing to [x0, x1) × [y0, y1).
  void setClip(float x0, float y0, float x1, float y1);
  /// Drawing reaches the whole image again.
  void resetClip();

  /// Fills the pixels whose centres lie in [x0, x1) × [y0, y1).
  void fillRect(float x0, float y0, float x1, float y1, Rgb colour);
  /// A segment `thickness` pixels wide with round ends. `dash` > 0 draws dashes and gaps of that length along
  /// it, counted from (x0, y0).
  void line(float x0, float y0, float x1, float y1, float thickness, Rgb colour, float dash = 0);
  /// Segments through `points` in order (round joins).
  void polyline(const std::vector<std::pair<float, float>>& points, float thickness, Rgb colour);

  /// Writes `text` (ASCII; anything else shows as '?') with its box aligned at (x, y), `scale` pixels per
  /// font unit (a digit is 7 units high). `turned` gives it a quarter turn anticlockwise, reading bottom to
  /// top; the alignments then apply along the turned text.
  void text(float x, float y, const std::string& text, float scale, Rgb colour,
            Align horizontal = Align::Start, Align vertical = Align::Start, bool turned = false);
  /// Width of `text` in pixels at `scale`.
  static float textWidth(const std::string& text, float scale);
  /// Height of a line of text in pixels at `scale` (capitals and digits; descenders go below).
  static float textHeight(float scale);

 private:
  RgbImage& m_image;
  float m_clip[4];
};

}  // namespace gpucol::demo
