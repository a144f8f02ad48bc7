// MeshShape::fromGImpact and MeshShape::fromBvh: a MeshShape with the triangles, scaling and margin of a
// Bullet mesh shape.
#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "gpucol/mesh_shape.h"

namespace gpucol {

std::unique_ptr<MeshShape> MeshShape::fromGImpact(const btGImpactMeshShape& shape, const Config& config) {
  TriangleMesh mesh = TriangleMesh::fromStridingMesh(*shape.getMeshInterface(), "btGImpactMeshShape");
  // GImpact reads the arrays' vertices times each part's scale (not the mesh interface's), and collides its
  // triangles with each part's margin.
  btScalar margin = 0;
  bool sameScaling = true;
  const btVector3 scaling =
      shape.getMeshPartCount() > 0 ? shape.getMeshPart(0)->getLocalScaling() : btVector3(1, 1, 1);
  for (int p = 0; p < shape.getMeshPartCount(); ++p) {
    margin = std::max(margin, shape.getMeshPart(p)->getMargin());
    sameScaling = sameScaling && shape.getMeshPart(p)->getLocalScaling() == scaling;
  }
  std::unique_ptr<MeshShape> out;
  if (sameScaling) {
    out = std::make_unique<MeshShape>(std::make_shared<const TriangleMesh>(std::move(mesh)), config);
    out->setLocalScaling(scaling);
  } else {
    // One local scaling cannot say what each part's does: each part's goes into its vertices.
    std::vector<float> xyz = mesh.positions();
    std::vector<std::uint32_t> indices = mesh.indices();
    for (std::size_t p = 0; p < mesh.parts().size(); ++p) {
      const MeshPart& part = mesh.parts()[p];
      const btVector3& s = shape.getMeshPart(int(p))->getLocalScaling();
      for (std::size_t v = part.firstVertex; v < std::size_t(part.firstVertex) + part.vertexCount; ++v) {
        for (int axis = 0; axis < 3; ++axis) xyz[3 * v + axis] *= float(s[axis]);
      }
      // A mirroring scale turns the winding inward: two corners swap to keep it outward.
      if (s.x() * s.y() * s.z() < 0) {
        for (std::size_t t = part.firstTriangle; t < std::size_t(part.firstTriangle) + part.triangleCount;
             ++t) {
          std::swap(indices[3 * t + 1], indices[3 * t + 2]);
        }
      }
    }
    out = std::make_unique<MeshShape>(
        std::make_shared<const TriangleMesh>(TriangleMesh::fromParts(
            std::move(xyz), std::move(indices), mesh.parts(), mesh.name() + " (parts' scaling applied)")),
        config);
  }
  out->setMargin(margin);
  return out;
}

std::unique_ptr<MeshShape> MeshShape::fromBvh(const btBvhTriangleMeshShape& shape, const Config& config) {
  auto out = std::make_unique<MeshShape>(std::make_shared<const TriangleMesh>(TriangleMesh::fromStridingMesh(
                                             *shape.getMeshInterface(), "btBvhTriangleMeshShape")),
                                         config);
  // A BVH mesh's local scaling is its mesh interface's.
  out->setLocalScaling(shape.getLocalScaling());
  out->setMargin(shape.getMargin());
  return out;
}

}  // namespace gpucol
