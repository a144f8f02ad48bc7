#pragma once

#include <cstdint>
#include <vector>

namespace gpucol {

class TriangleMesh;

/// Per triangle, the half extents of the box around its flat face (3 floats per triangle, in the mesh's own
/// coordinates): the triangles joined to it across flat diagonals (`across` from matchEdges, `flatDiagonals`
/// from findFlatDiagonals), a box's whole side for a triangle of that side, the triangle alone on a curved
/// surface. A contact between two flat faces has a support as wide as the smaller face, where one on a curved
/// surface has a support of its own small patch (ContactManifoldSet).
std::vector<float> flatFaceHalfExtents(const TriangleMesh& mesh, const std::vector<std::uint32_t>& across,
                                       const std::vector<std::uint8_t>& flatDiagonals);

}  // namespace gpucol
