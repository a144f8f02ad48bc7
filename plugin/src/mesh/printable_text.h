#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace gpucol {

/// `text` in single quotes for an error message, safe to print: bytes outside printable ASCII (control bytes,
/// binary data, UTF-8) as \xNN, a quote or backslash escaped, and at most `limit` bytes of it shown (then
/// "..." after the closing quote), so a message never carries raw binary or a whole file.
std::string printable(std::string_view text, std::size_t limit = 40);

}  // namespace gpucol
