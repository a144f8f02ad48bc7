#pragma once

// Helpers of the numerical stability tests: shapes over meshes built in place, meshes scaled in double,
// a double-precision reference of the documented contact rule (narrowphase/triangle_contact.h), and one
// check of a mesh pair query against the double brute force of bullet/mesh_pair_test_util.h.

#include <LinearMath/btTransform.h>
#include <gpucol/gpucol.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bullet/mesh_pair_test_util.h"
#include "narrowphase/reference_triangles.h"

namespace gpucol::test {

/// A MeshShape over a mesh built in place.
inline std::shared_ptr<MeshShape> stressShape(TriangleMesh mesh) {
  return std::make_shared<MeshShape>(std::make_shared<const TriangleMesh>(std::move(mesh)));
}

/// `mesh` with every coordinate multiplied by `scale` in double and rounded once to float.
inline TriangleMesh scaledMesh(const TriangleMesh& mesh, double scale) {
  std::vector<float> xyz(mesh.positions().size());
  for (std::size_t i = 0; i < xyz.size(); ++i) xyz[i] = float(double(mesh.positions()[i]) * scale);
  return TriangleMesh::fromArrays(std::move(xyz), mesh.indices(), mesh.name() + " scaled");
}

/// True when every contact (reduced ones included) has finite points, normal and depth.
inline bool allFinite(const MeshPairResult& r) {
  auto finite = [](const MeshContact& c) {
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(c.pointWorld[i]) || !std::isfinite(c.pointOnBWorld[i]) ||
          !std::isfinite(c.normalWorldOnB[i]))
        return false;
    }
    return std::isfinite(c.depth);
  };
  return std::all_of(r.contacts.begin(), r.contacts.end(), finite) &&
         std::all_of(r.reducedContacts.begin(), r.reducedContacts.end(), finite);
}

/// The contact rule of generateContact (triangle_contact.h), written again from its documentation in
/// double on world triangles: A's move along nB and B's move along nA until each is out of the other's
/// plane, the smaller wins (ties to A). `dropped` when the triangles slide apart along their intersection
/// line by less than the move. Only meaningful for intersecting, non-coplanar pairs.
struct ReferenceContact {
  double moveA = 0;        ///< Distance A must move along nB.
  double moveB = 0;        ///< Distance B must move along nA.
  double slide = 0;        ///< Overlap of the projections of the whole triangles on the line direction.
  Eigen::Vector3d nA, nB;  ///< Unit outward normals.
};

/// Computes the quantities of the rule above.
inline ReferenceContact referenceContact(const TriangleD& a, const TriangleD& b) {
  ReferenceContact r;
  r.nA = (a[1] - a[0]).cross(a[2] - a[0]).normalized();
  r.nB = (b[1] - b[0]).cross(b[2] - b[0]).normalized();
  double lowestA = 0, lowestB = 0;
  for (int i = 0; i < 3; ++i) {
    lowestA = std::min(lowestA, r.nB.dot(a[i] - b[0]));
    lowestB = std::min(lowestB, r.nA.dot(b[i] - a[0]));
  }
  r.moveA = -lowestA;
  r.moveB = -lowestB;
  const Eigen::Vector3d line = r.nA.cross(r.nB);
  if (line.norm() > 0) {
    const Eigen::Vector3d u = line.normalized();
    double loA = 1e300, hiA = -1e300, loB = 1e300, hiB = -1e300;
    for (int i = 0; i < 3; ++i) {
      loA = std::min(loA, u.dot(a[i])), hiA = std::max(hiA, u.dot(a[i]));
      loB = std::min(loB, u.dot(b[i])), hiB = std::max(hiB, u.dot(b[i]));
    }
    r.slide = std::min(hiA - loB, hiB - loA);
  }
  return r;
}

/// For each edge k of triangle `t` (corner k to k + 1), the far vertex (in the world) of the one triangle of
/// the shape that runs the same edge the other way, by brute force over the mesh (equal positions), and
/// whether the edge is a diagonal of a flat face (the far vertex within 1e-4 of the edge's length of the
/// triangle's plane in the mesh's own coordinates). None when no triangle or more than one shares the edge,
/// or one runs it the same way.
struct ReferenceWings {
  FlatWings far;
  std::array<bool, 3> flat{};
};
inline ReferenceWings referenceWings(const MeshShape& shape, const btTransform& transform, std::uint32_t t) {
  const TriangleMesh& mesh = shape.mesh();
  const auto vertex = [&](std::uint32_t triangle, int corner) {
    const float* p =
        mesh.positions().data() + 3 * std::size_t(mesh.indices()[3 * std::size_t(triangle) + corner]);
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  const Eigen::Vector3d own[3] = {vertex(t, 0), vertex(t, 1), vertex(t, 2)};
  const Eigen::Vector3d normal = (own[1] - own[0]).cross(own[2] - own[0]).normalized();
  ReferenceWings wings;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& p = own[k];
    const Eigen::Vector3d& q = own[(k + 1) % 3];
    int sharing = 0;
    bool reversed = false;
    std::uint32_t farTriangle = 0;
    int farCorner = 0;
    for (std::uint32_t j = 0; j < mesh.triangleCount(); ++j) {
      if (j == t) continue;
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector3d a = vertex(j, e), b = vertex(j, (e + 1) % 3);
        if ((a == p && b == q) || (a == q && b == p)) {
          ++sharing;
          reversed = a == q;
          farTriangle = j;
          farCorner = (e + 2) % 3;
        }
      }
    }
    if (sharing != 1 || !reversed) continue;
    wings.flat[std::size_t(k)] =
        std::abs(normal.dot(vertex(farTriangle, farCorner) - p)) <= 1e-4 * (q - p).norm();
    wings.far[std::size_t(k)] = worldTriangle(shape, transform, farTriangle)[farCorner];
  }
  return wings;
}

/// The far vertices of referenceWings across the edges of `t` that are diagonals of a flat face (`flat`), and
/// across those that are convex (`convex`: not flat, the far vertex behind the triangle's plane in the world).
struct SplitWings {
  FlatWings flat, convex;
};
inline SplitWings referenceSplitWings(const MeshShape& shape, const btTransform& transform, std::uint32_t t) {
  const ReferenceWings wings = referenceWings(shape, transform, t);
  const TriangleD own = worldTriangle(shape, transform, t);
  const Eigen::Vector3d normal = (own[1] - own[0]).cross(own[2] - own[0]);
  SplitWings out;
  for (std::size_t k = 0; k < 3; ++k) {
    if (wings.flat[k]) {
      out.flat[k] = wings.far[k];
    } else if (wings.far[k] && normal.dot(*wings.far[k] - own[k]) < 0) {
      out.convex[k] = wings.far[k];
    }
  }
  return out;
}

/// What checkQuery counted.
struct QueryCheck {
  std::size_t clearlyIntersecting = 0;  ///< Brute-force pairs penetrating by more than the band.
  std::size_t missedCandidates = 0;     ///< Touching or intersecting pairs the middle phase lost.
  std::size_t missedIntersecting = 0;   ///< Clearly intersecting pairs not reported.
  std::size_t falseIntersecting = 0;    ///< Reported pairs farther apart than the band.
  std::size_t contactsChecked = 0;      ///< Contacts compared with the reference rule.
  double worstDepthError = 0;           ///< Largest |depth - reference| / pair scale.
  double worstNormalError = 0;          ///< Largest |normal - reference normal|.
  double worstPointDistance = 0;        ///< Largest distance of a contact point from either triangle / scale.
};

/// Checks `result` (collideMeshes of the same arguments) against the double brute force: candidates hold
/// every touching or intersecting pair, intersecting pairs agree outside the relative band `band`, and every
/// contact agrees with the reference rule: its normal that of the winning move, its depth between 0 and the
/// deepest corner of the winner's overlap (referenceClippedMove) and each pair's deepest contact at that
/// corner's depth, its point on both triangles or a corner of the moving triangle moved halfway out.
/// `absolutePoint` is added to the point tolerance (the float rounding of world coordinates far from the
/// origin). Tolerances: depth and point `contactTolerance` of the pair's size, normal `contactTolerance`
/// (unit vectors); pairs whose two moves tie within the tolerance may take either normal.
inline QueryCheck checkQuery(const MeshShape& a, const btTransform& ta, const MeshShape& b,
                             const btTransform& tb, const MeshPairResult& result, double band,
                             double contactTolerance, double absolutePoint = 0) {
  QueryCheck check;
  const std::set<TrianglePair> candidates(result.candidatePairs.begin(), result.candidatePairs.end());
  const std::set<TrianglePair> intersecting(result.intersectingPairs.begin(), result.intersectingPairs.end());
  std::set<TrianglePair> nearPairs;
  for (const BruteForcePair& p : bruteForceNearPairs(a, ta, b, tb, band)) {
    nearPairs.insert(p.pair);
    if (p.separation <= 0 && !candidates.count(p.pair)) ++check.missedCandidates;
    if (p.separation < -band * p.scale) {
      ++check.clearlyIntersecting;
      if (!intersecting.count(p.pair)) ++check.missedIntersecting;
    }
  }
  for (const TrianglePair& p : result.intersectingPairs) check.falseIntersecting += nearPairs.count(p) == 0;

  std::map<TrianglePair, double> deepestOfPair;
  for (const MeshContact& c : result.contacts) {
    const TriangleD triA = worldTriangle(a, ta, c.triangleA), triB = worldTriangle(b, tb, c.triangleB);
    const double scale = pairScale(triA, triB);
    const Eigen::Vector3d point(c.pointWorld.x(), c.pointWorld.y(), c.pointWorld.z());
    const Eigen::Vector3d normal(c.normalWorldOnB.x(), c.normalWorldOnB.y(), c.normalWorldOnB.z());
    const ReferenceContact ref = referenceContact(triA, triB);
    const double tie = contactTolerance * scale;
    const bool aMayMove = ref.moveA <= ref.moveB + tie, bMayMove = ref.moveB <= ref.moveA + tie;
    // The winner's contacts are at the corners of the part of it over the other triangle that dip in: the
    // deepest at the middle of the pair's common segment (on both triangles), the others at their corner
    // moved halfway out.
    double pointDistance = std::max(pointTriangleDistance(point, triA), pointTriangleDistance(point, triB));
    double depthError = 1e300, normalError = 1e300;
    const auto byCorners = [&](const TriangleD& moving, const TriangleD& fixed, const Eigen::Vector3d& out,
                               const SplitWings& wings) {
      // No deeper than the overlap's deepest corner, and not above the plane. (A corner where the moving
      // triangle's edge meets a side at a grazing angle is ill-conditioned: its own depth is not compared.)
      const double deepest = referenceClippedMove(moving, fixed, out, wings.flat, wings.convex);
      depthError = std::min(depthError, std::max({0.0, -double(c.depth) - deepest, double(c.depth)}));
      const Eigen::Vector3d corner = point + out * (0.5 * double(c.depth));
      pointDistance = std::min(pointDistance, pointTriangleDistance(corner, moving));
    };
    if (aMayMove) {
      byCorners(triA, triB, ref.nB, referenceSplitWings(b, tb, c.triangleB));
      normalError = std::min(normalError, (normal - ref.nB).norm());
    }
    if (bMayMove) {
      byCorners(triB, triA, ref.nA, referenceSplitWings(a, ta, c.triangleA));
      normalError = std::min(normalError, (normal + ref.nA).norm());
    }
    check.worstPointDistance =
        std::max(check.worstPointDistance, std::max(0.0, pointDistance - absolutePoint) / scale);
    check.worstDepthError = std::max(check.worstDepthError, depthError / scale);
    check.worstNormalError = std::max(check.worstNormalError, normalError);
    ++check.contactsChecked;
    const TrianglePair pair{c.triangleA, c.triangleB};
    const auto held = deepestOfPair.find(pair);
    if (held == deepestOfPair.end() || c.depth < held->second) deepestOfPair[pair] = c.depth;
  }
  // Each pair's deepest contact at its overlap's deepest corner.
  for (const auto& [pair, depth] : deepestOfPair) {
    const TriangleD triA = worldTriangle(a, ta, pair.triangleA), triB = worldTriangle(b, tb, pair.triangleB);
    const double scale = pairScale(triA, triB);
    const ReferenceContact ref = referenceContact(triA, triB);
    const double tie = contactTolerance * scale;
    double error = 1e300;
    if (ref.moveA <= ref.moveB + tie) {
      const SplitWings wingsB = referenceSplitWings(b, tb, pair.triangleB);
      error = std::min(error, std::abs(depth + referenceClippedMove(triA, triB, ref.nB, wingsB.flat, wingsB.convex)));
    }
    if (ref.moveB <= ref.moveA + tie) {
      const SplitWings wingsA = referenceSplitWings(a, ta, pair.triangleA);
      error = std::min(error, std::abs(depth + referenceClippedMove(triB, triA, ref.nA, wingsA.flat, wingsA.convex)));
    }
    check.worstDepthError = std::max(check.worstDepthError, error / scale);
  }
  return check;
}

/// The assertions every stress scene makes on a QueryCheck (see checkQuery for the tolerances).
inline void expectAgrees(const QueryCheck& c, double contactTolerance, const std::string& where) {
  EXPECT_EQ(c.missedCandidates, 0u) << where << ": touching or intersecting pairs lost by the middle phase";
  EXPECT_EQ(c.missedIntersecting, 0u) << where << ": clearly intersecting pairs not reported";
  EXPECT_EQ(c.falseIntersecting, 0u) << where << ": reported pairs farther apart than the band";
  EXPECT_LE(c.worstDepthError, contactTolerance) << where << ": contact depth off the reference rule";
  EXPECT_LE(c.worstNormalError, contactTolerance) << where << ": contact normal off the reference rule";
  EXPECT_LE(c.worstPointDistance, contactTolerance) << where << ": contact point off a triangle";
}

/// Smallest angle of a triangle (radians), in double.
inline double smallestAngle(const TriangleD& t) {
  double smallest = M_PI;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e1 = t[(i + 1) % 3] - t[i], e2 = t[(i + 2) % 3] - t[i];
    const double n1 = e1.norm(), n2 = e2.norm();
    if (n1 == 0 || n2 == 0) return 0;
    smallest = std::min(smallest, std::atan2(e1.cross(e2).norm(), e1.dot(e2)));
  }
  return smallest;
}

}  // namespace gpucol::test
