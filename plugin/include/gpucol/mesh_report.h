#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gpucol {

/// A triangle is degenerate when twice its area over its squared longest edge (its height over its
/// longest edge) is at most this. Float coordinates carry a relative error of about 6e-8, so below a
/// height ratio of 1e-6 the triangle's normal is off by several degrees and the plane that contact
/// generation needs (thesis §5.3.1) is noise. Every real mesh in ../shared/data/meshes stays three
/// orders of magnitude above it (measured minimum 1.0e-3, in armadillo-27674; 3.9e-3 in armadillo-99976).
inline constexpr double kDegenerateTriangleRatio = 1e-6;

/// What a mesh is, topologically and numerically (thesis §5.3.1). Open and non-manifold meshes still
/// collide; the report says so.
struct MeshReport {
  std::size_t vertexCount = 0;        ///< Vertices in the mesh.
  std::size_t triangleCount = 0;      ///< Triangles in the mesh.
  std::size_t edgeCount = 0;          ///< Distinct undirected edges.
  std::size_t boundaryEdges = 0;      ///< Edges used by exactly one triangle.
  std::size_t nonManifoldEdges = 0;   ///< Edges used by more than two triangles.
  std::size_t inconsistentEdges = 0;  ///< Edges whose two triangles walk them the same way (flipped winding).
  bool edgeCountMatchesClosedManifold = false;     ///< The thesis's quick check E == 3F/2.
  std::vector<std::uint32_t> degenerateTriangles;  ///< Ids, ascending: flatness <= kDegenerateTriangleRatio.
  std::vector<std::uint32_t> duplicateTriangles;  ///< Ids, ascending: same vertex set as an earlier triangle.
  std::size_t unreferencedVertices = 0;           ///< Vertices no triangle uses.
  bool closed = false;                            ///< Every edge used by exactly two triangles.

  /// One line a person can read, e.g. "1152 triangles, 576 vertices, 1728 edges, closed 2-manifold, 0
  /// degenerate, ...".
  std::string summary() const;
};

}  // namespace gpucol
