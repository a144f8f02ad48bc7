#pragma once

#include <string>

#include "mesh/raw_mesh.h"

namespace gpucol {

/// Reads a PLY file (format ascii, binary_little_endian or binary_big_endian 1.0) from its bytes. The header
/// must declare one element 'vertex' with scalar properties x, y and z, and one element 'face' with one list
/// 'vertex_indices' (or 'vertex_index') of an integer type; other elements and properties are checked and
/// skipped, except 'tristrips' and 'range_grid', which hold geometry gpucol would drop and are refused. The
/// counts are checked against the file's size before anything is allocated; every value is read exactly for
/// its declared type (an ASCII record is one line); every index must be in range and every face have at least
/// three corners; nothing may follow the last record. Throws MeshError naming `path`, the line or record, and
/// the value.
RawMesh readPly(const std::string& bytes, const std::string& path);

}  // namespace gpucol
