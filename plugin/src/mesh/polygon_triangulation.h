#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace gpucol {

/// Non-convex polygons with more corners than this are refused: ear clipping costs the square of the corners.
constexpr std::size_t kMaxNonConvexCorners = 1024;

/// How triangulatePolygon ended.
enum class PolygonStatus {
  kOk,                ///< Split into n - 2 triangles.
  kSelfIntersecting,  ///< Seen along its normal, the polygon's edges cross or it folds back on itself.
  kTooManyCorners,    ///< Non-convex with more than kMaxNonConvexCorners corners.
};

/// Splits the polygon of `n` >= 3 distinct vertex indices `corners` (positions in `xyz`) into n - 2 triangles
/// with the polygon's winding, written to `out` (3 (n - 2) indices). The polygon is seen along its Newell
/// normal: a convex one is split as a fan from its first corner, a non-convex simple one by ear clipping
/// (Eberly, "Triangulation by Ear Clipping", 2002), in double. A polygon of zero area is split as a fan (its
/// triangles are degenerate, as the polygon is).
PolygonStatus triangulatePolygon(const std::vector<float>& xyz, const std::uint32_t* corners, std::size_t n,
                                 std::uint32_t* out);

}  // namespace gpucol
