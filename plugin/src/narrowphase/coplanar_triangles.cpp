#include "narrowphase/coplanar_triangles.h"

#include "narrowphase/triangle_plane.h"

namespace gpucol::detail {
namespace {

/// Accumulates the corners of the overlap polygon; only the sum and count are needed for its mean.
struct CornerSum {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  void add(const Eigen::Vector3d& p) {
    sum += p;
    ++count;
  }
};

/// True when the signed values x and y are zero or of opposite signs (the segment between them reaches 0).
inline bool straddles(double x, double y) {
  return (x <= 0.0 && y >= 0.0) || (x >= 0.0 && y <= 0.0);
}

/// Point-in-triangle for a 2-D triangle of either winding; the boundary counts as inside.
inline bool insideOrOn(const double tx[3], const double ty[3], double px, double py) {
  const double o0 = orient2d(tx[0], ty[0], tx[1], ty[1], px, py);
  const double o1 = orient2d(tx[1], ty[1], tx[2], ty[2], px, py);
  const double o2 = orient2d(tx[2], ty[2], tx[0], ty[0], px, py);
  return (o0 >= 0.0 && o1 >= 0.0 && o2 >= 0.0) || (o0 <= 0.0 && o1 <= 0.0 && o2 <= 0.0);
}

}  // namespace

bool coplanarTrianglesOverlap(const Eigen::Vector3d* const a[3], const Eigen::Vector3d* const b[3],
                              int dropAxis, Eigen::Vector3d* point) {
  const int u = dropAxis == 0 ? 1 : 0;
  const int v = dropAxis == 2 ? 1 : 2;
  const double ax[3] = {(*a[0])[u], (*a[1])[u], (*a[2])[u]};
  const double ay[3] = {(*a[0])[v], (*a[1])[v], (*a[2])[v]};
  const double bx[3] = {(*b[0])[u], (*b[1])[u], (*b[2])[u]};
  const double by[3] = {(*b[0])[v], (*b[1])[v], (*b[2])[v]};
  const bool wantPoint = point != nullptr;
  CornerSum corners;

  // Edge against edge: proper crossings and an endpoint on the other segment. Collinear edge pairs
  // (all four orientations zero) are skipped: when they overlap, an endpoint of one lies on the other
  // and the containment tests below find it.
  for (int i = 0; i < 3; ++i) {
    const int i1 = i == 2 ? 0 : i + 1;
    for (int j = 0; j < 3; ++j) {
      const int j1 = j == 2 ? 0 : j + 1;
      const double o1 = orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j], by[j]);
      const double o2 = orient2d(ax[i], ay[i], ax[i1], ay[i1], bx[j1], by[j1]);
      if (!straddles(o1, o2) || (o1 == 0.0 && o2 == 0.0)) continue;
      const double o3 = orient2d(bx[j], by[j], bx[j1], by[j1], ax[i], ay[i]);
      const double o4 = orient2d(bx[j], by[j], bx[j1], by[j1], ax[i1], ay[i1]);
      // o3 == o4 (both zero, since they straddle) says that a's edge lies on b's line. Exact input reaches it
      // only for collinear edges, but rounding does too: an edge shorter than about 1e-16 of the other
      // triangle's size has both ends "on" b's line while o1, o2 still straddle (found by the triangle fuzzer:
      // a needle 1e-44 wide gave 0 / 0 = NaN as the contact point). Either way the endpoints that matter are
      // found by the containment tests below, as for collinear edges.
      if (!straddles(o3, o4) || o3 == o4) continue;
      if (!wantPoint) return true;
      const double t = o3 / (o3 - o4);
      corners.add(*a[i] + (*a[i1] - *a[i]) * t);
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (insideOrOn(bx, by, ax[i], ay[i])) {
      if (!wantPoint) return true;
      corners.add(*a[i]);
    }
    if (insideOrOn(ax, ay, bx[i], by[i])) {
      if (!wantPoint) return true;
      corners.add(*b[i]);
    }
  }
  if (corners.count == 0) return false;
  *point = corners.sum / static_cast<double>(corners.count);
  return true;
}

}  // namespace gpucol::detail
