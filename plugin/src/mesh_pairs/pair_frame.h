#pragma once
// The frame a mesh pair is tested in, made once per pair per step and used by every stage on both paths: the
// CPU's middle and near phases (cpu_mesh_pair.cpp), the device's (mesh_batch_device.h; the kernels take it
// laid out as GpucolMeshPair, opencl/shared/mesh_pipeline_types.h) and the conversion of contacts to the
// world.
#include <LinearMath/btTransform.h>

#include <Eigen/Core>

#include "bvh/tree_traversal.h"

namespace gpucol {

class MeshShape;

/// A's body frame with A's local scaling applied ("A's scaled frame"). It is local to the pair, so scenes far
/// from the origin keep their precision, and A's triangles need only a per-axis scale. B's triangles are
/// carried in by one affine map computed once per pair (in double, so the relative transform adds no rounding
/// of its own to Bullet's float transforms).
struct PairFrame {
  Eigen::Vector3f scaleA = Eigen::Vector3f::Ones();        ///< A's local scaling.
  bool flipA = false;  ///< A's scaling mirrors the mesh: swap two vertices to keep the winding outward.
  bool flipB = false;  ///< The same for B.
  Eigen::Matrix3f bLinear = Eigen::Matrix3f::Identity();   ///< B's mesh coordinates into A's scaled frame: R_rel * S_B ...
  Eigen::Vector3f bTranslation = Eigen::Vector3f::Zero();  ///< ... + t_rel.
  AffineMap treeMap;            ///< B's mesh coordinates into A's unscaled mesh frame, for the traversal.
  btTransform worldFromA;       ///< A's rigid transform: from A's scaled frame to the world.
  /// The sum of the shapes' margins and the speculative reach (the motion's length and the turns' distance):
  /// triangles this close give contacts.
  float reach = 0;
  /// The margins' part of `reach`: contacts farther apart than this are speculative.
  float marginReach = 0;
  /// How far the traversal's box tests widen along each mesh frame's axes: the margins and the turns'
  /// distance every way, the motion along itself.
  CandidateReach candidateReach;
};

/// The frame of the pair (a at transformA, b at transformB), whose triangles give speculative contacts as
/// MeshPairQuery's speculativeMotion and speculativeDistance say. Throws std::invalid_argument when a margin
/// is not finite, the speculative distance is negative or not finite, or the motion is not finite.
PairFrame makePairFrame(const MeshShape& a, const btTransform& transformA, const MeshShape& b,
                        const btTransform& transformB,
                        const btVector3& speculativeMotion = btVector3(0, 0, 0),
                        btScalar speculativeDistance = 0);

}  // namespace gpucol
