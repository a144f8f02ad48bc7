#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gpucol/mass_properties.h"
#include "gpucol/mesh_report.h"

class btStridingMeshInterface;

namespace gpucol {

/// One part of a mesh made of several, as a btStridingMeshInterface's subparts: its triangles and its
/// vertices are contiguous ranges of the mesh's, and its triangles use only its own vertices.
struct MeshPart {
  std::uint32_t firstTriangle = 0;  ///< Index of the part's first triangle in the mesh.
  std::uint32_t triangleCount = 0;  ///< Number of triangles of the part.
  std::uint32_t firstVertex = 0;    ///< Index of the part's first vertex in the mesh.
  std::uint32_t vertexCount = 0;    ///< Number of vertices of the part.
};

/// A triangle as Bullet's contacts name it: its part and its index within that part.
struct PartTriangle {
  int part = 0;   ///< The part (a btStridingMeshInterface subpart; 0 for a mesh of one part).
  int index = 0;  ///< The triangle's index within its part.
};

/// A validated, immutable triangle mesh: float xyz vertices and uint32 triangles, in its own frame.
/// Construction validates the input (thesis §5.3.1) and throws MeshError on bad data; the report
/// describes what the mesh is (open, non-manifold, degenerate triangles...) without rejecting it.
class TriangleMesh {
 public:
  /// The largest coordinate magnitude a mesh may have, locally scaled or not: Bullet squares lengths in
  /// float, and 1e18 squared (1e36, with room for sums) stays finite there; larger coordinates are refused.
  static constexpr float kMaxCoordinate = 1e18f;

  /// Builds a mesh from xyz triples and index triples; `name` appears in error messages. Throws MeshError for
  /// a non-finite coordinate or one beyond kMaxCoordinate, an index out of range, a triangle repeating a
  /// vertex, or an empty mesh.
  static TriangleMesh fromArrays(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                                 std::string name = "arrays");

  /// Builds a mesh of several parts: `parts` must cover the triangles and the vertices in order, and each
  /// part's triangles index the mesh's vertex array within the part's own range. Errors name the part and the
  /// element's index within it.
  static TriangleMesh fromParts(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                                std::vector<MeshPart> parts, std::string name = "arrays");

  /// The triangles of a Bullet mesh interface (btTriangleMesh, btTriangleIndexVertexArray...): every subpart
  /// becomes a part, so that a contact can name a triangle as Bullet does (part, index within the part).
  /// Indices may be 8-, 16- or 32-bit, vertices float or double (converted to float); the vertices are the
  /// arrays' own, without the interface's scaling (a shape's local scaling, MeshShape::setLocalScaling,
  /// carries it). Throws MeshError naming the part and the triangle or vertex for an index out of the part's
  /// range, a repeated index, a non-finite coordinate (or one too large for float), and for an index or
  /// vertex type it cannot read.
  static TriangleMesh fromStridingMesh(const btStridingMeshInterface& meshInterface,
                                       std::string name = "btStridingMeshInterface");

  /// Number of vertices.
  std::size_t vertexCount() const { return m_positions.size() / 3; }
  /// Number of triangles.
  std::size_t triangleCount() const { return m_indices.size() / 3; }
  /// Vertex coordinates, x y z per vertex.
  const std::vector<float>& positions() const { return m_positions; }
  /// Vertex indices, three per triangle, counter-clockwise seen from outside.
  const std::vector<std::uint32_t>& indices() const { return m_indices; }
  /// Where the mesh came from: a file path or the name given to fromArrays.
  const std::string& name() const { return m_name; }
  /// Topology and quality report, computed once at construction.
  const MeshReport& report() const { return m_report; }
  /// The parts, in order (one covering the whole mesh unless it was made of several).
  const std::vector<MeshPart>& parts() const { return m_parts; }
  /// The part of `triangle` and its index within that part; (0, triangle) for a mesh of one part.
  PartTriangle partTriangle(std::uint32_t triangle) const;

  /// Volume, centre of mass and inertia for a uniform density, computed in double about the bounding box
  /// centre. Throws MeshError, saying why, for an open or non-manifold mesh, inconsistent winding, a
  /// negative signed volume (inward winding: it is reported, never flipped), no enclosed volume, a density
  /// that is not finite and positive, or a volume, mass or inertia outside float's normal range (Bullet
  /// computes in float: an overflow would reach a body as inf, an underflow as NaN after a step).
  MassProperties massProperties(double density = 1.0) const;

  /// The same mesh (triangles and parts) with every vertex mapped by p' = rotation * p + translation
  /// (rotation row-major, computed in double, stored as float). Throws MeshError unless rotation is a proper
  /// rotation (orthonormal to 1e-6, det +1) and the results are finite.
  TriangleMesh transformed(const std::array<double, 9>& rotation,
                           const std::array<double, 3>& translation) const;

  /// The mesh moved into its principal frame (centre of mass at the origin, principal axes along x, y, z),
  /// so that a btRigidBody gets a diagonal inertia; `massProperties()` of the result has a diagonal tensor.
  /// `fromPrincipalRotation` and `fromPrincipalTranslation`, when given, receive the transform from the
  /// principal frame back to the original one (p = R p' + t). Throws like massProperties().
  TriangleMesh inPrincipalFrame(double density, std::array<double, 9>* fromPrincipalRotation = nullptr,
                                std::array<double, 3>* fromPrincipalTranslation = nullptr) const;

 private:
  TriangleMesh() = default;

  std::vector<float> m_positions;
  std::vector<std::uint32_t> m_indices;
  std::string m_name;
  MeshReport m_report;
  std::vector<MeshPart> m_parts;
};

/// Loads a mesh file: PLY (.ply: ASCII, binary little- or big-endian), OBJ (.obj), STL (.stl: ASCII or
/// binary) or OFF (.off), chosen by the extension in any case; other files are refused. Each format is read
/// by gpucol's own strict reader: counts checked against the file's size before anything is allocated, every
/// number read exactly for its type, every index in range, structure the format does not allow refused (see
/// docs/using-gpucol.md, "Mesh files"). PLY and OFF files of triangles keep their vertices and triangles exactly; PLY and
/// OFF files with polygons, and every OBJ and STL file, have vertices at exactly equal positions joined
/// (first one kept). Polygons are split into triangles (fan when convex, ear clipping otherwise); points and
/// lines are refused. Throws MeshError naming the file, the line or record, and the value; special files
/// (directories, FIFOs, devices) are refused from their stat, without being opened.
TriangleMesh loadMesh(const std::string& path);

}  // namespace gpucol
