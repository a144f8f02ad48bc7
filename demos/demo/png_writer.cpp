#include "demo/png_writer.h"

#include <stb_image_write.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace gpucol::demo {

void writePng(const RgbImage& image, const std::string& path) {
  if (image.width() == 0 || image.height() == 0)
    throw std::runtime_error("cannot write an empty image to " + path);
  errno = 0;
  // stb reports failure as 0 without a reason; errno from fopen is the best cause there is.
  if (stbi_write_png(path.c_str(), image.width(), image.height(), 3, image.bytes(), image.width() * 3) == 0) {
    const int error = errno;
    throw std::runtime_error("cannot write PNG file '" + path + "'" +
                             (error != 0 ? std::string(": ") + std::strerror(error) : std::string()));
  }
}

}  // namespace gpucol::demo
