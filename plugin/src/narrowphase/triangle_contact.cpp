#include "narrowphase/triangle_contact.h"

#include <algorithm>
#include <cmath>

#include "narrowphase/triangle_plane.h"
#include "narrowphase/triangle_proximity.h"
#include "shared_math/triangle_test.h"

namespace gpucol {
namespace {

// A corner of the overlap deeper behind the face across a convex edge of the fixed triangle than this share
// of the fixed triangle's size is not pushed out along the fixed face's normal beyond that depth and this
// share: the face across (another pair's contact) answers for it. A box corner just inside another box's
// bottom face lies a whole box side behind its side face; pushed out along the side's normal it was a contact
// 0.28 m deep between boxes that touched. Nearer the edge, as at the rim of a face overhanging another, the
// corner keeps its depth along the fixed face.
constexpr double kConvexWingSlack = 0.05;

}  // namespace

std::optional<TriangleContact> generateContact(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3]) {
  bool intersects = false;
  return detail::generateContactAndTest(a, b, intersects);
}

int clipContactToOverlap(const Eigen::Vector3f (&a)[3], const Eigen::Vector3f (&b)[3],
                         const EdgeWings& flatWings, const EdgeWings& otherWings, TriangleContact& contact,
                         TriangleContact (&corners)[kMaxOverlapCorners]) {
  if (!(contact.depth < 0)) return 0;
  // The moving triangle leaves the fixed one's plane along `out`: B's normal when A moves, A's when B does.
  // Everything relative to the fixed triangle's first vertex, in double.
  const Eigen::Vector3f(&moving)[3] = contact.onFaceOfB ? a : b;
  const Eigen::Vector3f(&fixed)[3] = contact.onFaceOfB ? b : a;
  const Eigen::Vector3d out =
      (contact.onFaceOfB ? contact.normalOnB : Eigen::Vector3f(-contact.normalOnB)).cast<double>();
  const Eigen::Vector3d origin = fixed[0].cast<double>();
  const Eigen::Vector3d f[3] = {Eigen::Vector3d::Zero(), fixed[1].cast<double>() - origin,
                                fixed[2].cast<double>() - origin};
  // The region over the fixed face: the prism of the fixed triangle along `out`, each side a plane through an
  // edge that contains `out`, turned towards the triangle. At a flat diagonal (a wing given) the face goes
  // on: the two far sides of the triangle across it stand for that edge, so that the two triangles of a flat
  // quad share one region. Each side is moved out by 1e-5 of the triangle's size: a moving face that lies in
  // it (the sides of two boxes stacked flush) is kept whole rather than cut by rounding. A side keeps p where
  // side.dot(p) >= limit.
  const double size =
      std::sqrt(std::max({f[1].squaredNorm(), (f[2] - f[1]).squaredNorm(), f[2].squaredNorm()}));
  Eigen::Vector3d sides[6];
  double limits[6];
  int planes = 0;
  const auto addSide = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                           const Eigen::Vector3d& inner) {
    Eigen::Vector3d side = out.cross(to - from);
    if (side.dot(inner - from) < 0) side = -side;
    sides[planes] = side;
    limits[planes++] = side.dot(from) - 1e-5 * size * side.norm();
  };
  // The two far sides bound the two triangles together only where they make a convex quad: the far vertex
  // lies across the edge from the triangle's own third vertex, and that third vertex on the inner side of
  // both far sides. Where they do not (two triangles of a flat face meeting at its inner corner: an L's cap,
  // a bin's rim at a corner), the far sides would cut away part of the triangle itself, and the edge bounds
  // the region as any other does.
  const auto convexAcross = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& w,
                                const Eigen::Vector3d& to, const Eigen::Vector3d& third) {
    // The sides of `third` and of `other` from the line p -> q, seen along `out`: positive when the same.
    const auto sameSide = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& other) {
      const Eigen::Vector3d normal = out.cross(q - p);
      return normal.dot(other - p) * normal.dot(third - p);
    };
    return sameSide(from, to, w) < 0 && sameSide(from, w, to) >= 0 && sameSide(w, to, from) >= 0;
  };
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& from = f[k];
    const Eigen::Vector3d& to = f[(k + 1) % 3];
    const Eigen::Vector3d& third = f[(k + 2) % 3];
    const Eigen::Vector3f& wing = flatWings.across[k];
    const Eigen::Vector3d w = wing.cast<double>() - origin;
    if (wing.allFinite() && convexAcross(from, w, to, third)) {
      addSide(from, w, to);
      addSide(w, to, from);
    } else {
      addSide(from, to, third);
    }
  }
  // Sutherland-Hodgman against each side.
  Eigen::Vector3d polygon[kMaxOverlapCorners + 1], clipped[kMaxOverlapCorners + 1];
  int count = 3;
  for (int k = 0; k < 3; ++k) polygon[k] = moving[k].cast<double>() - origin;
  for (int k = 0; k < planes && count > 0; ++k) {
    double distance[kMaxOverlapCorners + 1];
    bool allInside = true;
    for (int i = 0; i < count; ++i) {
      distance[i] = sides[k].dot(polygon[i]) - limits[k];
      allInside &= distance[i] >= 0;
    }
    if (allInside) continue;
    int kept = 0;
    for (int i = 0; i < count; ++i) {
      const int j = i + 1 == count ? 0 : i + 1;
      const double dp = distance[i], dq = distance[j];
      if (dp >= 0) clipped[kept++] = polygon[i];
      if ((dp >= 0) != (dq >= 0)) clipped[kept++] = polygon[i] + (polygon[j] - polygon[i]) * (dp / (dp - dq));
    }
    count = kept;
    for (int i = 0; i < count; ++i) polygon[i] = clipped[i];
  }
  // An empty polygon is rounding at a grazing pair (the triangles cross, so their common segment is over
  // the fixed triangle): the contact stays as it was.
  if (count == 0) return 0;
  // Convex edges of the fixed triangle (their wing behind its plane): the solid near it lies behind the face
  // across them too, so a corner's depth is bounded by how far it lies behind that face (kConvexWingSlack).
  Eigen::Vector3d wingNormals[3];
  Eigen::Vector3d wingFrom[3];
  int convex = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3f& wing = otherWings.across[k];
    if (!wing.allFinite()) continue;
    const Eigen::Vector3d w = wing.cast<double>() - origin;
    const Eigen::Vector3d& from = f[k];
    const Eigen::Vector3d& to = f[(k + 1) % 3];
    const Eigen::Vector3d& third = f[(k + 2) % 3];
    if (!(out.dot(w - from) < -1e-6 * size)) continue;  // not convex
    Eigen::Vector3d n = (to - from).cross(w - from);
    if (n.dot(third - from) > 0) n = -n;
    const double len = n.norm();
    if (!(len > 0)) continue;
    wingNormals[convex] = n / len;
    wingFrom[convex++] = from;
  }
  const double slack = kConvexWingSlack * size;
  const auto depthBelow = [&](const Eigen::Vector3d& p) {
    double below = -out.dot(p);
    for (int k = 0; k < convex; ++k) below = std::min(below, -wingNormals[k].dot(p - wingFrom[k]) + slack);
    return below;
  };
  double deepest = 0;
  int at = -1;
  for (int i = 0; i < count; ++i) {
    const double below = depthBelow(polygon[i]);
    if (below > deepest) {
      deepest = below;
      at = i;
    }
  }
  if (at < 0) {
    contact.depth = 0;
    contact.deepestPoint = contact.point;
    return 0;
  }
  // The other corners below the plane, each with its own depth, at the corner moved halfway out.
  int more = 0;
  for (int i = 0; i < count; ++i) {
    const double below = depthBelow(polygon[i]);
    if (i == at || !(below > 0)) continue;
    TriangleContact& corner = corners[more++];
    corner = contact;
    corner.depth = -static_cast<float>(below);
    corner.deepestPoint = (polygon[i] + origin).cast<float>();
    corner.point = (polygon[i] + origin + out * (0.5 * below)).cast<float>();
  }
  contact.depth = -static_cast<float>(deepest);
  contact.deepestPoint = (polygon[at] + origin).cast<float>();
  return more;
}

namespace detail {

std::optional<TriangleContact> generateContactAndTest(const Eigen::Vector3f (&af)[3],
                                                      const Eigen::Vector3f (&bf)[3], bool& intersects) {
  // Double arithmetic on the float input (see triangle_plane.h); the test and the rule are
  // gpucol_triangle_contact's (thesis §5.3.4 runs Möller's test, §3.5, before generating contacts).
  double a[3][3], b[3][3];
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) {
      a[v][k] = af[v][k];
      b[v][k] = bf[v][k];
    }
  }
  const GpucolContact r = gpucol_triangle_contact(a, b);
  intersects = r.intersects != 0;
  if (!r.contact) return std::nullopt;
  auto toFloat = [](const double(&v)[3]) {
    return Eigen::Vector3f(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
  };
  return TriangleContact{toFloat(r.point), toFloat(r.normalOnB), static_cast<float>(r.depth),
                         r.onFaceOfB != 0, r.sameFacing != 0,    toFloat(r.deepest)};
}

}  // namespace detail

}  // namespace gpucol
