#include "gpucol/triangle_mesh.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "gpucol/mesh_error.h"
#include "mesh/mesh_analysis.h"

namespace gpucol {

namespace {

const char* const kAxisNames[3] = {"x", "y", "z"};

/// Rejects what no later stage could make sense of (thesis §5.3.1); the message names the source,
/// the element and the value so a user can find it in the file.
void validate(const std::vector<float>& xyz, const std::vector<std::uint32_t>& indices,
              const std::string& name) {
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
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    if (!std::isfinite(xyz[i])) {
      std::ostringstream out;
      out << name << ": vertex " << i / 3 << " has a non-finite coordinate " << kAxisNames[i % 3] << " = "
          << xyz[i];
      throw MeshError(out.str());
    }
    if (std::abs(xyz[i]) > TriangleMesh::kMaxCoordinate) {
      std::ostringstream out;
      out << name << ": vertex " << i / 3 << " has the coordinate " << kAxisNames[i % 3] << " = " << xyz[i]
          << ", beyond gpucol's limit of +-" << TriangleMesh::kMaxCoordinate
          << " (Bullet squares lengths in float)";
      throw MeshError(out.str());
    }
  }
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t* tri = &indices[3 * t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] >= vertices) {
        std::ostringstream out;
        out << name << ": triangle " << t << " corner " << k << " has vertex index " << tri[k]
            << ", out of range for " << vertices << " vertices";
        throw MeshError(out.str());
      }
    }
    for (int k = 0; k < 3; ++k) {
      const int next = (k + 1) % 3;
      if (tri[k] == tri[next]) {
        std::ostringstream out;
        out << name << ": triangle " << t << " repeats vertex index " << tri[k] << " (corners "
            << std::min(k, next) << " and " << std::max(k, next) << ")";
        throw MeshError(out.str());
      }
    }
  }
}

}  // namespace

TriangleMesh TriangleMesh::fromArrays(std::vector<float> xyz, std::vector<std::uint32_t> indices,
                                      std::string name) {
  validate(xyz, indices, name);
  TriangleMesh mesh;
  mesh.m_positions = std::move(xyz);
  mesh.m_indices = std::move(indices);
  mesh.m_name = std::move(name);
  mesh.m_report = analyzeMesh(mesh.m_positions, mesh.m_indices);
  return mesh;
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
  return fromArrays(std::move(xyz), m_indices, m_name);
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
