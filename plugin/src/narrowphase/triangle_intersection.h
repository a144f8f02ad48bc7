#pragma once

#include <Eigen/Core>

namespace gpucol {

/// Möller 1997 triangle-triangle overlap test with its early rejections and the coplanar case (thesis
/// §3.5). Touching counts as intersecting: a shared vertex, a vertex on the other face, an edge on an edge.
///
/// Precision and tolerance: the float input is evaluated in double (exact products), and a signed
/// vertex-plane distance within 1e-12 (relative to the triangle's edge lengths and the other triangle's
/// extent) is snapped to exactly zero, so configurations that are exact in the input (shared vertex,
/// vertex on the plane, coplanar faces) are decided exactly. Pairs within about 1e-6 of their size from
/// touching may be reported either way. When every vertex of B lies in A's plane (or vice versa) after
/// snapping, the 2-D coplanar test decides.
///
/// Degenerate triangles (zero area: repeated or collinear vertices, sin^2 of the angle at v0 below
/// 1e-12) and NaN coordinates have no plane, hence no normal and no contact; they return false. Mesh
/// validation reports such triangles; neighbouring triangles still collide.
bool trianglesIntersect(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                        const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2);

}  // namespace gpucol
