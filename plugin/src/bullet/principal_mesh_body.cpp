#include "gpucol/principal_mesh_body.h"

#include <array>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "gpucol/mesh_error.h"

namespace gpucol {

btRigidBody::btRigidBodyConstructionInfo PrincipalMeshBody::constructionInfo(
    const btTransform& meshWorldTransform, btMotionState* motionState) const {
  btRigidBody::btRigidBodyConstructionInfo info(mass, motionState, shape.get(), inertia);
  info.m_startWorldTransform = bodyTransform(meshWorldTransform);
  return info;
}

PrincipalMeshBody principalMeshBody(const MeshShape& shape, btScalar mass, const Config& config) {
  const TriangleMesh& mesh = shape.mesh();
  if (!std::isfinite(mass) || !(mass > 0)) {
    std::ostringstream out;
    out << mesh.name() << ": principalMeshBody needs a finite, positive mass; got " << mass;
    throw MeshError(out.str());
  }
  // The scaled mesh, as MeshShape::calculateLocalInertia integrates it: a mirroring scale swaps two corners
  // back to keep the winding outward.
  const btVector3& s = shape.getLocalScaling();
  std::vector<float> xyz = mesh.positions();
  for (std::size_t i = 0; i < xyz.size(); ++i) xyz[i] *= float(s[int(i % 3)]);
  std::vector<std::uint32_t> indices = mesh.indices();
  if (s.x() * s.y() * s.z() < 0) {
    for (std::size_t t = 0; t < indices.size(); t += 3) std::swap(indices[t + 1], indices[t + 2]);
  }
  const TriangleMesh scaled =
      TriangleMesh::fromParts(std::move(xyz), std::move(indices), mesh.parts(), mesh.name());
  std::array<double, 9> rotation{};
  std::array<double, 3> translation{};
  TriangleMesh principal = scaled.inPrincipalFrame(1.0, &rotation, &translation);
  const MassProperties unitDensity = scaled.massProperties(1.0);
  const double density = double(mass) / unitDensity.volume;

  PrincipalMeshBody out;
  out.shape = std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(std::move(principal)), config);
  out.shape->setMargin(shape.getMargin());
  out.principal.setBasis(btMatrix3x3(btScalar(rotation[0]), btScalar(rotation[1]), btScalar(rotation[2]),
                                     btScalar(rotation[3]), btScalar(rotation[4]), btScalar(rotation[5]),
                                     btScalar(rotation[6]), btScalar(rotation[7]), btScalar(rotation[8])));
  out.principal.setOrigin(
      btVector3(btScalar(translation[0]), btScalar(translation[1]), btScalar(translation[2])));
  // The principal axes are the frame's x, y, z in the order of the moments.
  const auto& moments = unitDensity.principalMoments;
  out.inertia.setValue(btScalar(moments[0] * density), btScalar(moments[1] * density),
                       btScalar(moments[2] * density));
  out.mass = mass;
  return out;
}

}  // namespace gpucol
