#pragma once

#include <string>

namespace gpucol {

/// The bytes of the mesh file at `path`. Only a regular file is opened: a directory, a FIFO, a device or a
/// socket is refused from its stat before any open (a FIFO without a writer would block, /dev/zero never
/// ends), and so is an empty file. The file is read into one buffer of its stat size, so reading costs its
/// size and no more. Throws MeshError naming `path`.
std::string readMeshFile(const std::string& path);

/// The checks readMeshFile makes before it opens the file, alone: the path names an existing, non-empty
/// regular file. Throws MeshError naming `path`.
void checkMeshFile(const std::string& path);

/// Throws MeshError "<path>: malformed <format> file: <what>".
[[noreturn]] void throwMalformed(const std::string& path, const char* format, const std::string& what);

}  // namespace gpucol
