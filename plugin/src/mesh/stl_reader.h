#pragma once

#include <string>

#include "mesh/raw_mesh.h"

namespace gpucol {

/// Reads an STL file. Binary when its size is exactly 84 + 50 N bytes for the facet count N at byte 80 (a
/// binary header may begin with "solid" too); otherwise it must be ASCII STL: 'solid [name]', then per facet
/// 'facet normal i j k', 'outer loop', exactly three 'vertex x y z', 'endloop', 'endfacet', and 'endsolid
/// [name]' (several solids may follow each other), one statement per line, keywords in any case. A fourth
/// vertex, a missing one, a non-finite number and anything after the last 'endsolid' are refused; normals
/// are checked and ignored, as is a binary facet's attribute word. Throws MeshError naming `path`, the facet
/// and its line (ASCII) and the value.
RawMesh readStl(const std::string& bytes, const std::string& path);

}  // namespace gpucol
