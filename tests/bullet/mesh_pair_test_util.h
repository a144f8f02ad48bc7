#pragma once

// Helpers of the mesh pair tests: world-space triangles in double, brute-force references, random poses.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <LinearMath/btTransform.h>
#include <algorithm>
#include <memory>
#include <random>
#include <set>
#include <vector>

#include <gpucol/gpucol.h>

#include "narrowphase/reference_triangles.h"

namespace gpucol::test {

/// Triangle `t` of a shape in world space, in double: world = transform * (scaling ∘ vertex).
inline TriangleD worldTriangle(const MeshShape& shape, const btTransform& transform, std::uint32_t t) {
  TriangleD out;
  const TriangleMesh& mesh = shape.mesh();
  for (int corner = 0; corner < 3; ++corner) {
    const float* p = mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * std::size_t(t) + corner]);
    Eigen::Vector3d local;
    for (int axis = 0; axis < 3; ++axis) local[axis] = double(p[axis]) * double(shape.getLocalScaling()[axis]);
    for (int r = 0; r < 3; ++r) {
      out[corner][r] = double(transform.getOrigin()[r]);
      for (int c = 0; c < 3; ++c) out[corner][r] += double(transform.getBasis()[r][c]) * local[c];
    }
  }
  return out;
}

/// Every triangle pair of the two shapes, tested in double; `separation` receives signedSeparation per pair.
struct BruteForcePair {
  TrianglePair pair;
  double separation;  ///< Signed: negative when penetrating (see signedSeparation).
  double scale;       ///< Length scale of the pair (pairScale).
};

/// All pairs whose triangles the double-precision reference finds intersecting or closer than `band` × scale.
inline std::vector<BruteForcePair> bruteForceNearPairs(const MeshShape& a, const btTransform& ta, const MeshShape& b,
                                                       const btTransform& tb, double band) {
  std::vector<TriangleD> trianglesB;
  std::vector<Eigen::Vector3d> minB, maxB;
  for (std::uint32_t t = 0; t < b.mesh().triangleCount(); ++t) {
    trianglesB.push_back(worldTriangle(b, tb, t));
    minB.push_back(trianglesB.back()[0].cwiseMin(trianglesB.back()[1]).cwiseMin(trianglesB.back()[2]));
    maxB.push_back(trianglesB.back()[0].cwiseMax(trianglesB.back()[1]).cwiseMax(trianglesB.back()[2]));
  }
  std::vector<BruteForcePair> out;
  for (std::uint32_t ta_ = 0; ta_ < a.mesh().triangleCount(); ++ta_) {
    const TriangleD triA = worldTriangle(a, ta, ta_);
    const Eigen::Vector3d lo = triA[0].cwiseMin(triA[1]).cwiseMin(triA[2]);
    const Eigen::Vector3d hi = triA[0].cwiseMax(triA[1]).cwiseMax(triA[2]);
    const double slack = band * (hi - lo).norm() + 1e-12;
    for (std::uint32_t tb_ = 0; tb_ < trianglesB.size(); ++tb_) {
      // Exact box rejection in double, widened by the band, before the costlier reference.
      if (((minB[tb_].array() - slack) > hi.array()).any() || ((maxB[tb_].array() + slack) < lo.array()).any()) {
        continue;
      }
      const double scale = pairScale(triA, trianglesB[tb_]);
      const double separation = signedSeparation(triA, trianglesB[tb_]);
      if (separation <= band * scale) out.push_back({{ta_, tb_}, separation, scale});
    }
  }
  return out;
}

/// A rigid transform from a random unit quaternion and a translation inside `box` half extents.
inline btTransform randomPose(std::mt19937& rng, const btVector3& centre, float halfExtent) {
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> uniform(-halfExtent, halfExtent);
  btQuaternion q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
  q.normalize();
  return btTransform(q, centre + btVector3(uniform(rng), uniform(rng), uniform(rng)));
}

/// Largest side of a mesh's bounding box.
inline float largestSide(const TriangleMesh& mesh) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    const Eigen::Vector3f p(mesh.positions()[3 * v], mesh.positions()[3 * v + 1], mesh.positions()[3 * v + 2]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).maxCoeff();
}

/// The deepest contact of each triangle pair (a pair gives one contact per corner of its overlap that dips
/// in, the deepest first; the others follow it), in the contacts' order.
inline std::vector<MeshContact> deepestContactPerPair(const std::vector<MeshContact>& contacts) {
  std::vector<MeshContact> out;
  for (const MeshContact& c : contacts) {
    if (!out.empty() && out.back().triangleA == c.triangleA && out.back().triangleB == c.triangleB) {
      if (c.depth < out.back().depth) out.back() = c;
      continue;
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace gpucol::test
