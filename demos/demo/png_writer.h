#pragma once

#include <string>

#include "demo/rgb_image.h"

namespace gpucol::demo {

/// Writes `image` as an 8-bit RGB PNG file at `path` (through stb_image_write, Debian's libstb). Throws
/// std::runtime_error naming the path when the file cannot be written (missing folder, no permission).
void writePng(const RgbImage& image, const std::string& path);

}  // namespace gpucol::demo
