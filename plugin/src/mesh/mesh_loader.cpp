#include <string>

#include "gpucol/mesh_error.h"
#include "gpucol/triangle_mesh.h"
#include "mesh/mesh_file.h"
#include "mesh/obj_reader.h"
#include "mesh/off_reader.h"
#include "mesh/ply_reader.h"
#include "mesh/printable_text.h"
#include "mesh/stl_reader.h"

namespace gpucol {

namespace {

constexpr const char* kAccepted = "gpucol reads PLY (.ply), OBJ (.obj), STL (.stl) and OFF (.off) mesh files";

/// The path's extension in lower case, with its dot; empty when the file name has none.
std::string extensionOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return std::string();
  std::string extension = path.substr(dot);
  for (char& c : extension) c = c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c;
  return extension;
}

}  // namespace

TriangleMesh loadMesh(const std::string& path) {
  // Refused before the file is read: a format gpucol does not check itself is not passed to any other reader.
  const std::string extension = extensionOf(path);
  if (extension != ".ply" && extension != ".obj" && extension != ".stl" && extension != ".off") {
    checkMeshFile(path);  // a missing, special or empty file says so first
    throw MeshError(path + ": " +
                    (extension.empty() ? std::string("the file name has no extension")
                                       : "unsupported mesh file type " + printable(extension)) +
                    "; " + kAccepted);
  }
  std::string bytes = readMeshFile(path);
  RawMesh raw = extension == ".ply"   ? readPly(bytes, path)
                : extension == ".off" ? readOff(bytes, path)
                : extension == ".obj" ? readObj(bytes, path)
                                      : readStl(bytes, path);
  std::string().swap(bytes);  // the file's bytes are not needed while the mesh is built
  // Files that list faces over shared vertices keep their vertices exactly unless they hold polygons, which
  // modelling tools write with a vertex per corner and position; OBJ and STL are always joined by position.
  const bool weld = extension == ".obj" || extension == ".stl" || raw.hasPolygons();
  return std::move(raw).build(weld);
}

}  // namespace gpucol
