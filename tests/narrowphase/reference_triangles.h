#pragma once

// Double-precision references for the near phase tests: an independent separating-axis triangle test,
// the exact distance between two triangles, and a signed "how far from touching" measure.

#include <Eigen/Core>
#include <array>

namespace gpucol::test {

/// A triangle in double precision.
using TriangleD = std::array<Eigen::Vector3d, 3>;
/// A triangle in float, as the plugin takes it.
using TriangleF = std::array<Eigen::Vector3f, 3>;

/// The float triangle, converted exactly to double.
TriangleD toDouble(const TriangleF& t);

/// Separating axis test in double over nA, nB, the nine edge-edge cross products and the six in-plane edge
/// normals nA x eA, nB x eB (which decide coplanar pairs). Touching (projections sharing one point) counts
/// as intersecting. Axes shorter than 1e-12 of the edge product are skipped: they belong to parallel edges,
/// whose separation the face and in-plane axes already decide.
bool referenceIntersect(const TriangleD& a, const TriangleD& b);

/// Euclidean distance from p to the closed triangle t.
double pointTriangleDistance(const Eigen::Vector3d& p, const TriangleD& t);

/// Euclidean distance between two closed segments.
double segmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                              const Eigen::Vector3d& q1);

/// Distance between two triangles that do not intersect (minimum over the 6 vertex-face and 9 edge-edge
/// distances); meaningless for intersecting ones.
double triangleDistance(const TriangleD& a, const TriangleD& b);

/// Smallest overlap of the two triangles' projections over the axes of referenceIntersect, per unit
/// axis length: how far the pair must move along its best axis to separate; 0 when only touching.
double separatingAxisPenetration(const TriangleD& a, const TriangleD& b);

/// Signed closeness to touching: the distance between separated triangles, minus the separating-axis
/// penetration of intersecting ones. Near 0 means "almost touching".
double signedSeparation(const TriangleD& a, const TriangleD& b);

/// Diagonal of the bounding box of both triangles: the length scale of a pair.
double pairScale(const TriangleD& a, const TriangleD& b);

}  // namespace gpucol::test
