#pragma once

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <LinearMath/btTransform.h>
#include <LinearMath/btVector3.h>

#include <memory>

#include "gpucol/config.h"
#include "gpucol/mesh_shape.h"

namespace gpucol {

/// A dynamic mesh body in its principal frame, as btCompoundShape::calculatePrincipalAxisTransform gives a
/// compound one: Bullet's btRigidBody takes a diagonal inertia about the centre of mass, so a mesh whose own
/// frame is not its principal frame (centre of mass off the origin, or a tensor with off-diagonal terms) is
/// moved into that frame and the body placed where the mesh's frame puts it. Nothing is approximated: the
/// diagonal is the whole tensor.
struct PrincipalMeshBody {
  /// The scaled mesh moved into its principal frame (scaling (1,1,1); margin, parts and name kept).
  std::shared_ptr<MeshShape> shape;
  /// The principal frame in the frame of the shape it was made from: a point p of `shape` is `principal * p`
  /// there.
  btTransform principal = btTransform::getIdentity();
  /// The principal moments of inertia for `mass` (uniform density): Bullet's local inertia for `shape`.
  btVector3 inertia{0, 0, 0};
  /// The body's mass.
  btScalar mass = 0;

  /// The body's world transform that puts the original shape's frame at `meshWorldTransform`.
  btTransform bodyTransform(const btTransform& meshWorldTransform) const {
    return meshWorldTransform * principal;
  }
  /// Where the original shape's frame is when the body is at `bodyWorldTransform`.
  btTransform meshTransform(const btTransform& bodyWorldTransform) const {
    return bodyWorldTransform * principal.inverse();
  }
  /// Construction info for the btRigidBody (mass, `shape`, `inertia`, start transform bodyTransform(...)).
  /// The body does not own `shape`: keep this object (or the shape) alive as long as the body.
  btRigidBody::btRigidBodyConstructionInfo constructionInfo(const btTransform& meshWorldTransform,
                                                            btMotionState* motionState = nullptr) const;
};

/// The principal-frame body of `shape` (its local scaling applied, its margin kept) with `mass`, its tree
/// built with `config`. Throws MeshError, saying why, for a mesh without a volume (open, non-manifold, inward
/// winding) and for a mass that is not finite and positive.
PrincipalMeshBody principalMeshBody(const MeshShape& shape, btScalar mass, const Config& config = Config());

}  // namespace gpucol
