#pragma once

// Double-precision references for the near phase tests: an independent separating-axis triangle test,
// the exact distance between two triangles, a signed "how far from touching" measure, and the depth of a
// contact taken over the triangles' overlap.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

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

/// For each edge k of a triangle (corner k to k + 1), the far vertex of the triangle across it when the edge
/// is a diagonal of a flat face; empty elsewhere.
using FlatWings = std::array<std::optional<Eigen::Vector3d>, 3>;

/// A corner of the overlap of a moving triangle with the region over a fixed one, and how far it lies below
/// the fixed triangle's plane (along -out).
struct OverlapCorner {
  Eigen::Vector3d point;
  double below = 0;
};

/// The corners of the part of `moving` over `fixed` (the documented rule of clipContactToOverlap,
/// triangle_contact.h, written again as an enumeration): the region over the fixed triangle is bounded by a
/// plane through each edge that contains the unit direction `out`, or, at a flat diagonal (a wing in
/// `fixedWings`) whose two triangles make a convex quad, by the two far edges of the triangle across it; each
/// moved out by 1e-5 of the fixed
/// triangle's size. The corners of moving ∩ region are among: moving's vertices, its edges crossing a plane,
/// and the lines where two planes meet crossing its plane; those inside both are returned (a corner may come
/// more than once). A corner's `below` is at most how far it lies behind the face across each edge of
/// `convexWings` (the far vertex across a convex edge of the fixed triangle) plus 5% of the fixed triangle's
/// size.
std::vector<OverlapCorner> referenceOverlapCorners(const TriangleD& moving, const TriangleD& fixed,
                                                   const Eigen::Vector3d& out,
                                                   const FlatWings& fixedWings = {},
                                                   const FlatWings& convexWings = {});

/// How far the part of `moving` over `fixed` must move along `out` to leave fixed's plane: the deepest of
/// referenceOverlapCorners (0 when none is below the plane).
double referenceClippedMove(const TriangleD& moving, const TriangleD& fixed, const Eigen::Vector3d& out,
                            const FlatWings& fixedWings = {}, const FlatWings& convexWings = {});

/// Diagonal of the bounding box of both triangles: the length scale of a pair.
double pairScale(const TriangleD& a, const TriangleD& b);

}  // namespace gpucol::test
