#include "gpucol/triangle_mesh.h"

#include <Eigen/Dense>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "gpucol/mesh_error.h"
#include "mesh/mesh_analysis.h"

namespace gpucol {

namespace {

const char* const kAxisNames[3] = {"x", "y", "z"};

/// How an error names element `i` of `part`: by its index alone in a mesh of one part, else by its part and
/// its index within the part (as Bullet's mesh interfaces number them).
std::string elementName(const char* element, std::size_t i, const std::vector<MeshPart>& parts,
                        std::size_t part, std::uint32_t first) {
  std::ostringstream out;
  if (parts.size() > 1) out << "part " << part << " ";
  out << element << " " << (parts.size() > 1 ? i - first : i);
  return out.str();
}

/// Rejects what no later stage could make sense of (thesis §5.3.1); the message names the source,
/// the element and the value so a user can find it in the file.
void validate(const std::vector<float>& xyz, const std::vector<std::uint32_t>& indices,
              const std::vector<MeshPart>& parts, const std::string& name) {
  if (xyz.size() % 3 != 0) {
    std::ostringstream out;
    out << name << ": the coordinate array has " << xyz.size()
        << " floats, not a multiple of 3 (x y z per vertex)";
    throw MeshError(out.str());
  }
  if (indices.size() % 3 != 0) {
    std::ostringstream out;
    out << name << ": the index array has " << indices.size()
        << " entries, not a multiple of 3 (three per triangle)";
    throw MeshError(out.str());
  }
  const std::size_t vertices = xyz.size() / 3, triangles = indices.size() / 3;
  if (vertices == 0 || triangles == 0) {
    std::ostringstream out;
    out << name << ": empty mesh (" << vertices << " vertices, " << triangles << " triangles)";
    throw MeshError(out.str());
  }
  std::size_t nextTriangle = 0, nextVertex = 0;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    if (parts[p].firstTriangle != nextTriangle || parts[p].firstVertex != nextVertex) {
      std::ostringstream out;
      out << name << ": part " << p << " starts at triangle " << parts[p].firstTriangle << " and vertex "
          << parts[p].firstVertex << "; the parts must follow each other from 0 (expected " << nextTriangle
          << " and " << nextVertex << ")";
      throw MeshError(out.str());
    }
    nextTriangle += parts[p].triangleCount;
    nextVertex += parts[p].vertexCount;
  }
  if (nextTriangle != triangles || nextVertex != vertices) {
    std::ostringstream out;
    out << name << ": the parts cover " << nextTriangle << " triangles and " << nextVertex << " vertices of "
        << triangles << " and " << vertices;
    throw MeshError(out.str());
  }
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const MeshPart& part = parts[p];
    for (std::size_t v = part.firstVertex; v < std::size_t(part.firstVertex) + part.vertexCount; ++v) {
      for (int axis = 0; axis < 3; ++axis) {
        if (!std::isfinite(xyz[3 * v + axis])) {
          std::ostringstream out;
          out << name << ": " << elementName("vertex", v, parts, p, part.firstVertex)
              << " has a non-finite coordinate " << kAxisNames[axis] << " = " << xyz[3 * v + axis];
          throw MeshError(out.str());
        }
        if (std::abs(xyz[3 * v + axis]) > TriangleMesh::kMaxCoordinate) {
          std::ostringstream out;
          out << name << ": " << elementName("vertex", v, parts, p, part.firstVertex) << " has the coordinate "
              << kAxisNames[axis] << " = " << xyz[3 * v + axis] << ", beyond gpucol's limit of +-"
              << TriangleMesh::kMaxCoordinate << " (Bullet squares lengths in float)";
          throw MeshError(out.str());
        }
      }
    }
    const std::size_t lastTriangle = std::size_t(part.firstTriangle) + part.triangleCount;
    for (std::size_t t = part.firstTriangle; t < lastTriangle; ++t) {
      const std::uint32_t* tri = &indices[3 * t];
      for (int k = 0; k < 3; ++k) {
        if (tri[k] < part.firstVertex || tri[k] - part.firstVertex >= part.vertexCount) {
          std::ostringstream out;
          out << name << ": " << elementName("triangle", t, parts, p, part.firstTriangle) << " corner " << k
              << " has vertex index " << tri[k] << ", out of range for ";
          if (parts.size() > 1) {
            out << "the part's vertices " << part.firstVertex << " to "
                << std::int64_t(part.firstVertex) + part.vertexCount - 1;
          } else {
            out << vertices << " vertices";
          }
          throw MeshError(out.str());
        }
      }
      for (int k = 0; k < 3; ++k) {
        const int next = (k + 1) % 3;
        if (tri[k] == tri[next]) {
          std::ostringstream out;
          out << name << ": " << elementName("triangle", t, parts, p, part.firstTriangle)
              << " repeats vertex index " << tri[k] << " (corners " << std::min(k, next) << " and "
              << std::max(k, next) << ")";
          throw MeshError(out.str());
        }
      }
    }
  }
}

}  // namespace

TriangleMesh TriangleMesh::fromArrays(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                                      std::string name) {
  MeshPart whole;
  whole.triangleCount = std::uint32_t(indices.size() / 3);
  whole.vertexCount = std::uint32_t(xyz.size() / 3);
  return fromParts(std::move(xyz), std::move(indices), {whole}, std::move(name));
}

TriangleMesh TriangleMesh::fromParts(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                                     std::vector<MeshPart> parts, std::string name) {
  if (parts.empty() || xyz.size() / 3 > UINT32_MAX || indices.size() / 3 > UINT32_MAX) {
    std::ostringstream out;
    out << name << ": " << (parts.empty() ? "no parts given" : "more than 2^32 - 1 vertices or triangles");
    throw MeshError(out.str());
  }
  validate(xyz, indices, parts, name);
  TriangleMesh mesh;
  mesh.m_positions = std::move(xyz);
  mesh.m_indices = std::move(indices);
  mesh.m_name = std::move(name);
  mesh.m_parts = std::move(parts);
  mesh.m_report = analyzeMesh(mesh.m_positions, mesh.m_indices);
  return mesh;
}

PartTriangle TriangleMesh::partTriangle(std::uint32_t triangle) const {
  if (m_parts.size() == 1) return {0, int(triangle)};
  // The last part whose first triangle is not after `triangle`.
  const auto after = std::upper_bound(m_parts.begin(), m_parts.end(), triangle,
                                      [](std::uint32_t t, const MeshPart& p) { return t < p.firstTriangle; });
  const std::size_t part = std::size_t(after - m_parts.begin()) - 1;
  return {int(part), int(triangle - m_parts[part].firstTriangle)};
}

MassProperties TriangleMesh::massProperties(double density) const {
  return computeMassProperties(m_positions, m_indices, m_report, density, m_name);
}

TriangleMesh TriangleMesh::transformed(const std::array<double, 9>& rotation,
                                       const std::array<double, 3>& translation) const {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r(rotation.data());
  const Eigen::Vector3d t(translation.data());
  // Only a proper rotation keeps the winding outward and the mass properties meaningful; 1e-6 lets
  // through rotations that went through float, and nothing that scales or mirrors visibly.
  const double orthogonality = (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!r.allFinite() || !t.allFinite() || orthogonality > 1e-6 || r.determinant() < 0) {
    std::ostringstream out;
    out << m_name << ": transformed() needs a proper rotation and a finite translation; got a matrix with "
        << "|R R^T - I| = " << orthogonality << " and det " << r.determinant();
    throw MeshError(out.str());
  }
  std::vector<float> xyz(m_positions.size());
  for (std::size_t v = 0; v < vertexCount(); ++v) {
    const Eigen::Vector3d p(m_positions[3 * v], m_positions[3 * v + 1], m_positions[3 * v + 2]);
    const Eigen::Vector3d q = r * p + t;
    for (int k = 0; k < 3; ++k) xyz[3 * v + k] = float(q[k]);
  }
  return fromParts(std::move(xyz), m_indices, m_parts, m_name);
}

TriangleMesh TriangleMesh::inPrincipalFrame(double density, std::array<double, 9>* fromPrincipalRotation,
                                            std::array<double, 3>* fromPrincipalTranslation) const {
  const MassProperties mp = massProperties(density);
  // The principal axes are the columns of R, so p_principal = R^T (p - com), and back p = R p' + com.
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> axes(mp.principalAxes.data());
  const Eigen::Vector3d com(mp.centerOfMass.data());
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> toPrincipal = axes.transpose();
  const Eigen::Vector3d shift = -(toPrincipal * com);
  std::array<double, 9> rotation{};
  std::array<double, 3> translation{};
  for (int i = 0; i < 3; ++i) {
    translation[i] = shift[i];
    for (int j = 0; j < 3; ++j) rotation[3 * i + j] = toPrincipal(i, j);
  }
  if (fromPrincipalRotation != nullptr) *fromPrincipalRotation = mp.principalAxes;
  if (fromPrincipalTranslation != nullptr) *fromPrincipalTranslation = mp.centerOfMass;
  return transformed(rotation, translation);
}

}  // namespace gpucol
