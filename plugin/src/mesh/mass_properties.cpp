#include <Eigen/Dense>
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <sstream>

#include "gpucol/mesh_error.h"
#include "mesh/mesh_analysis.h"

namespace gpucol {

namespace {

/// Below this fraction of the bounding box's diagonal cubed a closed mesh encloses nothing a rigid
/// body can use (a doubly covered sheet, say); the double sums below are accurate to ~1e-15 of it.
constexpr double kMinRelativeVolume = 1e-12;

[[noreturn]] void refuse(const std::string& name, const std::string& why) {
  throw MeshError(name + ": cannot compute mass properties: " + why);
}

}  // namespace

MassProperties integrateMassProperties(const std::vector<float>& positions,
                                       const std::vector<std::uint32_t>& indices, const MeshReport& report,
                                       double density, const std::string& name,
                                       const std::array<double, 3>& scale) {
  // Thesis §5.3.1: volume, centre of mass and inertia are only meaningful for a closed manifold.
  if (!(std::isfinite(density) && density > 0)) {
    std::ostringstream out;
    out << "density must be finite and positive, got " << density;
    refuse(name, out.str());
  }
  if (report.boundaryEdges > 0 || report.nonManifoldEdges > 0) {
    std::ostringstream out;
    out << "the mesh is not a closed manifold (" << report.boundaryEdges << " boundary edges, "
        << report.nonManifoldEdges
        << " edges shared by more than two triangles), so it encloses no well-defined volume";
    refuse(name, out.str());
  }
  if (report.inconsistentEdges > 0) {
    std::ostringstream out;
    out << report.inconsistentEdges << " edges are walked in the same direction by both of their triangles "
        << "(inconsistent winding), so the signed volume would be wrong";
    refuse(name, out.str());
  }

  // Work relative to the bounding box centre so a mesh far from the origin keeps its precision:
  // the tetrahedra below are then small, and so are their products.
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], scale[i % 3] * positions[i]);
    hi[i % 3] = std::max(hi[i % 3], scale[i % 3] * positions[i]);
  }
  const Eigen::Vector3d reference(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
  const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                    (hi[2] - lo[2]) * (hi[2] - lo[2]));

  // Each triangle spans a signed tetrahedron with the reference point. Over a tetrahedron with one
  // corner at the origin and the others at a, b, c (det = a.(b x c)):
  //   volume = det / 6, first moment = det / 24 (a + b + c),
  //   second moment (integral of x x^T) = det / 120 (a a^T + b b^T + c c^T + s s^T), s = a + b + c,
  // the map of the unit tetrahedron's moments (1 + delta_ij) / 120 by the matrix [a b c].
  double sixVolume = 0;
  Eigen::Vector3d firstMoment24 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d secondMoment120 = Eigen::Matrix3d::Zero();
  const auto corner = [&](std::uint32_t v) -> Eigen::Vector3d {
    return Eigen::Vector3d(scale[0] * positions[3 * std::size_t(v)],
                           scale[1] * positions[3 * std::size_t(v) + 1],
                           scale[2] * positions[3 * std::size_t(v) + 2]) -
           reference;
  };
  // A mirror turns outward winding inward: its tetrahedra count with the opposite sign.
  const double orientation = scale[0] * scale[1] * scale[2] < 0 ? -1.0 : 1.0;
  for (std::size_t t = 0; t < indices.size() / 3; ++t) {
    const Eigen::Vector3d a = corner(indices[3 * t]), b = corner(indices[3 * t + 1]),
                          c = corner(indices[3 * t + 2]);
    const double det = orientation * a.dot(b.cross(c));
    const Eigen::Vector3d s = a + b + c;
    sixVolume += det;
    firstMoment24 += det * s;
    secondMoment120 += det * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  const double volume = sixVolume / 6;
  if (volume < 0) {
    std::ostringstream out;
    out << "the signed volume is negative (" << volume
        << "): the triangles are wound clockwise seen from outside (inward normals); reverse the winding";
    refuse(name, out.str());
  }
  if (volume <= kMinRelativeVolume * diagonal * diagonal * diagonal) {
    std::ostringstream out;
    out << "the mesh encloses no volume (" << volume << " for a bounding box diagonal of " << diagonal << ")";
    refuse(name, out.str());
  }

  const Eigen::Vector3d com = firstMoment24 / 24 / volume;  // relative to the reference point
  // Parallel axis theorem on the second moment, then I = trace(C) Id - C.
  const Eigen::Matrix3d centralMoment = secondMoment120 / 120 - volume * com * com.transpose();
  Eigen::Matrix3d inertia = density * (centralMoment.trace() * Eigen::Matrix3d::Identity() - centralMoment);
  inertia = 0.5 * (inertia + inertia.transpose());

  MassProperties result;
  result.volume = volume;
  result.mass = density * volume;
  for (int i = 0; i < 3; ++i) {
    result.centerOfMass[i] = reference[i] + com[i];
    for (int j = 0; j < 3; ++j) result.inertia[3 * i + j] = inertia(i, j);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
  if (solver.info() != Eigen::Success) refuse(name, "the eigen decomposition of the inertia tensor failed");
  Eigen::Matrix3d axes = solver.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);  // a proper rotation, det +1
  for (int i = 0; i < 3; ++i) {
    result.principalMoments[i] = solver.eigenvalues()[i];
    for (int j = 0; j < 3; ++j) result.principalAxes[3 * i + j] = axes(i, j);
  }
  return result;
}

MassProperties computeMassProperties(const std::vector<float>& positions,
                                     const std::vector<std::uint32_t>& indices, const MeshReport& report,
                                     double density, const std::string& name) {
  const MassProperties result = integrateMassProperties(positions, indices, report, density, name, {1, 1, 1});
  // Bullet works in float: a volume or inertia that overflows float, or underflows into its denormals or
  // zero, would reach a rigid body as inf or as a NaN after one step.
  const auto requireNormalFloat = [&](double value, const std::string& what) {
    if (std::abs(value) >= double(FLT_MIN) && std::abs(value) <= double(FLT_MAX)) return;
    std::ostringstream out;
    out << what << " is " << value << ", outside float's normal range (" << FLT_MIN << " to " << FLT_MAX
        << "), which Bullet computes in; scale the mesh or change the density";
    refuse(name, out.str());
  };
  requireNormalFloat(result.volume, "the volume");
  requireNormalFloat(result.mass, "the mass");
  for (int axis = 0; axis < 3; ++axis) {
    requireNormalFloat(result.inertia[std::size_t(4 * axis)],
                       std::string("the inertia about ") + "xyz"[axis]);
    requireNormalFloat(result.principalMoments[std::size_t(axis)],
                       "principal moment " + std::to_string(axis));
  }
  return result;
}

}  // namespace gpucol
