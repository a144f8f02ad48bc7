#include "mesh/flat_faces.h"

#include <algorithm>
#include <limits>
#include <numeric>

#include "gpucol/triangle_mesh.h"
#include "mesh/edge_wings.h"

namespace gpucol {

std::vector<float> flatFaceHalfExtents(const TriangleMesh& mesh, const std::vector<std::uint32_t>& across,
                                       const std::vector<std::uint8_t>& flatDiagonals) {
  const std::vector<float>& positions = mesh.positions();
  const std::vector<std::uint32_t>& indices = mesh.indices();
  const std::size_t triangles = indices.size() / 3;
  // Union-find over the flat diagonals, each face named by its root triangle.
  std::vector<std::uint32_t> parent(triangles);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&](std::uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  for (std::size_t t = 0; t < triangles; ++t) {
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t other = across[3 * t + k];
      if (other == kNoEdge || !(flatDiagonals[t] & (1u << k))) continue;
      const std::uint32_t a = root(std::uint32_t(t)), b = root(other / 3);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<float> lo(3 * triangles, kInf), hi(3 * triangles, -kInf);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t face = root(std::uint32_t(t));
    for (int i = 0; i < 3; ++i) {
      const float* p = positions.data() + 3 * std::size_t(indices[3 * t + i]);
      for (int c = 0; c < 3; ++c) {
        lo[3 * face + c] = std::min(lo[3 * face + c], p[c]);
        hi[3 * face + c] = std::max(hi[3 * face + c], p[c]);
      }
    }
  }
  std::vector<float> halfExtents(3 * triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::uint32_t face = root(std::uint32_t(t));
    for (int c = 0; c < 3; ++c) halfExtents[3 * t + c] = 0.5f * (hi[3 * face + c] - lo[3 * face + c]);
  }
  return halfExtents;
}

}  // namespace gpucol
