#pragma once

#include <Eigen/Core>

namespace gpucol::detail {

/// Overlap of two triangles that lie in one plane (Möller 1997, coplanar case; thesis §3.5): both are
/// projected onto the coordinate plane that drops `dropAxis` (the dominant axis of the normal, so the
/// projection keeps the most area), then any edge of one crossing an edge of the other, or a vertex of
/// one inside the other, means they overlap. Touching (a shared vertex, an edge on an edge) counts.
/// When `point` is not null and they overlap, it receives a point of the overlap: the mean of the
/// overlap polygon's corners (vertices of one inside the other and edge crossings), lifted back to 3-D
/// on the edges of the triangles so it lies on both up to rounding.
bool coplanarTrianglesOverlap(const Eigen::Vector3d* const a[3], const Eigen::Vector3d* const b[3],
                              int dropAxis, Eigen::Vector3d* point);

}  // namespace gpucol::detail
