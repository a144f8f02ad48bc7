// The pair's frame (pair_frame.h): the relative transform in double, once per pair.
#include "mesh_pairs/pair_frame.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "gpucol/mesh_shape.h"

namespace gpucol {
namespace {

// The sum of the shapes' margins (a negative sum reaches nothing) and the speculative distance; a margin that
// is not finite or a speculative distance that is negative or not finite is an error.
float pairReach(const MeshShape& a, const MeshShape& b, btScalar speculativeDistance) {
  const double sum = double(a.getMargin()) + double(b.getMargin());
  if (!std::isfinite(sum)) {
    throw std::invalid_argument("collideMeshes: the margin of shape " +
                                std::string(std::isfinite(a.getMargin()) ? "B" : "A") + " is not finite");
  }
  if (!(speculativeDistance >= 0) || !std::isfinite(speculativeDistance)) {
    throw std::invalid_argument("collideMeshes: the speculative distance " +
                                std::to_string(speculativeDistance) + " is not a finite distance >= 0");
  }
  return float(std::max(0.0, sum) + double(speculativeDistance));
}

}  // namespace

PairFrame makePairFrame(const MeshShape& a, const btTransform& transformA, const MeshShape& b,
                        const btTransform& transformB, btScalar speculativeDistance) {
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
  frame.reach = pairReach(a, b, speculativeDistance);
  if (frame.reach > 0) {
    // A world distance d is at most d / |s| along a mesh axis scaled by s; the factor covers the float rounding.
    const double widen = double(frame.reach) * (1 + 1.0 / 1048576);
    frame.candidateReach.inA = (widen * scaleA.cwiseAbs().cwiseInverse()).cast<float>();
    frame.candidateReach.inB = (widen * scaleB.cwiseAbs().cwiseInverse()).cast<float>();
  }
  return frame;
}

}  // namespace gpucol
