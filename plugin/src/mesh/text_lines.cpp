#include "mesh/text_lines.h"

#include <cstring>

#include "mesh/mesh_file.h"

namespace gpucol {

TextLines::TextLines(std::string_view text, std::size_t offset, std::size_t firstLine,
                     const std::string& path, const char* format, char comment)
    : m_text(text),
      m_offset(offset),
      m_line(firstLine - 1),
      m_path(path),
      m_format(format),
      m_comment(comment) {}

bool TextLines::next() {
  m_words.clear();
  while (m_offset < m_text.size()) {
    const std::size_t start = m_offset;
    const void* found = std::memchr(m_text.data() + start, '\n', m_text.size() - start);
    const std::size_t end =
        found ? std::size_t(static_cast<const char*>(found) - m_text.data()) : m_text.size();
    m_offset = found ? end + 1 : end;
    ++m_line;
    std::size_t stop = end > start && m_text[end - 1] == '\r' ? end - 1 : end;
    for (std::size_t k = start; k < stop; ++k) {
      const unsigned char c = static_cast<unsigned char>(m_text[k]);
      if ((c < 0x20 && c != '\t') || c == 0x7f) {
        static const char kHex[] = "0123456789abcdef";
        fail(std::string("control byte 0x") + kHex[c >> 4] + kHex[c & 15] + " at column " +
             std::to_string(k - start + 1) + "; text may hold only printable characters, spaces and tabs");
      }
    }
    if (m_comment != '\0') {
      const void* mark = std::memchr(m_text.data() + start, m_comment, stop - start);
      if (mark) stop = std::size_t(static_cast<const char*>(mark) - m_text.data());
    }
    std::size_t k = start;
    while (k < stop) {
      while (k < stop && (m_text[k] == ' ' || m_text[k] == '\t')) ++k;
      const std::size_t wordStart = k;
      while (k < stop && m_text[k] != ' ' && m_text[k] != '\t') ++k;
      if (k > wordStart) m_words.push_back(m_text.substr(wordStart, k - wordStart));
    }
    if (!m_words.empty()) return true;
  }
  return false;
}

void TextLines::fail(const std::string& what) const {
  throwMalformed(m_path, m_format, "line " + std::to_string(m_line) + ": " + what);
}

}  // namespace gpucol
