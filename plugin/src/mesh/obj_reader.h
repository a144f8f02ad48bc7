#pragma once

#include <string>

#include "mesh/raw_mesh.h"

namespace gpucol {

/// Reads a Wavefront OBJ file's polygonal geometry: 'v x y z' (also 'v x y z 1' and 'v x y z r g b'), and 'f'
/// faces of at least three corners 'v', 'v/vt', 'v//vn' or 'v/vt/vn'. An index counts from 1, or back from
/// the last vertex defined when negative (-1 is the latest), and must name a vertex (or texture coordinate,
/// or normal) defined before its line. 'vt', 'vn' and 'vp' are checked and skipped; so are names, groups,
/// smoothing and material statements (no .mtl file is opened). Points, lines, free-form curves and surfaces,
/// line continuations and unknown statements are refused; '#' starts a comment. Throws MeshError naming
/// `path`, the line and the value.
RawMesh readObj(const std::string& bytes, const std::string& path);

}  // namespace gpucol
