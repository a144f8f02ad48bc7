#pragma once

#include <cstdint>
#include <vector>

namespace gpucol {

class TriangleMesh;

/// No triangle across an edge (matchEdges).
inline constexpr std::uint32_t kNoEdge = 0xffffffffu;

/// For each edge of each triangle (3 t + k, edge k from vertex k to vertex k + 1 in index order), the same
/// edge of the one triangle across it, as 3 t' + k'; kNoEdge where no other triangle, or more than one,
/// shares the edge, or where the triangle across it runs the edge the same way (its winding disagrees).
/// Vertices are matched by position, so meshes whose faces carry vertices of their own are matched too.
std::vector<std::uint32_t> matchEdges(const TriangleMesh& mesh);

/// For each edge of each triangle, the far vertex of the one triangle across it (the edge's "wing"; `across`
/// from matchEdges): 9 floats per triangle t at [9 t, 9 t + 9), edge k at 9 t + 3 k; NaN where matchEdges
/// found no triangle across. With its wing an edge knows the angle of the surface around it: convex, flat or
/// concave.
std::vector<float> buildEdgeWings(const TriangleMesh& mesh, const std::vector<std::uint32_t>& across);

/// Per triangle, bit k set when edge k is a diagonal of a flat face: its wing (`wings`, buildEdgeWings) lies
/// in the triangle's plane within 1e-4 of the edge's length. Decided in the mesh's own coordinates, in
/// double: a scaling keeps a flat face flat.
std::vector<std::uint8_t> findFlatDiagonals(const TriangleMesh& mesh, const std::vector<float>& wings);

}  // namespace gpucol
