#include "reference_triangles.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

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

}  // namespace gpucol::test
