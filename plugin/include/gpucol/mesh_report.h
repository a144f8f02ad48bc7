#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gpucol {

/// What a mesh is, topologically and numerically (thesis §5.3.1). Open and non-manifold meshes still
/// collide; the report says so.
struct MeshReport {
  std::size_t vertexCount = 0;            ///< Vertices in the mesh.
  std::size_t triangleCount = 0;          ///< Triangles in the mesh.
  std::size_t edgeCount = 0;              ///< Distinct undirected edges.
  std::size_t boundaryEdges = 0;          ///< Edges used by exactly one triangle.
  std::size_t nonManifoldEdges = 0;       ///< Edges used by more than two triangles.
  bool edgeCountMatchesClosedManifold = false;  ///< The thesis's quick check E == 3F/2.
  std::vector<std::uint32_t> degenerateTriangles;  ///< Near-zero area (collinear or coincident vertices).
  std::vector<std::uint32_t> duplicateTriangles;   ///< Same vertex set as an earlier triangle.
  std::size_t unreferencedVertices = 0;   ///< Vertices no triangle uses.
  bool closed = false;                    ///< Every edge used by exactly two triangles.

  /// One line a person can read, e.g. "1152 triangles, closed 2-manifold, 0 degenerate".
  std::string summary() const;
};

}  // namespace gpucol
