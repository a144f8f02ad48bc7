#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace gpucol {

/// Walks the text of a mesh file line by line, as an editor numbers them: a line ends at '\n' (a '\r' just
/// before it is dropped), words are split at spaces and tabs, and a line holding any other control byte (a
/// '\0', '\f', '\v', a lone '\r': binary data, or text two readers would split differently) is refused with
/// its line and column. Bytes from 0x80 up (UTF-8 in names and comments) are left alone.
class TextLines {
 public:
  /// Reads `text` from `offset`, whose line is number `firstLine`; `comment` starts a comment running to the
  /// end of its line ('\0': none). `path` and `format` name the file in messages.
  TextLines(std::string_view text, std::size_t offset, std::size_t firstLine, const std::string& path,
            const char* format, char comment);

  /// Moves to the next line that holds a word; false (and no words) at the end of the text.
  bool next();
  /// The words of the current line.
  const std::vector<std::string_view>& words() const { return m_words; }
  /// The current line's number (1 for the file's first line).
  std::size_t line() const { return m_line; }
  /// Bytes after the current line: an upper bound on what the rest of the file can hold.
  std::size_t bytesLeft() const { return m_text.size() - m_offset; }

  /// Throws MeshError "<path>: malformed <format> file: line <n>: <what>" for the current line.
  [[noreturn]] void fail(const std::string& what) const;

 private:
  std::string_view m_text;
  std::size_t m_offset;
  std::size_t m_line;
  const std::string& m_path;
  const char* m_format;
  char m_comment;
  std::vector<std::string_view> m_words;
};

}  // namespace gpucol
