#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "gpucol/triangle_mesh.h"

namespace gpucol::test {

/// Raw arrays of a triangle soup, the input form of AabbTree::build.
struct Soup {
  std::vector<float> xyz;               ///< 3 floats per vertex.
  std::vector<std::uint32_t> indices;   ///< 3 vertex indices per triangle.
  /// Number of triangles.
  std::size_t triangleCount() const { return indices.size() / 3; }
  /// Vertex `k` of triangle `t` in double.
  Eigen::Vector3d vertex(std::size_t t, int k) const {
    const std::size_t v = indices[3 * t + k];
    return Eigen::Vector3d(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
  }
};

/// The arrays of a loaded mesh.
inline Soup soupOf(const TriangleMesh& mesh) { return Soup{mesh.positions(), mesh.indices()}; }

/// `count` random triangles with vertices in [-extent, extent]^3, each at most `size` across.
inline Soup randomSoup(std::size_t count, float extent, float size, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> where(-extent, extent);
  std::uniform_real_distribution<float> offset(-size, size);
  Soup soup;
  for (std::size_t t = 0; t < count; ++t) {
    const float c[3] = {where(rng), where(rng), where(rng)};
    for (int k = 0; k < 3; ++k) {
      for (int axis = 0; axis < 3; ++axis) soup.xyz.push_back(c[axis] + offset(rng));
      soup.indices.push_back(static_cast<std::uint32_t>(3 * t + k));
    }
  }
  return soup;
}

/// A uniformly random rotation (from a normalised Gaussian quaternion).
inline Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> gauss;
  Eigen::Quaterniond q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
  q.normalize();
  return q.toRotationMatrix();
}

}  // namespace gpucol::test
