#include "bullet/triangle_mesh_patch.h"

#include <BulletCollision/CollisionShapes/btTriangleCallback.h>

#include <algorithm>

namespace gpucol {
namespace {

class TriangleCollector : public btTriangleCallback {
 public:
  void processTriangle(btVector3* triangle, int partId, int triangleIndex) override {
    ids.push_back((std::uint64_t(std::uint32_t(partId)) << 32) | std::uint32_t(triangleIndex));
    for (int i = 0; i < 3; ++i) {
      for (int axis = 0; axis < 3; ++axis) xyz.push_back(float(triangle[i][axis]));
    }
  }
  std::vector<std::uint64_t> ids;
  std::vector<float> xyz;
};

}  // namespace

const MeshShape* TriangleMeshPatch::update(const btConcaveShape& other, const btTransform& otherTransform,
                                           const MeshShape& mesh, const btTransform& meshTransform,
                                           btScalar speculativeReach) {
  btVector3 lo, hi;
  mesh.getAabb(otherTransform.inverseTimes(meshTransform), lo, hi);
  // The mesh's box holds its own margin; the other's margin and the speculative contacts reach further still.
  const btScalar widen = std::max(btScalar(0), other.getMargin()) + std::max(btScalar(0), speculativeReach);
  lo -= btVector3(widen, widen, widen);
  hi += btVector3(widen, widen, widen);
  TriangleCollector collector;
  other.processAllTriangles(&collector, lo, hi);
  if (collector.ids.empty()) {
    m_triangleIds.clear();
    m_shape.reset();
    return nullptr;
  }
  // Rebuilt when other triangles come near, or the same ones moved (a deforming shape, such as a GImpact mesh
  // whose vertices the user updates).
  if (collector.ids != m_triangleIds || collector.xyz != m_positions || !m_shape) {
    m_positions = collector.xyz;
    // Each triangle gets its own three vertices: the patch needs no welding, only the triangles' positions.
    std::vector<std::uint32_t> indices(collector.xyz.size() / 3);
    for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = std::uint32_t(i);
    auto patch = std::make_shared<const TriangleMesh>(
        TriangleMesh::fromArrays(std::move(collector.xyz), std::move(indices), "triangles of a concave shape"));
    m_shape = std::make_unique<MeshShape>(std::move(patch));
    m_triangleIds = std::move(collector.ids);
  }
  // The patch stands in for the other shape: its margin too, so that the pair reaches both margins.
  m_shape->setMargin(other.getMargin());
  return m_shape.get();
}

}  // namespace gpucol
