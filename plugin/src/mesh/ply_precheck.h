#pragma once

#include <cstddef>
#include <string>

namespace gpucol {

/// Checks that a PLY file's header is well formed and that its body holds every element the header
/// declares, before assimp parses it. Debian's assimp 5.2.5 crashes (segfault), loops forever,
/// aborts on an internal assert, or pads with made-up faces on truncated PLY files, so a malformed
/// file must be refused here. Throws MeshError naming `path` and what is wrong. Returns the file to give
/// assimp: the same body after the header rewritten with only its format, element and property lines, so that
/// assimp's header reader sees the elements this check saw (comments between properties mislead it).
std::string checkPlyStructure(const char* data, std::size_t size, const std::string& path);

/// True when the bytes start with the PLY magic line ("ply" then a line break).
bool looksLikePly(const char* data, std::size_t size);

/// True when Debian's assimp 5.2.5 would give the file to its PLY reader and that reader would get past its
/// magic test, so the file must pass checkPlyStructure first. That is wider than looksLikePly: assimp picks
/// its PLY reader for every path ending in ".ply" (any case) whatever the bytes, and for other paths by
/// content; its magic test accepts any first line that begins with "ply" in any case, after skipping one
/// leading line end. Such a file that looksLikePly refuses ("ply" followed by other bytes, "\nply") otherwise
/// reaches assimp unchecked, where a header without "end_header" loops forever and a 3 MB file of zero bytes
/// named .ply reads past a buffer.
bool reachesAssimpPlyReader(const char* data, std::size_t size, const std::string& path);

}  // namespace gpucol
