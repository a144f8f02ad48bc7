#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gpucol/mass_properties.h"
#include "gpucol/mesh_report.h"

namespace gpucol {

/// Computes the topology and quality report of already validated arrays (thesis §5.3.1).
/// Edges are found by sorting packed 64-bit edge keys, so the cost is O(F log F), not O(F^2).
MeshReport analyzeMesh(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices);

/// Volume, centre of mass and inertia of a closed, consistently wound mesh of uniform density.
/// Throws MeshError (naming `name`) when the report says the mesh cannot enclose a solid.
MassProperties computeMassProperties(const std::vector<float>& positions,
                                     const std::vector<std::uint32_t>& indices, const MeshReport& report,
                                     double density, const std::string& name);

}  // namespace gpucol
