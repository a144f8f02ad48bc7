#include "mesh/edge_wings.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "gpucol/triangle_mesh.h"
#include "mesh/vertex_welding.h"

namespace gpucol {

std::vector<std::uint32_t> matchEdges(const TriangleMesh& mesh) {
  const std::vector<std::uint32_t>& indices = mesh.indices();
  const std::size_t triangles = indices.size() / 3;
  std::vector<std::uint32_t> across(3 * triangles, kNoEdge);
  std::vector<float> welded = mesh.positions();
  const std::vector<std::uint32_t> vertexOf = weldEqualPositions(welded);

  // Each edge once per triangle, keyed by its two welded ends (lower first), sorted so that the triangles
  // sharing an edge come together.
  struct Entry {
    std::uint64_t key;
    std::uint32_t edge;  // 3 t + k
    bool forward;        // runs from the lower welded index to the higher
  };
  std::vector<Entry> entries;
  entries.reserve(3 * triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = vertexOf[indices[3 * t + k]], b = vertexOf[indices[3 * t + (k + 1) % 3]];
      if (a == b) continue;
      entries.push_back(
          {(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), std::uint32_t(3 * t + k), a < b});
    }
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& l, const Entry& r) { return l.key != r.key ? l.key < r.key : l.edge < r.edge; });
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i;
    while (j < entries.size() && entries[j].key == entries[i].key) ++j;
    if (j - i == 2 && entries[i].forward != entries[i + 1].forward) {
      across[entries[i].edge] = entries[i + 1].edge;
      across[entries[i + 1].edge] = entries[i].edge;
    }
    i = j;
  }
  return across;
}

std::vector<float> buildEdgeWings(const TriangleMesh& mesh, const std::vector<std::uint32_t>& across) {
  const std::vector<float>& positions = mesh.positions();
  const std::vector<std::uint32_t>& indices = mesh.indices();
  std::vector<float> wings(3 * across.size(), std::numeric_limits<float>::quiet_NaN());
  for (std::size_t edge = 0; edge < across.size(); ++edge) {
    if (across[edge] == kNoEdge) continue;
    // The far vertex of the triangle across: the one its shared edge does not start or end at.
    const std::uint32_t other = across[edge], otherTriangle = other / 3;
    const std::uint32_t far = indices[3 * std::size_t(otherTriangle) + (other % 3 + 2) % 3];
    for (int c = 0; c < 3; ++c) wings[3 * edge + c] = positions[3 * std::size_t(far) + c];
  }
  return wings;
}

std::vector<std::uint8_t> findFlatDiagonals(const TriangleMesh& mesh, const std::vector<float>& wings) {
  const std::vector<float>& positions = mesh.positions();
  const std::vector<std::uint32_t>& indices = mesh.indices();
  const std::size_t triangles = indices.size() / 3;
  std::vector<std::uint8_t> flat(triangles, 0);
  for (std::size_t t = 0; t < triangles; ++t) {
    Eigen::Vector3d v[3];
    for (int k = 0; k < 3; ++k) {
      const float* p = positions.data() + 3 * std::size_t(indices[3 * t + k]);
      v[k] = Eigen::Vector3d(p[0], p[1], p[2]);
    }
    const Eigen::Vector3d normal = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
    for (int k = 0; k < 3; ++k) {
      const float* w = wings.data() + 9 * t + 3 * k;
      const Eigen::Vector3d wing(w[0], w[1], w[2]);
      if (wing.allFinite() && normal.allFinite() &&
          std::abs(normal.dot(wing - v[k])) <= 1e-4 * (v[(k + 1) % 3] - v[k]).norm()) {
        flat[t] |= std::uint8_t(1u << k);
      }
    }
  }
  return flat;
}

}  // namespace gpucol
