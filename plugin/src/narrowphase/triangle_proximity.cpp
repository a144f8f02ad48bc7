// Contacts of triangles closer than the shapes' margins: vertex over face and edge against edge, the features
// whose closest points realise the distance between two triangles that do not intersect.
#include "narrowphase/triangle_proximity.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gpucol {
namespace {

using Vec = Eigen::Vector3d;

// Tolerance of the outer-side test: it keeps faces at right angles (a box's side against the face it stands
// on), whose contact normal is perpendicular to one of them.
constexpr double kSideTolerance = 1e-6;

// A triangle in double with its unit outward normal; `valid` is false for a degenerate or non-finite one, with
// the same threshold as trianglesIntersect (sin^2 of the angle at v0 below 1e-12).
struct Face {
  Vec v[3];
  Vec normal;
  bool valid = false;
};

Face makeFace(const Eigen::Vector3f (&t)[3]) {
  Face f;
  for (int i = 0; i < 3; ++i) f.v[i] = t[i].cast<double>();
  const Vec e1 = f.v[1] - f.v[0], e2 = f.v[2] - f.v[0];
  const Vec n = e1.cross(e2);
  const double n2 = n.squaredNorm();
  f.valid = std::isfinite(n2) && n2 > 1e-12 * e1.squaredNorm() * e2.squaredNorm();
  if (f.valid) f.normal = n / std::sqrt(n2);
  return f;
}

// True when p's projection along the face's normal falls on the face, its edges included (a vertex on a shared
// edge belongs to both faces; the contact reduction merges what that doubles).
bool projectsOntoFace(const Face& f, const Vec& p) {
  for (int i = 0; i < 3; ++i) {
    const Vec edge = f.v[(i + 1) % 3] - f.v[i];
    if (edge.cross(p - f.v[i]).dot(f.normal) < -1e-9 * edge.squaredNorm()) return false;
  }
  return true;
}

// True when one triangle lies wholly on one side of the other's plane such that no contact below can come:
// beyond `reach` in front of it or behind it (every contact is closer than reach), or behind it at all (a
// contact needs a point on the other's outer side; `behind` exceeds what the outer-side test's 1e-6 and the
// touching-edge case's 1e-7 of the size let through). Most candidates of two meshes with margins end here,
// before the vertex and edge tests.
bool separatedByAPlane(const Face& fa, const Face& fb, double reach) {
  double size2 = 0;
  for (int i = 0; i < 3; ++i) {
    size2 = std::max(
        {size2, (fa.v[(i + 1) % 3] - fa.v[i]).squaredNorm(), (fb.v[(i + 1) % 3] - fb.v[i]).squaredNorm()});
  }
  const double size = std::sqrt(size2), behind = 2e-6 * reach + 1e-6 * size;
  const auto apart = [&](const Face& of, const Face& plane) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec& v : of.v) {
      const double d = plane.normal.dot(v - plane.v[0]);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    return lo > reach + 1e-6 * size || hi < -behind;
  };
  return apart(fa, fb) || apart(fb, fa);
}

// Parameters of the closest points of the segments p0 + s u and q0 + t v, s and t in [0, 1]. The squared
// distance is a convex quadratic in (s, t): take the unconstrained minimum's s clamped, the best t for it, and
// if that t must be clamped, the best s for the clamped t. Parallel segments take s = 0.
void closestOnSegments(const Vec& p0, const Vec& u, const Vec& q0, const Vec& v, double& s, double& t) {
  const Vec w = p0 - q0;
  const double a = u.dot(u), b = u.dot(v), c = v.dot(v), d = u.dot(w), e = v.dot(w);
  const double denominator = a * c - b * b;
  s = denominator > 1e-12 * a * c ? std::clamp((b * e - c * d) / denominator, 0.0, 1.0) : 0.0;
  t = (b * s + e) / c;
  if (t < 0) {
    t = 0;
    s = std::clamp(-d / a, 0.0, 1.0);
  } else if (t > 1) {
    t = 1;
    s = std::clamp((b - d) / a, 0.0, 1.0);
  }
}

// A contact whose point on A is `onA`, on B `onA - normal * distance`. toWorld puts Bullet's point on B at
// deepestPoint - normalOnB * depth when onFaceOfB, else at deepestPoint.
TriangleContact contactFromA(const Vec& onA, const Vec& normalOnB, double distance) {
  TriangleContact c;
  c.point = (onA - 0.5 * distance * normalOnB).cast<float>();
  c.normalOnB = normalOnB.cast<float>();
  c.depth = float(distance);
  c.onFaceOfB = true;
  c.deepestPoint = onA.cast<float>();
  return c;
}

TriangleContact contactFromB(const Vec& onB, const Vec& normalOnB, double distance) {
  TriangleContact c;
  c.point = (onB + 0.5 * distance * normalOnB).cast<float>();
  c.normalOnB = normalOnB.cast<float>();
  c.depth = float(distance);
  c.onFaceOfB = false;
  c.deepestPoint = onB.cast<float>();
  return c;
}

}  // namespace

int proximityContacts(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3], float reach,
                      TriangleContact (&out)[kMaxProximityContacts], float speculativeFrom) {
  if (!(reach > 0)) return 0;
  const Face fa = makeFace(a), fb = makeFace(b);
  if (!fa.valid || !fb.valid) return 0;
  if (separatedByAPlane(fa, fb, reach)) return 0;
  // Each contact's point on A on B's outer side and its point on B on A's outer side: along the contact's
  // normal n (from B to A), n.nB >= 0 and n.nA <= 0 (within kSideTolerance).
  const auto outerSides = [&](const Vec& normal) {
    return normal.dot(fb.normal) >= -kSideTolerance && normal.dot(fa.normal) <= kSideTolerance;
  };
  int count = 0;
  // The smallest distance from a vertex to the other's face over it, on either side: when an edge pair is not
  // closer than this, the closest points are a vertex over a face, already given (or refused).
  double closestOverFace = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (!projectsOntoFace(fb, fa.v[i])) continue;
    const double d = fb.normal.dot(fa.v[i] - fb.v[0]);
    closestOverFace = std::min(closestOverFace, std::fabs(d));
    if (d >= 0 && d < reach && outerSides(fb.normal)) out[count++] = contactFromA(fa.v[i], fb.normal, d);
  }
  for (int i = 0; i < 3; ++i) {
    if (!projectsOntoFace(fa, fb.v[i])) continue;
    const double d = fa.normal.dot(fb.v[i] - fa.v[0]);
    closestOverFace = std::min(closestOverFace, std::fabs(d));
    if (d >= 0 && d < reach && outerSides(-fa.normal)) out[count++] = contactFromB(fb.v[i], -fa.normal, d);
  }

  double best = std::numeric_limits<double>::infinity();
  Vec bestA = Vec::Zero(), bestB = Vec::Zero();
  double size = 0;
  for (int i = 0; i < 3; ++i) {
    const Vec u = fa.v[(i + 1) % 3] - fa.v[i];
    size = std::max(size, u.norm());
    for (int j = 0; j < 3; ++j) {
      const Vec v = fb.v[(j + 1) % 3] - fb.v[j];
      size = std::max(size, v.norm());
      double s, t;
      closestOnSegments(fa.v[i], u, fb.v[j], v, s, t);
      const Vec pa = fa.v[i] + s * u, pb = fb.v[j] + t * v;
      const double d2 = (pa - pb).squaredNorm();
      if (d2 < best) best = d2, bestA = pa, bestB = pb;
    }
  }
  const double distance = std::sqrt(best);
  if (!(distance < reach) || !(distance < closestOverFace * (1 - 1e-6))) return count;
  // Touching edges (the exact test may call a pair within about 1e-6 of its size either way) have no
  // direction between their points: B's face normal stands in. Speculative contacts of edges that nearly
  // touch take the face whose plane has the other triangle wholly on its outer side (a box's edge at a
  // floor's edge gets the floor's normal, not a sideways one), and none when neither face separates them.
  Vec normal = distance > 1e-7 * size ? Vec((bestA - bestB) / distance) : fb.normal;
  if (distance >= speculativeFrom && distance < 1e-3 * size) {
    const auto outside = [&](const Face& of, const Face& plane) {
      for (const Vec& v : of.v) {
        if (plane.normal.dot(v - plane.v[0]) < -1e-6 * size) return false;
      }
      return true;
    };
    if (outside(fb, fa)) {
      normal = -fa.normal;
    } else if (outside(fa, fb)) {
      normal = fb.normal;
    } else {
      return count;
    }
  }
  if (outerSides(normal)) out[count++] = contactFromA(bestA, normal, distance);
  return count;
}

}  // namespace gpucol
