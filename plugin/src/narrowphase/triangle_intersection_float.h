#pragma once

#include <Eigen/Core>

namespace gpucol {

/// Möller 1997's triangle-triangle test done entirely in float with no snapping (the thesis's GPU near phase,
/// §5.4.1, computes this way). It is not what the plugin uses: trianglesIntersect decides in double, exactly
/// for configurations exact in the input. This one is the other end of the accuracy sweep
/// (`gpucol-bench accuracy`, "precision"): it shows what float alone costs in missed and false pairs and saves
/// in time. Touching counts as intersecting when float sees it exactly; coplanar means every distance is
/// exactly zero in float. Degenerate (zero-area in float) or NaN triangles return false.
bool trianglesIntersectFloat(const Eigen::Vector3f& a0, const Eigen::Vector3f& a1, const Eigen::Vector3f& a2,
                             const Eigen::Vector3f& b0, const Eigen::Vector3f& b1, const Eigen::Vector3f& b2);

}  // namespace gpucol
