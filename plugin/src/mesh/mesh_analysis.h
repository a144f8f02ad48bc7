#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gpucol/mass_properties.h"
#include "gpucol/mesh_report.h"

namespace gpucol {

/// Computes the topology and quality report of already validated arrays (thesis §5.3.1).
/// Edges are found by sorting packed 64-bit edge keys, so the cost is O(F log F), not O(F^2).
MeshReport analyzeMesh(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices);

/// Volume, centre of mass and inertia of a closed, consistently wound mesh of uniform density, in double.
/// Throws MeshError (naming `name`) when the report says the mesh cannot enclose a solid, or when a result
/// Bullet would take (volume, mass, the inertia's diagonal and principal moments) is not a normal float.
MassProperties computeMassProperties(const std::vector<float>& positions,
                                     const std::vector<std::uint32_t>& indices, const MeshReport& report,
                                     double density, const std::string& name);

/// computeMassProperties of the mesh with every vertex multiplied by `scale` per axis (in double; a mirroring
/// scale's inward winding counted outward), without the float range check: for a caller that rescales the
/// results and checks what it hands on.
MassProperties integrateMassProperties(const std::vector<float>& positions,
                                       const std::vector<std::uint32_t>& indices, const MeshReport& report,
                                       double density, const std::string& name,
                                       const std::array<double, 3>& scale);

}  // namespace gpucol
