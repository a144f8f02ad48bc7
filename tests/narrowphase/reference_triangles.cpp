#include "reference_triangles.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace gpucol::test {
namespace {

/// Interval of a triangle projected on an axis.
void project(const TriangleD& t, const Eigen::Vector3d& axis, double& lo, double& hi) {
  const double p0 = axis.dot(t[0]), p1 = axis.dot(t[1]), p2 = axis.dot(t[2]);
  lo = std::min({p0, p1, p2});
  hi = std::max({p0, p1, p2});
}

/// Calls visit(axis) for every candidate separating axis that is not degenerate.
template <class Visit>
void forEachAxis(const TriangleD& a, const TriangleD& b, Visit visit) {
  const Eigen::Vector3d ea[3] = {a[1] - a[0], a[2] - a[1], a[0] - a[2]};
  const Eigen::Vector3d eb[3] = {b[1] - b[0], b[2] - b[1], b[0] - b[2]};
  const Eigen::Vector3d na = ea[0].cross(-ea[2]);
  const Eigen::Vector3d nb = eb[0].cross(-eb[2]);
  auto consider = [&](const Eigen::Vector3d& axis, double scale2) {
    if (axis.squaredNorm() > 1e-24 * scale2) visit(axis);
  };
  consider(na, ea[0].squaredNorm() * ea[2].squaredNorm());
  consider(nb, eb[0].squaredNorm() * eb[2].squaredNorm());
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) consider(ea[i].cross(eb[j]), ea[i].squaredNorm() * eb[j].squaredNorm());
    consider(na.cross(ea[i]), na.squaredNorm() * ea[i].squaredNorm());
    consider(nb.cross(eb[i]), nb.squaredNorm() * eb[i].squaredNorm());
  }
}

double pointSegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& s0, const Eigen::Vector3d& s1) {
  const Eigen::Vector3d d = s1 - s0;
  const double length2 = d.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - s0).dot(d) / length2, 0.0, 1.0) : 0.0;
  return (s0 + t * d - p).norm();
}

}  // namespace

TriangleD toDouble(const TriangleF& t) {
  return {t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()};
}

bool referenceIntersect(const TriangleD& a, const TriangleD& b) {
  bool separated = false;
  forEachAxis(a, b, [&](const Eigen::Vector3d& axis) {
    double loA, hiA, loB, hiB;
    project(a, axis, loA, hiA);
    project(b, axis, loB, hiB);
    if (hiA < loB || hiB < loA) separated = true;
  });
  return !separated;
}

double pointTriangleDistance(const Eigen::Vector3d& p, const TriangleD& t) {
  // Inside the prism over the triangle the distance is the plane distance; outside it, the nearest
  // point is on an edge.
  const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  bool inside = true;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& u = t[i];
    const Eigen::Vector3d& v = t[(i + 1) % 3];
    if ((v - u).cross(p - u).dot(n) < 0.0) inside = false;
  }
  if (inside) return std::fabs(n.dot(p - t[0])) / n.norm();
  return std::min({pointSegmentDistance(p, t[0], t[1]), pointSegmentDistance(p, t[1], t[2]),
                   pointSegmentDistance(p, t[2], t[0])});
}

double segmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                              const Eigen::Vector3d& q1) {
  // The squared distance is convex in (s, t) over [0,1]^2: its minimum is either the interior
  // stationary point or on the square's boundary, where one endpoint is fixed.
  double best = std::min({pointSegmentDistance(p0, q0, q1), pointSegmentDistance(p1, q0, q1),
                          pointSegmentDistance(q0, p0, p1), pointSegmentDistance(q1, p0, p1)});
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const double denominator = a * e - b * b;
  if (denominator > 1e-14 * a * e) {
    const double s = (b * f - c * e) / denominator;
    const double t = (a * f - b * c) / denominator;
    if (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0) best = std::min(best, (p0 + s * d1 - (q0 + t * d2)).norm());
  }
  return best;
}

double triangleDistance(const TriangleD& a, const TriangleD& b) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    best = std::min({best, pointTriangleDistance(a[i], b), pointTriangleDistance(b[i], a)});
    for (int j = 0; j < 3; ++j) {
      best = std::min(best, segmentSegmentDistance(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]));
    }
  }
  return best;
}

double separatingAxisPenetration(const TriangleD& a, const TriangleD& b) {
  double best = std::numeric_limits<double>::infinity();
  forEachAxis(a, b, [&](const Eigen::Vector3d& axis) {
    double loA, hiA, loB, hiB;
    project(a, axis, loA, hiA);
    project(b, axis, loB, hiB);
    const double overlap = std::min(hiA - loB, hiB - loA) / axis.norm();
    best = std::min(best, std::max(overlap, 0.0));
  });
  return best;
}

double signedSeparation(const TriangleD& a, const TriangleD& b) {
  return referenceIntersect(a, b) ? -separatingAxisPenetration(a, b) : triangleDistance(a, b);
}

double pairScale(const TriangleD& a, const TriangleD& b) {
  Eigen::Vector3d lower = a[0], upper = a[0];
  for (const TriangleD* t : {&a, &b}) {
    for (const Eigen::Vector3d& v : *t) {
      lower = lower.cwiseMin(v);
      upper = upper.cwiseMax(v);
    }
  }
  return (upper - lower).norm();
}

std::vector<OverlapCorner> referenceOverlapCorners(const TriangleD& moving, const TriangleD& fixed,
                                                   const Eigen::Vector3d& out, const FlatWings& fixedWings,
                                                   const FlatWings& convexWings) {
  const double size =
      std::max({(fixed[1] - fixed[0]).norm(), (fixed[2] - fixed[1]).norm(), (fixed[0] - fixed[2]).norm()});
  struct Plane {
    Eigen::Vector3d origin, inward;  // unit inward normal
  };
  std::vector<Plane> planes;
  const auto add = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& inner) {
    Eigen::Vector3d n = out.cross(to - from).normalized();
    if (n.dot(inner - from) < 0) n = -n;
    planes.push_back({from - n * (1e-5 * size), n});
  };
  // The quad of the fixed triangle and the one across a flat diagonal, in order around it, turns the same way
  // at every corner (seen along `out`) when it is convex.
  const auto convexQuad = [&](const Eigen::Vector3d(&q)[4]) {
    int left = 0, right = 0;
    for (int i = 0; i < 4; ++i) {
      const double turn = out.dot((q[(i + 1) % 4] - q[i]).cross(q[(i + 2) % 4] - q[(i + 1) % 4]));
      left += turn > 0;
      right += turn < 0;
    }
    return left == 0 || right == 0;
  };
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& from = fixed[k];
    const Eigen::Vector3d& to = fixed[(k + 1) % 3];
    if (fixedWings[k] && convexQuad({fixed[(k + 2) % 3], from, *fixedWings[k], to})) {
      add(from, *fixedWings[k], to);
      add(*fixedWings[k], to, from);
    } else {
      add(from, to, fixed[(k + 2) % 3]);
    }
  }
  std::vector<Eigen::Vector3d> corners(moving.begin(), moving.end());
  for (const Plane& plane : planes) {
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector3d& p = moving[e];
      const Eigen::Vector3d& q = moving[(e + 1) % 3];
      const double sp = plane.inward.dot(p - plane.origin), sq = plane.inward.dot(q - plane.origin);
      if ((sp < 0) != (sq < 0)) corners.push_back(p + (q - p) * (sp / (sp - sq)));
    }
  }
  const Eigen::Vector3d nMoving = (moving[1] - moving[0]).cross(moving[2] - moving[0]).normalized();
  for (std::size_t i = 0; i < planes.size(); ++i) {
    for (std::size_t j = i + 1; j < planes.size(); ++j) {
      // The line along `out` where planes i and j meet: solve within the plane normal to `out`.
      const Eigen::Vector3d& ni = planes[i].inward;
      const Eigen::Vector3d& nj = planes[j].inward;
      const double di = ni.dot(planes[i].origin), dj = nj.dot(planes[j].origin);
      const double det = ni.cross(nj).dot(out);
      if (std::abs(det) < 1e-12) continue;
      // A point x with ni.x = di, nj.x = dj, out.x = 0, then moved along `out` onto moving's plane.
      const Eigen::Vector3d x = (di * nj.cross(out) + dj * out.cross(ni)) / det;
      const double along = nMoving.dot(out);
      if (std::abs(along) < 1e-12) continue;
      corners.push_back(x + out * (nMoving.dot(moving[0] - x) / along));
    }
  }
  const double tolerance = 1e-9 * size;
  std::vector<OverlapCorner> inside;
  for (const Eigen::Vector3d& c : corners) {
    bool in = std::all_of(planes.begin(), planes.end(), [&](const Plane& plane) {
      return plane.inward.dot(c - plane.origin) >= -tolerance;
    });
    // Inside the moving triangle: on the inner side of each of its edges within its plane.
    for (int e = 0; e < 3 && in; ++e) {
      const Eigen::Vector3d edge = moving[(e + 1) % 3] - moving[e];
      in = nMoving.cross(edge).dot(c - moving[e]) >= -tolerance * edge.norm();
    }
    if (!in) continue;
    double below = -out.dot(c - fixed[0]);
    for (int k = 0; k < 3; ++k) {
      if (!convexWings[k]) continue;
      // The face across the edge, facing away from the fixed triangle's third vertex.
      const Eigen::Vector3d& from = fixed[k];
      Eigen::Vector3d n = (fixed[(k + 1) % 3] - from).cross(*convexWings[k] - from).normalized();
      if (n.dot(fixed[(k + 2) % 3] - from) > 0) n = -n;
      below = std::min(below, -n.dot(c - from) + 0.05 * size);
    }
    inside.push_back({c, below});
  }
  return inside;
}

double referenceClippedMove(const TriangleD& moving, const TriangleD& fixed, const Eigen::Vector3d& out,
                            const FlatWings& fixedWings, const FlatWings& convexWings) {
  double deepest = 0;
  for (const OverlapCorner& c : referenceOverlapCorners(moving, fixed, out, fixedWings, convexWings))
    deepest = std::max(deepest, c.below);
  return deepest;
}

}  // namespace gpucol::test
