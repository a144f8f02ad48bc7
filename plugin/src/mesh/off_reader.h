#pragma once

#include <string>

#include "mesh/raw_mesh.h"

namespace gpucol {

/// Reads a plain ASCII OFF file: the line "OFF", the line "<vertices> <faces> <edges>", a line "x y z" per
/// vertex, then a line "<n> <i1> ... <in>" per face (n >= 3); '#' starts a comment. Variants with colours,
/// normals, texture coordinates, other dimensions or binary data (COFF, NOFF, STOFF, 4OFF, nOFF, OFF BINARY)
/// and extra values on a line are refused. The counts are checked against the file's size before anything is
/// allocated; every number is read exactly, every index must name a vertex, and nothing may follow the last
/// face. Throws MeshError naming `path`, the line and the value.
RawMesh readOff(const std::string& bytes, const std::string& path);

}  // namespace gpucol
