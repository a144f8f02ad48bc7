#pragma once

#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <LinearMath/btTransform.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "gpucol/mesh_shape.h"

namespace gpucol {

/// The triangles of a foreign concave shape (a BVH, scaled BVH, heightfield, GImpact or user's concave shape) near a mesh, as a MeshShape of their own,
/// so that the mesh-vs-mesh query collides the two. The patch is rebuilt only when the set of triangles near the
/// mesh changes: a mesh resting on a floor reuses the same patch step after step.
class TriangleMeshPatch {
 public:
  /// The patch of `other`'s triangles (in `other`'s scaled local frame) whose boxes overlap `mesh`'s box
  /// widened by `speculativeReach` (the pair's speculative contacts reach that far); null when there are
  /// none. `other` must stay the same shape across calls.
  const MeshShape* update(const btConcaveShape& other, const btTransform& otherTransform,
                          const MeshShape& mesh, const btTransform& meshTransform,
                          btScalar speculativeReach = 0);

  /// The part and index that `other`'s processAllTriangles gave for triangle `patchTriangle` of the patch.
  void sourceTriangle(std::uint32_t patchTriangle, int& partId, int& triangleIndex) const {
    const std::uint64_t id = m_triangleIds.at(patchTriangle);
    partId = int(std::uint32_t(id >> 32));
    triangleIndex = int(std::uint32_t(id));
  }

 private:
  std::vector<std::uint64_t> m_triangleIds;  // (part, index) of the patch's triangles, in the order collected
  std::vector<float> m_positions;            // their corners as collected (the patch's own copy is its mesh's)
  std::unique_ptr<MeshShape> m_shape;
};

}  // namespace gpucol
