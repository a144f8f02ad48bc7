#pragma once

#include <array>

namespace gpucol {

/// Mass properties of a closed mesh of uniform density, in the mesh's own frame.
struct MassProperties {
  double volume = 0;                         ///< Enclosed volume (positive for outward winding).
  double mass = 0;                           ///< volume * density.
  std::array<double, 3> centerOfMass{};      ///< Centre of mass.
  std::array<double, 9> inertia{};           ///< Inertia tensor about the centre of mass, row-major.
  std::array<double, 3> principalMoments{};  ///< Eigenvalues of the tensor, ascending.
  std::array<double, 9> principalAxes{};     ///< Row-major rotation whose columns are the principal axes.
};

}  // namespace gpucol
