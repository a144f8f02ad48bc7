#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gpucol/triangle_mesh.h"

namespace gpucol {

/// A mesh as a reader found it in a file: vertices, and faces of three or more corners, each remembering
/// where in the file it was so that a face refused later is named by its line or record.
class RawMesh {
 public:
  /// `path` and `format` ("OBJ") name the file in messages; a face's place reads "<place> <number>", such as
  /// "line 12" or "facet 3".
  RawMesh(const std::string& path, const char* format, const char* place);

  /// x y z of every vertex; readers fill it directly.
  std::vector<float> xyz;

  /// Adds a face of `n` >= 3 corners (vertex indices already checked to be in range) found at `where`.
  void addFace(const std::uint32_t* corners, std::size_t n, std::uint64_t where);
  /// Reserves room for `corners` more corners of `faces` more faces.
  void reserveFaces(std::size_t faces, std::size_t corners);
  /// Number of faces added.
  std::size_t faceCount() const { return m_where.size(); }
  /// True when some face has more than three corners.
  bool hasPolygons() const { return m_corners.size() != 3 * m_where.size(); }

  /// The triangle mesh: vertices at exactly equal positions joined first when `weld` is set, then each face
  /// checked for repeated corners (a repeated index, or after welding two corners at one position) and
  /// polygons triangulated. Throws MeshError naming the face's place for a face that cannot be a surface.
  TriangleMesh build(bool weld) &&;

 private:
  [[noreturn]] void failFace(std::size_t face, const std::string& what) const;

  const std::string& m_path;
  const char* m_format;
  const char* m_place;
  std::vector<std::uint32_t> m_corners;    ///< Every face's corners, face after face.
  std::vector<std::uint64_t> m_faceStart;  ///< Where face f's corners start in m_corners.
  std::vector<std::uint64_t> m_where;      ///< Face f's line or record number.
};

}  // namespace gpucol
