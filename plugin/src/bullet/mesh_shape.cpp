#include "gpucol/mesh_shape.h"

#include <cmath>
#include <sstream>

#include "bvh/aabb_tree.h"
#include "gpucol/mesh_error.h"

namespace gpucol {

MeshShape::MeshShape(std::shared_ptr<const TriangleMesh> mesh, const Config& config) : m_mesh(std::move(mesh)) {
  if (!m_mesh) throw MeshError("MeshShape: the mesh pointer is null");
  m_tree = std::make_shared<const AabbTree>(AabbTree::build(*m_mesh, config.trianglesPerLeaf));
}

MeshShape::~MeshShape() = default;

void MeshShape::setLocalScaling(const btVector3& scaling) {
  for (int axis = 0; axis < 3; ++axis) {
    const btScalar s = scaling[axis];
    if (!std::isfinite(s) || s == btScalar(0)) {
      std::ostringstream message;
      message << "MeshShape '" << m_mesh->name() << "': local scaling component " << axis << " is " << s
              << "; it must be finite and non-zero";
      throw MeshError(message.str());
    }
  }
  m_localScaling = scaling;
}

}  // namespace gpucol
