#pragma once

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <LinearMath/btTransform.h>

#include <vector>

#include "bullet/contact_manifold_set.h"
#include "gpucol/mesh_shape.h"

namespace gpucol {

/// Contacts of a mesh (body0) against a btStaticPlaneShape's half-space (body1): every mesh vertex on or below the
/// plane (margins included), found through the tree, reduced by the 6-D binning at
/// `reductionResolution` (thesis §5.3.5). The plane is a half-space, so a vertex deep below it still gives a
/// contact pushing it out along the plane's normal, however deep. Points are on the plane, normals are the
/// plane's, in ascending vertex order before reduction.
std::vector<PairContact> meshPlaneContacts(const MeshShape& mesh, const btTransform& meshTransform,
                                           const btStaticPlaneShape& plane, const btTransform& planeTransform,
                                           int reductionResolution);

}  // namespace gpucol
