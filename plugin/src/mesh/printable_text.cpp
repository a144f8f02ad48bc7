#include "mesh/printable_text.h"

namespace gpucol {

std::string printable(std::string_view text, std::size_t limit) {
  static const char kHex[] = "0123456789abcdef";
  std::string out = "'";
  const std::size_t shown = text.size() < limit ? text.size() : limit;
  for (std::size_t k = 0; k < shown; ++k) {
    const unsigned char c = static_cast<unsigned char>(text[k]);
    if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
      out += char(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  out += '\'';
  if (shown < text.size()) out += "...";
  return out;
}

}  // namespace gpucol
