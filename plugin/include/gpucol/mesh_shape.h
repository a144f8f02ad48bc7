#pragma once

#include <LinearMath/btVector3.h>

#include <memory>

#include "gpucol/config.h"
#include "gpucol/triangle_mesh.h"

namespace gpucol {

class AabbTree;

/// A triangle mesh as a collision shape: the shared, immutable mesh, its tree of non-updated AABBs
/// (built once, in the mesh's own frame) and a local scaling.
class MeshShape {
 public:
  /// Builds the tree of `mesh` with `config.trianglesPerLeaf` triangles per leaf.
  explicit MeshShape(std::shared_ptr<const TriangleMesh> mesh, const Config& config = Config());
  ~MeshShape();

  /// The mesh this shape collides with.
  const TriangleMesh& mesh() const { return *m_mesh; }
  /// The tree of non-updated AABBs of the mesh.
  const AabbTree& tree() const { return *m_tree; }
  /// Per-axis scale applied to the mesh (1,1,1 by default); each component must be finite and non-zero.
  void setLocalScaling(const btVector3& scaling);
  /// The current local scaling.
  const btVector3& getLocalScaling() const { return m_localScaling; }

 private:
  std::shared_ptr<const TriangleMesh> m_mesh;
  std::shared_ptr<const AabbTree> m_tree;
  btVector3 m_localScaling{1, 1, 1};
};

}  // namespace gpucol
