#pragma once

#include <cstddef>
#include <string>

namespace gpucol {

/// Checks that a PLY file's header is well formed and that its body holds every element the header
/// declares, before assimp parses it. Debian's assimp 5.2.5 crashes (segfault), loops forever,
/// aborts on an internal assert, or pads with made-up faces on truncated PLY files, so a malformed
/// file must be refused here. Throws MeshError naming `path` and what is wrong.
void checkPlyStructure(const char* data, std::size_t size, const std::string& path);

/// True when the bytes start with the PLY magic line ("ply" then a line break).
bool looksLikePly(const char* data, std::size_t size);

}  // namespace gpucol
