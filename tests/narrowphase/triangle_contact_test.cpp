#include "narrowphase/triangle_contact.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <random>

#include "narrowphase/triangle_intersection.h"
#include "narrowphase/triangle_plane.h"
#include "narrowphase/triangle_proximity.h"
#include "random_triangles.h"
#include "reference_triangles.h"

namespace gpucol {
namespace {

using test::PairFamily;
using test::TriangleD;
using test::TriangleF;

std::optional<TriangleContact> contactOf(const TriangleF& a, const TriangleF& b) {
  const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]};
  const Eigen::Vector3f pb[3] = {b[0], b[1], b[2]};
  return generateContact(pa, pb);
}

/// The near phase takes "intersects" from the contact generation instead of running trianglesIntersect as
/// well: the two must agree on every pair, and the contact must be generateContact's, bit for bit.
TEST(TriangleContact, ContactAndTestAgreesWithTrianglesIntersect) {
  std::mt19937_64 rng(11);
  long intersecting = 0, withContact = 0;
  for (int f = 0; f < static_cast<int>(PairFamily::Count); ++f) {
    for (int i = 0; i < 20000; ++i) {
      TriangleF a, b;
      test::randomPair(static_cast<PairFamily>(f), rng, a, b);
      const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]};
      const Eigen::Vector3f pb[3] = {b[0], b[1], b[2]};
      bool intersects = true;
      const std::optional<TriangleContact> c = detail::generateContactAndTest(pa, pb, intersects);
      ASSERT_EQ(intersects, trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]))
          << test::familyName(static_cast<PairFamily>(f)) << " pair " << i;
      const std::optional<TriangleContact> expected = generateContact(pa, pb);
      ASSERT_EQ(c.has_value(), expected.has_value());
      if (c) {
        EXPECT_EQ(c->point, expected->point);
        EXPECT_EQ(c->normalOnB, expected->normalOnB);
        EXPECT_EQ(c->depth, expected->depth);
      }
      intersecting += intersects;
      withContact += c.has_value();
    }
  }
  // Both answers occur, and some intersecting pairs have their contact dropped, so each branch was compared.
  EXPECT_GT(intersecting, 10000);
  EXPECT_GT(intersecting, withContact);
}

/// The §5.3.4 contact computed again in double, straight from its definition, for non-coplanar
/// intersecting pairs: how far each triangle must move along the other's normal, the slide along the
/// intersection line, and the common segment found by clipping each triangle's edges with the other plane.
struct ReferenceContact {
  double moveA = 0, moveB = 0, slide = 0;
  Eigen::Vector3d normalOnB, point;
  double depth = 0;
  double segmentLength = 0;
};

ReferenceContact referenceContact(const TriangleD& a, const TriangleD& b) {
  const Eigen::Vector3d nA = (a[1] - a[0]).cross(a[2] - a[0]).normalized();
  const Eigen::Vector3d nB = (b[1] - b[0]).cross(b[2] - b[0]).normalized();
  ReferenceContact r;
  for (int i = 0; i < 3; ++i) {
    r.moveA = std::max(r.moveA, -nB.dot(a[i] - b[0]));
    r.moveB = std::max(r.moveB, -nA.dot(b[i] - a[0]));
  }
  r.normalOnB = r.moveA <= r.moveB ? nB : Eigen::Vector3d(-nA);
  r.depth = -std::min(r.moveA, r.moveB);
  const Eigen::Vector3d u = nA.cross(nB).normalized();
  double loA = 1e300, hiA = -1e300, loB = 1e300, hiB = -1e300;
  for (int i = 0; i < 3; ++i) {
    loA = std::min(loA, u.dot(a[i])), hiA = std::max(hiA, u.dot(a[i]));
    loB = std::min(loB, u.dot(b[i])), hiB = std::max(hiB, u.dot(b[i]));
  }
  r.slide = std::min(hiA - loB, hiB - loA);
  // Each triangle's crossing of the other plane: the points where its edges change side.
  auto crossing = [&u](const TriangleD& t, const Eigen::Vector3d& n, const Eigen::Vector3d& p, double& lo,
                       double& hi) {
    lo = 1e300, hi = -1e300;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& s = t[i];
      const Eigen::Vector3d& e = t[(i + 1) % 3];
      const double ds = n.dot(s - p), de = n.dot(e - p);
      if ((ds <= 0 && de >= 0) || (ds >= 0 && de <= 0)) {
        const Eigen::Vector3d x = ds == de ? s : Eigen::Vector3d(s + (e - s) * (ds / (ds - de)));
        lo = std::min(lo, u.dot(x)), hi = std::max(hi, u.dot(x));
      }
    }
  };
  double loSA, hiSA, loSB, hiSB;
  crossing(a, nB, b[0], loSA, hiSA);
  crossing(b, nA, a[0], loSB, hiSB);
  const double lo = std::max(loSA, loSB), hi = std::min(hiSA, hiSB);
  r.segmentLength = hi - lo;
  // The line itself: the point of both planes closest to a[0], then along u.
  const double cA = nA.dot(a[0]), cB = nB.dot(b[0]);
  const double k = nA.dot(nB);
  const double alpha = (cA - k * cB) / (1 - k * k), beta = (cB - k * cA) / (1 - k * k);
  const Eigen::Vector3d onLine = alpha * nA + beta * nB;
  r.point = onLine + u * (0.5 * (lo + hi) - u.dot(onLine));
  return r;
}

/// A triangle of a box's top face (z = 0, outward +z) pierced from above by a tilted triangle whose lowest
/// vertex is d below the face: depth -d along the face normal; swapping A and B flips the normal.
TEST(TriangleContact, BoxTopFacePenetratedByDepthD) {
  const Eigen::Vector3f face[3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  for (float d : {0.0f, 0.001f, 0.05f, 0.1f, 0.2f}) {
    const Eigen::Vector3f pusher[3] = {{0.5f, 0.5f, -d}, {0.5f, 1.5f, 1}, {1.5f, 0.5f, 1}};
    ASSERT_TRUE(trianglesIntersect(pusher[0], pusher[1], pusher[2], face[0], face[1], face[2]));
    const std::optional<TriangleContact> c = generateContact(pusher, face);
    ASSERT_TRUE(c.has_value()) << "d = " << d;
    EXPECT_NEAR(c->depth, -d, 1e-6f);
    EXPECT_NEAR((c->normalOnB - Eigen::Vector3f(0, 0, 1)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR(c->point.z(), 0.0f, 1e-6f);  // on the face, and on the pusher (checked below)
    test::TriangleD da = test::toDouble({pusher[0], pusher[1], pusher[2]});
    test::TriangleD db = test::toDouble({face[0], face[1], face[2]});
    EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), da), 1e-6);
    EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), db), 1e-6);

    const std::optional<TriangleContact> swapped = generateContact(face, pusher);
    ASSERT_TRUE(swapped.has_value());
    EXPECT_NEAR(swapped->depth, -d, 1e-6f);
    EXPECT_NEAR((swapped->normalOnB - Eigen::Vector3f(0, 0, -1)).norm(), 0.0f, 1e-6f);
    EXPECT_NEAR((swapped->point - c->point).norm(), 0.0f, 1e-6f);
  }
}

EdgeWings noWings() {
  EdgeWings wings;
  for (Eigen::Vector3f& wing : wings.across) wing.setConstant(std::numeric_limits<float>::quiet_NaN());
  return wings;
}

/// The faces of two crossed rods: A's top face triangle runs along x (0.8 by 0.08), B's bottom face triangle
/// along z (0.08 wide in x), sloping down through A's plane over A. A moves less; the thesis's rule takes A's
/// corner at x = 0.4, far beyond B's side, 0.015 deep; over B, A is only about 0.005 deep, and the clipped
/// contact says so, at a point of A over B.
TEST(TriangleContact, CrossedRodFacesMeetWhereTheyOverlap) {
  const Eigen::Vector3f top[3] = {{-0.4f, 0, -0.04f}, {0.4f, 0, 0.04f}, {0.4f, 0, -0.04f}};
  // B's plane: y = -0.25 (z + 0.02), facing down.
  const Eigen::Vector3f bottom[3] = {
      {-0.04f, 0.095f, -0.4f}, {0.04f, -0.005f, 0.0f}, {-0.04f, -0.105f, 0.4f}};
  const std::optional<TriangleContact> c = generateContact(top, bottom);
  ASSERT_TRUE(c.has_value());
  ASSERT_TRUE(c->onFaceOfB);
  EXPECT_NEAR(c->deepestPoint.x(), 0.4f, 1e-6f);
  TriangleContact clipped = *c;
  TriangleContact corners[kMaxOverlapCorners];
  const int more = clipContactToOverlap(top, bottom, noWings(), noWings(), clipped, corners);
  EXPECT_EQ(clipped.normalOnB, c->normalOnB);
  EXPECT_EQ(clipped.point, c->point);
  // Every corner of the overlap that dips in is held, over B.
  ASSERT_GE(more, 1);
  for (int k = 0; k < more; ++k) {
    EXPECT_LT(corners[k].depth, 0);
    EXPECT_GE(corners[k].depth, clipped.depth);
    EXPECT_LE(std::abs(corners[k].deepestPoint.x()), 0.04f + 1e-5f);
  }
  EXPECT_GT(clipped.depth, c->depth + 0.005f);
  EXPECT_LT(clipped.depth, 0);
  const TriangleD da = test::toDouble({top[0], top[1], top[2]});
  const TriangleD db = test::toDouble({bottom[0], bottom[1], bottom[2]});
  EXPECT_LT(test::pointTriangleDistance(clipped.deepestPoint.cast<double>(), da), 1e-6);
  EXPECT_NEAR(clipped.depth, -test::referenceClippedMove(da, db, clipped.normalOnB.cast<double>()), 1e-6);
  EXPECT_LE(std::abs(clipped.deepestPoint.x()), 0.04f + 1e-5f);
}

/// Random crossing pairs: the contact and the corners' contacts are the double reference's corners of the
/// overlap below the plane (every one of them, the deepest in the contact), on the moving triangle, between
/// the unclipped depth and 0; with a flat neighbour across an edge of the fixed triangle the region goes on
/// over it.
TEST(TriangleContact, ClippedToOverlapMatchesTheDoubleReference) {
  std::mt19937_64 rng(11);
  int compared = 0, changed = 0, flatCompared = 0, cornerContacts = 0;
  for (int i = 0; i < 20000; ++i) {
    TriangleF a, b;
    test::randomPair(PairFamily::General, rng, a, b);
    const Eigen::Vector3f pa[3] = {a[0], a[1], a[2]}, pb[3] = {b[0], b[1], b[2]};
    const std::optional<TriangleContact> c = generateContact(pa, pb);
    if (!c || !(c->depth < 0)) continue;
    const TriangleD da = test::toDouble(a), db = test::toDouble(b);
    const double scale = test::pairScale(da, db);
    const double tolerance = 1e-5 * scale;
    // Half the pairs get a flat neighbour across edge 0 of each triangle: the edge's mirror image of the
    // third vertex, in the plane (a convex quad), or, for every other one of those, a far vertex beyond the
    // edge's first end, just across the edge's line (the two make a quad that is not convex there, as two
    // triangles meeting at the inner corner of an L's cap do).
    const bool flat = i % 2 == 1;
    const bool reflex = i % 4 == 3;
    EdgeWings wingsA = noWings(), wingsB = noWings();
    test::FlatWings flatA, flatB;
    if (flat) {
      const auto mirror = [&](const TriangleF& t) {
        const Eigen::Vector3f mid = 0.5f * (t[0] + t[1]);
        if (reflex) return Eigen::Vector3f(t[0] + 2.0f * (t[0] - t[1]) + 0.2f * (mid - t[2]));
        return Eigen::Vector3f(2.0f * mid - t[2]);
      };
      wingsA.across[0] = mirror(a);
      wingsB.across[0] = mirror(b);
      flatA[0] = wingsA.across[0].cast<double>();
      flatB[0] = wingsB.across[0].cast<double>();
    }
    TriangleContact clipped = *c;
    TriangleContact corners[kMaxOverlapCorners];
    const int more =
        clipContactToOverlap(pa, pb, c->onFaceOfB ? wingsB : wingsA, noWings(), clipped, corners);
    const TriangleD& moving = c->onFaceOfB ? da : db;
    const TriangleD& fixed = c->onFaceOfB ? db : da;
    const Eigen::Vector3d out = (c->onFaceOfB ? c->normalOnB : Eigen::Vector3f(-c->normalOnB)).cast<double>();
    const std::vector<test::OverlapCorner> reference =
        test::referenceOverlapCorners(moving, fixed, out, c->onFaceOfB ? flatB : flatA);
    ++compared;
    flatCompared += flat;
    changed += clipped.depth != c->depth;
    cornerContacts += more;
    EXPECT_NEAR(clipped.depth, -test::referenceClippedMove(moving, fixed, out, c->onFaceOfB ? flatB : flatA),
                tolerance)
        << "pair " << i;
    EXPECT_GE(clipped.depth, c->depth - 1e-6f * float(scale)) << "pair " << i;
    // Each contact at a reference corner, at its depth.
    const auto atACorner = [&](const TriangleContact& contact) {
      return std::any_of(reference.begin(), reference.end(), [&](const test::OverlapCorner& corner) {
        return (contact.deepestPoint.cast<double>() - corner.point).norm() <= tolerance &&
               std::abs(double(contact.depth) + corner.below) <= tolerance;
      });
    };
    EXPECT_TRUE(atACorner(clipped)) << "pair " << i;
    for (int k = 0; k < more; ++k) {
      EXPECT_TRUE(atACorner(corners[k])) << "pair " << i << " corner " << k;
      EXPECT_LT(corners[k].depth, 0) << "pair " << i;
      EXPECT_GE(corners[k].depth, clipped.depth) << "pair " << i;
      EXPECT_EQ(corners[k].normalOnB, c->normalOnB);
      EXPECT_LT(test::pointTriangleDistance(corners[k].deepestPoint.cast<double>(), moving), tolerance);
    }
    // Each reference corner clearly below the plane, held by a contact.
    for (const test::OverlapCorner& corner : reference) {
      if (corner.below <= tolerance) continue;
      bool held = (clipped.deepestPoint.cast<double>() - corner.point).norm() <= tolerance;
      for (int k = 0; k < more && !held; ++k)
        held = (corners[k].deepestPoint.cast<double>() - corner.point).norm() <= tolerance;
      EXPECT_TRUE(held) << "pair " << i << ": a corner " << corner.below << " below the plane has no contact";
    }
    EXPECT_LE(clipped.depth, 0) << "pair " << i;
    EXPECT_LT(test::pointTriangleDistance(clipped.deepestPoint.cast<double>(), moving), tolerance)
        << "pair " << i;
    EXPECT_EQ(clipped.normalOnB, c->normalOnB);
  }
  std::printf(
      "%d contacts clipped (%d with a flat neighbour), %d of them less deep than the whole triangle's; %d "
      "contacts at other corners\n",
      compared, flatCompared, changed, cornerContacts);
  EXPECT_GT(compared, 1000);
  EXPECT_GT(changed, compared / 10);
  EXPECT_GT(cornerContacts, compared / 10);
}

/// Box B rests tilted on the top edge of box A (a step of a pile). B's near-vertical side triangle dips just
/// under A's top and crosses A's side, and A's top corner lies 0.28 m behind that side's plane inside its
/// prism, but only 2e-4 m inside B's bottom face across the side's convex edge. Pushed out along the side's
/// normal it was a contact 0.28 m deep between boxes that touched; the face across the convex edge bounds it
/// to within 5% of the side triangle's size of the 2e-4 m.
TEST(TriangleContact, ACornerNearerTheFaceAcrossAConvexEdgeIsNotPushedThroughTheSide) {
  const Eigen::Vector3f a[3] = {{-2.52928472f, 0.700031042f, -0.217490166f},
                                {-1.99897695f, 4.40776348e-05f, -0.674427867f},
                                {-1.99904776f, 0.700044036f, -0.674489975f}};
  const Eigen::Vector3f b[3] = {{-2.7915535f, 0.868583739f, -0.444972128f},
                                {-1.92039013f, 1.3193171f, -0.311129659f},
                                {-2.12185478f, 0.690945387f, -0.544712484f}};
  const std::optional<TriangleContact> c = generateContact(a, b);
  ASSERT_TRUE(c.has_value());
  ASSERT_TRUE(c->onFaceOfB);
  EdgeWings flat = noWings(), convex = noWings();
  flat.across[0] = Eigen::Vector3f(-2.59008884f, 1.49695539f, -0.211389244f);   // the side's other half
  convex.across[1] = Eigen::Vector3f(-2.0915966f, 0.438767791f, 0.107584022f);  // B's bottom
  convex.across[2] = Eigen::Vector3f(-2.76129532f, 0.616406143f, 0.207324415f);
  TriangleContact unbounded = *c, bounded = *c;
  TriangleContact corners[kMaxOverlapCorners];
  clipContactToOverlap(a, b, flat, noWings(), unbounded, corners);
  EXPECT_NEAR(unbounded.depth, -0.284f, 1e-3f);
  const int more = clipContactToOverlap(a, b, flat, convex, bounded, corners);
  const float size = std::max({(b[1] - b[0]).norm(), (b[2] - b[1]).norm(), (b[0] - b[2]).norm()});
  EXPECT_LE(bounded.depth, 0);
  EXPECT_GE(bounded.depth, -(2e-4f + 0.05f * size) - 1e-5f);
  for (int k = 0; k < more; ++k) EXPECT_GE(corners[k].depth, bounded.depth);
}

/// A face overhanging a convex edge (box A's side crossing box B's top 5 mm deep, past B's rim at x = 0): the
/// corner at the rim lies on the plane of B's side, but within the slack of it, so it keeps its 5 mm along
/// the top's normal, as Bullet's box pair holds the overhanging face at the rim.
TEST(TriangleContact, AFaceOverhangingAConvexEdgeKeepsItsCornerAtTheRim) {
  const Eigen::Vector3f top[3] = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}};  // B's top, facing +y; edge 0 is the rim
  const Eigen::Vector3f side[3] = {{-0.5f, -0.005f, 0.5f}, {0.5f, -0.005f, 0.5f}, {0.5f, 0.7f, 0.5f}};
  const std::optional<TriangleContact> c = generateContact(side, top);
  ASSERT_TRUE(c.has_value());
  ASSERT_TRUE(c->onFaceOfB);
  EdgeWings convex = noWings();
  convex.across[0] = Eigen::Vector3f(0, -1, 0.5f);  // B's side face below the rim
  TriangleContact clipped = *c;
  TriangleContact corners[kMaxOverlapCorners];
  const int more = clipContactToOverlap(side, top, noWings(), convex, clipped, corners);
  EXPECT_NEAR(clipped.depth, -0.005f, 1e-5f);
  bool rimHeld = std::abs(clipped.deepestPoint.x()) < 1e-4f;  // the sides are moved out by 1e-5 of the size
  for (int k = 0; k < more; ++k) {
    EXPECT_NEAR(corners[k].depth, -0.005f, 1e-5f);
    rimHeld |= std::abs(corners[k].deepestPoint.x()) < 1e-4f;
  }
  EXPECT_TRUE(rimHeld);
}

/// A box hanging over the inner edge of a bin's rim, crossing the plane of the rim's top just inside the bin:
/// the rim's top triangle there has two flat neighbours, the other half of its side's top (a convex quad) and
/// the top of the side around the corner (the two make an L, not convex). The box's triangle crosses the top
/// triangle's plane along a line that leaves it at its inner edge, so its overlap is a sliver 7 mm deep at
/// that edge. The L's far sides had cut away the top triangle itself, the empty overlap left the contact
/// whole, and the box was pushed up as if 0.544 m deep.
TEST(TriangleContact, AFlatNeighbourAroundAnInnerCornerDoesNotBoundTheOverlap) {
  const Eigen::Vector3f rim[3] = {{-3.0f, 2.5f, 3.0f}, {-3.0f, 2.5f, -3.0f}, {-3.5f, 2.5f, -3.5f}};
  const Eigen::Vector3f box[3] = {
      {-2.5372f, 2.6875f, -1.3685f}, {-3.0327f, 2.6321f, -1.8598f}, {-2.8735f, 1.9557f, -1.9443f}};
  const std::optional<TriangleContact> c = generateContact(rim, box);
  ASSERT_TRUE(c.has_value());
  ASSERT_FALSE(c->onFaceOfB);  // the box's triangle moves out of the rim's top
  EXPECT_NEAR(c->depth, -0.544f, 1e-3f);
  EdgeWings wings = noWings();
  wings.across[1] = Eigen::Vector3f(3.5f, 2.5f, -3.5f);  // around the corner: an L with this triangle
  wings.across[2] = Eigen::Vector3f(-3.5f, 2.5f, 3.5f);  // the other half of the side's top
  TriangleContact clipped = *c;
  TriangleContact corners[kMaxOverlapCorners];
  clipContactToOverlap(rim, box, wings, noWings(), clipped, corners);
  const Eigen::Vector3d out(0, 1, 0);
  test::FlatWings flat;
  flat[1] = wings.across[1].cast<double>();
  flat[2] = wings.across[2].cast<double>();
  const double reference =
      test::referenceClippedMove(test::toDouble(TriangleF{box[0], box[1], box[2]}),
                                 test::toDouble(TriangleF{rim[0], rim[1], rim[2]}), out, flat);
  EXPECT_NEAR(reference, 0.007, 1e-3);
  EXPECT_NEAR(clipped.depth, -reference, 1e-5);
  EXPECT_NEAR(clipped.deepestPoint.x(), -3.0f, 1e-4f);
}

/// The sides of two stacked boxes when the upper one tilts a little: the faces face the same way and cross in a
/// thin wedge; their contact is marked sameFacing. Flush coplanar sides give none.
TEST(TriangleContact, SameFacingTrianglesAreMarkedOrGiveNoContact) {
  const Eigen::Vector3f lowerSide[3] = {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}};  // outward +x
  for (float tilt : {0.0f, 0.01f, 0.1f}) {
    // Outward +x turned by about `tilt` about z, crossing the plane x = 1 at y = 0.975, where the lower side is.
    const Eigen::Vector3f upperSide[3] = {{1 + tilt, 0.9f, 0.3f}, {1 - tilt, 1.05f, 0.3f}, {1 - tilt, 1.05f, 0.8f}};
    EXPECT_TRUE(trianglesIntersect(upperSide[0], upperSide[1], upperSide[2], lowerSide[0], lowerSide[1],
                                   lowerSide[2]))
        << "tilt " << tilt;
    for (const auto& c : {generateContact(upperSide, lowerSide), generateContact(lowerSide, upperSide)}) {
      if (tilt == 0) {
        EXPECT_FALSE(c.has_value());
      } else {
        ASSERT_TRUE(c.has_value()) << "tilt " << tilt;
        EXPECT_TRUE(c->sameFacing) << "tilt " << tilt;
      }
    }
  }
}

/// Two faces resting on each other (coplanar, opposite normals): depth 0 along B's normal, the point in the
/// overlap.
TEST(TriangleContact, CoplanarRestingFaces) {
  const Eigen::Vector3f top[3] = {{0, 0, 0}, {0, 2, 0}, {2, 0, 0}};   // outward -z: a body above
  const Eigen::Vector3f face[3] = {{1, 1, 0}, {3, 1, 0}, {1, 3, 0}};  // outward +z: the body below
  const std::optional<TriangleContact> c = generateContact(top, face);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->depth, 0.0f);
  EXPECT_NEAR((c->normalOnB - Eigen::Vector3f(0, 0, 1)).norm(), 0.0f, 1e-6f);
  // The overlap is the single point (1, 1, 0) (a vertex of `face` on the hypotenuse of `top`).
  EXPECT_NEAR((c->point - Eigen::Vector3f(1, 1, 0)).norm(), 0.0f, 1e-6f);
  const Eigen::Vector3f apart[3] = {{1.5f, 1.5f, 0}, {3, 1.5f, 0}, {1.5f, 3, 0}};
  EXPECT_FALSE(generateContact(top, apart).has_value());
}

/// A contact whose triangles slide apart along their intersection line more easily than along the normal
/// is dropped (thesis §5.3.4).
TEST(TriangleContact, DroppedWhenTheLineSlideIsShorter) {
  const Eigen::Vector3f face[3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  // A thin vertical sliver (in the plane y = 0.5) through the face, 0.5 deep, 0.01 from the face's edge
  // x = 0: sliding it off along the intersection line (x) takes 0.03, lifting it takes 0.5.
  const Eigen::Vector3f sliver[3] = {{0.01f, 0.5f, -0.5f}, {0.03f, 0.5f, 1}, {0.01f, 0.5f, 1}};
  EXPECT_TRUE(trianglesIntersect(sliver[0], sliver[1], sliver[2], face[0], face[1], face[2]));
  EXPECT_FALSE(generateContact(sliver, face).has_value());
  // The same sliver in the middle of the face would have to slide across it (0.52 > 0.5): kept.
  const Eigen::Vector3f middle[3] = {{0.5f, 0.5f, -0.5f}, {0.52f, 0.5f, 1}, {0.5f, 0.5f, 1}};
  const std::optional<TriangleContact> c = generateContact(middle, face);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->depth, -0.5f, 1e-6f);
}

/// Degenerate triangles give no contact.
TEST(TriangleContact, DegenerateGivesNone) {
  const Eigen::Vector3f face[3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  const Eigen::Vector3f segment[3] = {{0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {0.5f, 0.5f, 0}};
  EXPECT_FALSE(generateContact(segment, face).has_value());
  EXPECT_FALSE(generateContact(face, segment).has_value());
}

/// Random pairs against the double reference: the contact exists exactly when the pair intersects and is
/// not dropped, its normal and depth follow §5.3.4, its point lies on both triangles, and a random rigid
/// motion of the pair moves the contact with it. Pairs within a small margin of a decision (move A vs
/// move B, slide vs depth, touching) are skipped for the comparisons that decision affects.
TEST(TriangleContact, MatchesDoubleReferenceAndIsInvariantUnderRigidMotion) {
  std::mt19937_64 rng(7);
  int compared = 0, kept = 0, dropped = 0, rotatedCompared = 0;
  const PairFamily families[] = {PairFamily::General, PairFamily::VertexOnFace, PairFamily::EdgeOnEdge,
                                 PairFamily::NearTouching};
  for (int i = 0; i < 40000; ++i) {
    TriangleF a, b;
    test::randomPair(families[i % 4], rng, a, b);
    const TriangleD da = test::toDouble(a), db = test::toDouble(b);
    const std::optional<TriangleContact> c = contactOf(a, b);
    const bool intersecting = trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
    ASSERT_TRUE(!c || intersecting) << "contact for a pair the test calls separated, pair " << i;
    if (!test::referenceIntersect(da, db)) continue;
    const double scale = test::pairScale(da, db);
    const double margin = 1e-5 * scale;
    const double nAnB = std::fabs((da[1] - da[0])
                                      .cross(da[2] - da[0])
                                      .normalized()
                                      .dot((db[1] - db[0]).cross(db[2] - db[0]).normalized()));
    if (nAnB > 1 - 1e-6) continue;  // (nearly) parallel planes: no line, covered by the coplanar tests
    const ReferenceContact r = referenceContact(da, db);
    if (std::fabs(r.slide - std::min(r.moveA, r.moveB)) < margin) continue;
    // Pairs within rounding of a right angle may be called same-facing either way.
    const double facing = (da[1] - da[0]).cross(da[2] - da[0]).normalized().dot((db[1] - db[0]).cross(db[2] - db[0]).normalized());
    if (std::fabs(facing) < 1e-5) continue;
    const bool expectKept = r.slide >= std::min(r.moveA, r.moveB);
    if (-test::signedSeparation(da, db) < margin) continue;  // touching: the float input may miss it
    ++compared;
    ASSERT_EQ(c.has_value(), expectKept)
        << "pair " << i << " slide " << r.slide << " moves " << r.moveA << " " << r.moveB;
    if (!c) {
      ++dropped;
      continue;
    }
    ++kept;
    EXPECT_EQ(c->sameFacing, facing > 0) << "pair " << i;
    EXPECT_NEAR(c->depth, r.depth, margin) << "pair " << i;
    if (std::fabs(r.moveA - r.moveB) > margin) {
      EXPECT_LT((c->normalOnB.cast<double>() - r.normalOnB).norm(), 1e-5) << "pair " << i;
    }
    EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), da), margin) << "pair " << i;
    EXPECT_LT(test::pointTriangleDistance(c->point.cast<double>(), db), margin) << "pair " << i;
    EXPECT_LT((c->point.cast<double>() - r.point).norm(), margin + 1e-3 * r.segmentLength) << "pair " << i;

    // The same pair after a random rigid motion (well-conditioned pairs only, the float rounding of
    // the moved vertices is ~1e-7 of the scale).
    const double coarse = 1e-3 * scale;
    if (std::fabs(r.moveA - r.moveB) < coarse || std::fabs(r.slide + r.depth) < coarse ||
        -test::signedSeparation(da, db) < coarse || nAnB > 0.999) {
      continue;
    }
    const Eigen::Matrix3d rotation = test::randomRotation(rng);
    const Eigen::Vector3d offset = Eigen::Vector3d::Random() * scale;
    TriangleF ma, mb;
    for (int k = 0; k < 3; ++k) {
      ma[k] = (rotation * da[k] + offset).cast<float>();
      mb[k] = (rotation * db[k] + offset).cast<float>();
    }
    const std::optional<TriangleContact> moved = contactOf(ma, mb);
    ASSERT_TRUE(moved.has_value()) << "pair " << i;
    ++rotatedCompared;
    EXPECT_NEAR(moved->depth, c->depth, 1e-4 * scale) << "pair " << i;
    EXPECT_LT((moved->normalOnB.cast<double>() - rotation * c->normalOnB.cast<double>()).norm(), 1e-4);
    EXPECT_LT((moved->point.cast<double>() - (rotation * c->point.cast<double>() + offset)).norm(),
              1e-4 * scale);
  }
  std::cout << "  compared " << compared << " intersecting pairs: " << kept << " contacts kept, " << dropped
            << " dropped by the line slide; " << rotatedCompared << " also compared after a rigid motion\n";
  EXPECT_GT(kept, 2000);
  EXPECT_GT(dropped, 100);
  EXPECT_GT(rotatedCompared, 1000);
}

}  // namespace
}  // namespace gpucol
