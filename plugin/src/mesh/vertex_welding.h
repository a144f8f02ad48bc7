#pragma once

#include <cstdint>
#include <vector>

namespace gpucol {

/// Joins vertices at exactly equal positions (bit-equal floats, -0 the same as +0): `xyz` keeps the first
/// vertex of each position, in the order of first appearance, and the returned map gives each old vertex its
/// new index. Sorting an index array, so it costs 8 bytes per vertex besides `xyz`, whatever the positions.
std::vector<std::uint32_t> weldEqualPositions(std::vector<float>& xyz);

}  // namespace gpucol
