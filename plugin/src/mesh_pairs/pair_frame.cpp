// The pair's frame (pair_frame.h): the relative transform in double, once per pair.
#include "mesh_pairs/pair_frame.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "gpucol/mesh_shape.h"

namespace gpucol {
namespace {

// The sum of the shapes' margins (a negative sum reaches nothing); a margin that is not finite is an error.
double marginReach(const MeshShape& a, const MeshShape& b) {
  const double sum = double(a.getMargin()) + double(b.getMargin());
  if (!std::isfinite(sum)) {
    throw std::invalid_argument("collideMeshes: the margin of shape " +
                                std::string(std::isfinite(a.getMargin()) ? "B" : "A") + " is not finite");
  }
  return std::max(0.0, sum);
}

void requireSpeculativeReach(const btVector3& motion, btScalar distance) {
  if (!(distance >= 0) || !std::isfinite(distance)) {
    throw std::invalid_argument("collideMeshes: the speculative distance " + std::to_string(distance) +
                                " is not a finite distance >= 0");
  }
  if (!std::isfinite(motion.x()) || !std::isfinite(motion.y()) || !std::isfinite(motion.z())) {
    throw std::invalid_argument("collideMeshes: the speculative motion has a NaN or infinite component");
  }
}

}  // namespace

PairFrame makePairFrame(const MeshShape& a, const btTransform& transformA, const MeshShape& b,
                        const btTransform& transformB, const btVector3& speculativeMotion,
                        btScalar speculativeDistance) {
  requireSpeculativeReach(speculativeMotion, speculativeDistance);
  Eigen::Matrix3d rotationA, rotationB;
  Eigen::Vector3d originA, originB, scaleA, scaleB;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      rotationA(r, c) = transformA.getBasis()[r][c];
      rotationB(r, c) = transformB.getBasis()[r][c];
    }
    originA[r] = transformA.getOrigin()[r];
    originB[r] = transformB.getOrigin()[r];
    scaleA[r] = a.getLocalScaling()[r];
    scaleB[r] = b.getLocalScaling()[r];
  }
  const Eigen::Matrix3d relativeRotation = rotationA.transpose() * rotationB;
  const Eigen::Vector3d relativeTranslation = rotationA.transpose() * (originB - originA);
  const Eigen::Matrix3d bLinear = relativeRotation * scaleB.asDiagonal();

  PairFrame frame;
  frame.scaleA = scaleA.cast<float>();
  frame.flipA = scaleA.prod() < 0;
  frame.flipB = scaleB.prod() < 0;
  frame.bLinear = bLinear.cast<float>();
  frame.bTranslation = relativeTranslation.cast<float>();
  const Eigen::Vector3d inverseScaleA = scaleA.cwiseInverse();
  frame.treeMap.linear = (inverseScaleA.asDiagonal() * bLinear).cast<float>();
  frame.treeMap.translation = inverseScaleA.cwiseProduct(relativeTranslation).cast<float>();
  frame.worldFromA = transformA;
  const Eigen::Vector3d motion(speculativeMotion.x(), speculativeMotion.y(), speculativeMotion.z());
  const double margins = marginReach(a, b);
  const double everyWay = margins + double(speculativeDistance);
  frame.reach = float(everyWay + motion.norm());
  frame.marginReach = float(margins);
  if (frame.reach > 0) {
    // A world distance d is at most d / |s| along a mesh axis scaled by s; the factor covers the float rounding.
    const double widen = 1 + 1.0 / 1048576;
    const auto alongAxes = [&](const Eigen::Matrix3d& rotation, const Eigen::Vector3d& scale) {
      const Eigen::Vector3d world = (rotation.transpose() * motion).cwiseAbs().array() + everyWay;
      return (widen * world.cwiseQuotient(scale.cwiseAbs())).cast<float>().eval();
    };
    frame.candidateReach.inA = alongAxes(rotationA, scaleA);
    frame.candidateReach.inB = alongAxes(rotationB, scaleB);
  }
  return frame;
}

}  // namespace gpucol
